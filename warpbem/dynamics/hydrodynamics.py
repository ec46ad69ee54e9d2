"""The mobility solves of one state (DESIGN.md §3 step 4), exact or reused across steps.

Exact (``SolverOptions.reuse_tolerance = 0``): the background solve (flow and explicit loads) at
the state's own bodies, then one solve per load of the basis the stiff forces are combined from
(``implicit.py``): a unit force along each implicit coordinate when there are no more of them
than the free bodies' 6 degrees of freedom each (a repulsive contact or two), else unit forces
and torques on each free body (the grand mobility; tens of bonds).

Reused (``reuse_tolerance = d > 0``, m, for states whose interactions hold stiff forces:
bonds): the rigid bodies' mobility depends on the configuration only, and changes slowly with
it, while bond forces change fast. A snapshot holds the flow solve (no loads) and the grand
mobility at the configuration snapped to a lattice: free bodies' heights rounded to multiples
of d, their orientations likewise in steps of d / outer radius (except for spheres, whose
mobility does not depend on it). A lone body above the wall in shear (u = gdot z e_x) is
invariant under translation along the wall, so its snapshots are keyed by height alone and
computed at x = y = 0. With several bodies the snapshot is split: the whole system's (the
interaction snapshot) on a coarser lattice, heights to ``reuse_interaction`` (default 10 d,
orientations likewise) and lateral positions to ``reuse_lateral`` (default 50 d; with all
bodies free, the lattice points shifted by the first body's, by the same invariance, so that a
configuration recurring shifted by whole lattice steps finds its snapshot), and each
free body's self part moved from its coarse height to its fine one by the difference of its
lone snapshots there, M(X) ~ M(X*) + sum_i [M_i(h_i) - M_i(h_i*)] on body i's own block. A
cell's mobility changes with its height over the gap to the wall (0.2 um when rolling), but
the whole system's snapshot costs 6 n + 1 solves of n bodies and with n rolling cells a fine
lattice of every height would need a new one at nearly every step; the lone ones cost 7 solves
of one body. The coupling between cells still depends on their gaps (a near-wall cell answers
another's flow with its own near-wall mobility), so the split errs by 2e-3 at 20 nm where the
coarse snapshot alone errs by 7e-3 (benchmarks/adhesion.py, 2c). The background for any
explicit loads and the stiff forces follow from a snapshot by linearity, so a step costs no
solve while the cells stay near a snapped configuration already seen; the error is first
order in the lattice spacings (charted by ``benchmarks/adhesion.py``). The evaluation stays a
pure function of the state (resumed runs reproduce uninterrupted ones) to round-off: a snapshot's
flow solve starts GMRES from the previous solve's solution, so the same snapshot solved after
another history differs by about 1e-11 of the flow's motion (``snapshot_store.py``). Near contact the
lateral lattice is halved for a snapshot until no gap between two bodies moves by more than half
of it (GAP_SHARE); a snapped configuration that still moves one more, or is not a valid
placement, is solved exactly.

Lone and pair snapshots (``pairwise.py``) are also kept on disk across runs
(``snapshot_store.py``, ``SolverOptions.snapshot_store``): one missing here is looked up there
before it is solved, and written there once solved. The whole system's stay in memory: they are
keyed by every cell's lattice point and seldom recur in another run.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from ..options import OptionError
from ..surfaces.body import Body
from ..surfaces.placement import PlacementError, check_placement
from .pairwise import PairwiseMobility, TooClose
from .snapshot_store import SnapshotStore, snapshot_digest

PROBE_FORCE = 1e-12  # N: the scale of a basis load's solve (the response is linear)
MAX_SNAPSHOTS = 256
# pair snapshots kept (pairwise.py): each holds 2 cells' motion under 13 loads (about 2.5 kB), and
# a patch of cells rolling apart asks for a few per pair, so many more are kept than of the
# whole system (64 cells: 2.4 MB each)
MAX_PAIR_SNAPSHOTS = 65536
# a whole system's snapped configuration may move the gap between two bodies by at most this share
# of it; where the lateral lattice would move it more, the lattice is halved for that snapshot (up
# to LATTICE_HALVINGS times), and beyond that the state is solved exactly. Without the rule a 1 um
# lattice put a free cell passing 0.4 um from a rolling one 6 nm from it: refined for that gap,
# the snapshot's matrix took 8 GB and the pass stalled (scenes/rolling_capture.toml, y_7_5), and
# its coupling was not the state's. A shift of half the gap moves the coupling of two 5 um cells
# 2 um apart by about 4 % (benchmarks/adhesion.py 2b: linear, 0.77 % per 200 nm at 12 um)
GAP_SHARE = 0.5
LATTICE_HALVINGS = 6


@dataclass(frozen=True)
class Motion:
    """velocity, angular_velocity, force, torque (n, 3), as in ``MobilitySolution``."""

    velocity: np.ndarray
    angular_velocity: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    iterations: int
    residual: float

    @classmethod
    def of(cls, solution) -> "Motion":
        """The motion and loads of a ``MobilitySolution`` (without its GMRES vectors)."""
        return cls(solution.velocity, solution.angular_velocity, solution.force, solution.torque,
                   solution.iterations, solution.residual)


@dataclass(frozen=True)
class Responses:
    """The motion of each load of a basis (``implicit.py``): velocity, angular_velocity, force,
    torque (p, n, 3) per newton of coefficient, the loads themselves (``load_force``,
    ``load_torque``, (p, n, 3)), and the GMRES figures of their solves."""

    velocity: np.ndarray
    angular_velocity: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    load_force: np.ndarray
    load_torque: np.ndarray
    iterations: int
    residual: float

    def combine(self, z):
        """(U, Omega, F, T) of the loads sum_k z_k (load k), z in N."""
        return tuple(np.tensordot(z, a, axes=1) for a in (self.velocity, self.angular_velocity,
                                                          self.force, self.torque))

    def quadratic(self) -> np.ndarray:
        """Q_kl = (load k) . (motion l), symmetrised (reciprocity; removes the GMRES noise), once
        per step. Where every load is a single component (the "bodies" basis: a unit force or
        torque on one body), Q_kl is that component of motion l times the load: a gather, O(p^2),
        where the product of (p, 6 n) matrices costs O(p^2 n) (5 ms for the 384 loads of 64 cells,
        and n^3 beyond); the product otherwise (np.einsum's own loop took ten times as long as it).
        Loads and motions are laid out by degree of freedom (force, torque of each body in turn), so
        the free bodies' basis in its own order (load k on degree of freedom k) needs no gather at
        all (the gather took 40 ms of a step of 256 cells)."""
        p, n = self.load_force.shape[:2]
        loads = np.concatenate([self.load_force, self.load_torque], axis=2).reshape(p, 6 * n)
        motion = np.concatenate([self.velocity, self.angular_velocity], axis=2).reshape(p, 6 * n)
        component = np.argmax(loads != 0.0, axis=1)
        magnitude = loads[np.arange(p), component]
        if np.count_nonzero(loads) == p and np.all(magnitude != 0.0):
            moved = motion[:, :p] if np.array_equal(component, np.arange(p)) else motion[:, component]
            q = magnitude[:, None] * moved.T
        else:
            q = loads @ motion.T
        return 0.5 * (q + q.T)


@dataclass(frozen=True)
class Hydrodynamics:
    """The solves at one state: ``background`` (flow and explicit loads, a ``Motion``) and the
    ``basis`` Responses of the stiff forces, of ``kind`` "coordinates" (a unit force along each
    implicit coordinate) or "bodies" (unit forces, and torques of 1 N times the outer radius, on
    each free body in turn). ``chosen``: the accuracy target's settings of the last solve (None
    without a target)."""

    background: Motion
    basis: Responses | None
    kind: str
    chosen: object = None


class HydrodynamicSolves:
    """The mobility solves of a model's states, exact or from snapshots (module docstring)."""

    def __init__(self, model, mobility):
        self.model = model
        self.mobility = mobility
        self.tolerance = model.solver.reuse_tolerance
        self.lateral = model.solver.reuse_lateral or 50.0 * self.tolerance
        self.interaction = model.solver.reuse_interaction or 10.0 * self.tolerance
        self.spherical = [m.is_spherical() for m in model.meshes]
        self.free = np.flatnonzero(~model.fixed_mask)
        # bodies sharing a mesh share their lone snapshots
        self.lone_of = [next(j for j, other in enumerate(model.meshes) if other is m) for m in model.meshes]
        self._snapshots: OrderedDict = OrderedDict()
        self._pairs: OrderedDict = OrderedDict()
        self.snapshots_solved = 0
        # lone and pair snapshots on disk across runs (module docstring); None when off
        self.store = (SnapshotStore((Motion, Responses), size_limit=model.solver.snapshot_store_size)
                      if model.solver.snapshot_store == "on" else None)
        self.pairwise = None
        if model.solver.grand_mobility == "pairs":
            if model.fixed_mask.any() or not all(self.spherical):
                raise OptionError("solver.grand_mobility = 'pairs' takes free spherical cells only (its pair lattice"
                                  " holds no orientation and no fixed body); use 'system'")
            if model.solver.near_far_split == "on":
                raise OptionError("solver.grand_mobility = 'pairs' holds no fixed body: near_far_split = 'on' does"
                                  " not apply")
            if not self.tolerance > 0:
                raise OptionError("solver.grand_mobility = 'pairs' is built from snapshots: it needs"
                                  " solver.reuse_tolerance > 0 (2e-9 m, the adhesive scenes' default)")
            self.pairwise = PairwiseMobility(self)

    def background(self, bodies, loads, stiff: bool):
        """(Motion of the flow and the explicit ``loads``, the snapshot used or None); snapshots
        serve states with ``stiff`` forces only (bonds), so a free-stream pass, whose
        configurations never repeat, costs one solve per state; the pairs serve every state (they
        never solve the whole system)."""
        if self.tolerance > 0 and (stiff or self.pairwise is not None):
            try:
                snapshot = self._snapshot(bodies)
            except TooClose:  # solved exactly, not kept
                snapshot = self._solved(bodies)
            flow, basis = snapshot
            u, w, f, t = basis.combine(self.body_coefficients(loads.force, loads.torque))
            motion = Motion(flow.velocity + u, flow.angular_velocity + w, flow.force + f, flow.torque + t,
                            flow.iterations, flow.residual)
            return motion, snapshot
        return Motion.of(self.mobility.solve(bodies, forces=loads.force, torques=loads.torque,
                                           check_placement_first=False)), None

    def basis(self, bodies, coordinates, snapshot) -> tuple[Responses, str]:
        """The Responses the implicit forces along ``coordinates`` are combined from."""
        if snapshot is not None:
            return snapshot[1], "bodies"
        if len(coordinates.values) <= 6 * len(self.free):
            mask = ~self.model.fixed_mask[:, None]
            unit_force, unit_torque = coordinates.dense_loads()
            return self._responses(bodies, unit_force * mask, unit_torque * mask), "coordinates"
        return self._grand_mobility(bodies), "bodies"

    def body_coefficients(self, force, torque) -> np.ndarray:
        """Coefficients (N) of loads on the free bodies in the "bodies" basis."""
        radii = self.model.outer_radii[self.free, None]
        return np.concatenate([force[self.free], torque[self.free] / radii], axis=1).ravel()

    def _responses(self, bodies, load_force, load_torque, flow: bool = False):
        """The Responses of the loads, all solved at once (``MobilitySolver.solve_loads``);
        ``flow``: with the flow's Motion solved among them, as (Motion, Responses). A snapshot's
        solves factor every body's block, however large: the whole system of three refined k = 3
        cells 12 um apart took 19.2 s in 252 iterations for its 19 columns with the factors,
        25.7 s in 756 without (a script of this session)."""
        many = flow or len(load_force) > 6
        solves = self.mobility.solve_loads(bodies, PROBE_FORCE * load_force, PROBE_FORCE * load_torque,
                                           factor_every_body=many or self.pairwise is not None, with_background=flow)
        background = Motion.of(solves.pop(0)) if flow else None
        stack = [np.array([getattr(s, name) for s in solves]) / PROBE_FORCE
                 for name in ("velocity", "angular_velocity", "force", "torque")]
        responses = Responses(*stack, load_force, load_torque, sum(s.iterations for s in solves),
                              max(s.residual for s in solves))
        return (background, responses) if flow else responses

    def _grand_mobility(self, bodies, radii=None, half_turn: bool = False, flow: bool = False):
        """The "bodies" basis of the free bodies in ``bodies`` (outer ``radii``, default the
        model's), with their motion taken from the symmetrised grand mobility: the collocation
        discretisation is reciprocal only to its discretisation error (0.5 % in the
        translation-rotation coupling of a 24-element sphere), and a joint step whose rates and
        dissipation came from different halves would hold a cell at rest with a load that is not
        its holding load. ``half_turn``: two free bodies of one mesh that a half turn about the
        vertical through their midpoint exchanges (``_half_turn_responses``). ``flow``: the flow's
        Motion solved with the loads, as (Motion, Responses)."""
        radii = self.model.outer_radii if radii is None else radii
        free = [b for b, body in enumerate(bodies) if not body.fixed]
        loads = self._body_loads(len(bodies), free, radii)
        solved = (self._half_turn_responses if half_turn else self._responses)(bodies, *loads, flow=flow)
        background, r = solved if flow else (None, solved)
        q = r.quadratic()
        velocity, angular_velocity = r.velocity.copy(), r.angular_velocity.copy()
        for j, b in enumerate(free):
            velocity[:, b] = q[:, 6 * j:6 * j + 3]
            angular_velocity[:, b] = q[:, 6 * j + 3:6 * j + 6] / radii[b]
        grand = Responses(velocity, angular_velocity, r.force, r.torque, r.load_force, r.load_torque,
                          r.iterations, r.residual)
        return (background, grand) if flow else grand

    def _half_turn_responses(self, bodies, load_force, load_torque, flow: bool = False):
        """The Responses of the 12 basis loads of two free bodies of one mesh, at one height, that
        the half turn R = diag(-1, -1, 1) about the vertical through their midpoint maps onto each
        other (a sphere's mesh is symmetric under it, and so are the wall and its refinement):
        the problem of a load L on body 1 is the turned problem of R L on body 0, so its motion
        of body b is R times the motion of body 1 - b under R L. The 6 loads on body 1 cost no
        solve (pairwise.py's pair snapshots; the test there holds it to the direct solve)."""
        turn = np.array([-1.0, -1.0, 1.0])
        signs = np.tile(turn, 2)[:, None, None]  # R e_i = turn_i e_i, forces and torques alike
        solved = self._responses(bodies, load_force[:6], load_torque[:6], flow=flow)
        background, half = solved if flow else (None, solved)
        parts = [np.concatenate([a, signs * turn * a[:, ::-1]]) for a in (half.velocity, half.angular_velocity,
                                                                         half.force, half.torque)]
        responses = Responses(*parts, load_force, load_torque, half.iterations, half.residual)
        return (background, responses) if flow else responses

    def _body_loads(self, n, free=None, radii=None):
        """(force, torque) (6 f, n, 3) of the "bodies" basis of the ``free`` ones (default all) of
        ``n`` bodies: unit forces, and torques of 1 N times the outer ``radii``, on each in turn."""
        free = range(n) if free is None else free
        radii = self.model.outer_radii if radii is None else radii
        force, torque = np.zeros((6 * len(free), n, 3)), np.zeros((6 * len(free), n, 3))
        for k, b in enumerate(free):
            for i in range(3):
                force[6 * k + i, b, i] = 1.0
                torque[6 * k + 3 + i, b, i] = radii[b]
        return force, torque

    def _snapshot(self, bodies):
        """The (flow Motion, grand-mobility Responses) of ``bodies`` from the snapshots: a lone
        body's own; with several, the interaction snapshot on the coarse lattice with each free
        body's self part moved from its coarse height (and orientation) to its fine one."""
        if len(bodies) == 1:
            return self._lone(0, bodies[0], self.tolerance)
        if self.pairwise is not None:
            velocity, angular, basis_velocity, basis_angular, iterations, residual = self.pairwise.assemble(bodies)
            zeros = np.zeros_like(velocity)
            loads = self._body_loads(len(bodies))
            return (Motion(velocity, angular, zeros, zeros, iterations, residual),
                    Responses(basis_velocity, basis_angular, *loads, *loads, iterations, residual))
        key, snapped = self._snapped_apart(bodies)
        flow, grand = self._kept(key, snapped, self._solved)
        if self.interaction == self.tolerance:
            return flow, grand
        velocity, angular_velocity = flow.velocity.copy(), flow.angular_velocity.copy()
        basis_velocity, basis_angular = grand.velocity.copy(), grand.angular_velocity.copy()
        for j, b in enumerate(self.free):
            (fine_flow, fine), (coarse_flow, coarse) = (self._lone(b, bodies[b], d)
                                                        for d in (self.tolerance, self.interaction))
            velocity[b] += fine_flow.velocity[0] - coarse_flow.velocity[0]
            angular_velocity[b] += fine_flow.angular_velocity[0] - coarse_flow.angular_velocity[0]
            rows = slice(6 * j, 6 * j + 6)
            basis_velocity[rows, b] += fine.velocity[:, 0] - coarse.velocity[:, 0]
            basis_angular[rows, b] += fine.angular_velocity[:, 0] - coarse.angular_velocity[:, 0]
        return (Motion(velocity, angular_velocity, flow.force, flow.torque, flow.iterations, flow.residual),
                Responses(basis_velocity, basis_angular, grand.force, grand.torque, grand.load_force,
                          grand.load_torque, grand.iterations, grand.residual))

    def _lone(self, index, body, spacing, exact_if_too_close=False):
        """Snapshot of model body ``index`` alone above the wall, its height (and orientation)
        snapped to ``spacing``: invariant under translation along the wall, so at x = y = 0.
        ``exact_if_too_close``: a snapped height too near the wall solves the body as it is (not
        kept) instead of raising."""
        position = np.array([0.0, 0.0, body.position[2]])
        alone = Body(body.mesh, position=position, orientation=body.orientation, name=body.name)
        entry, (lone,) = self._snapped([alone], spacing, [index])
        radii = self.model.outer_radii[[index]]
        try:
            return self._kept(("lone", self.lone_of[index], spacing) + entry, [lone],
                              lambda b: self._solved(b, radii))
        except TooClose:
            if not exact_if_too_close:
                raise
            return self._solved([alone], radii)

    def _solved(self, bodies, radii=None, half_turn: bool = False):
        """A snapshot solved at ``bodies``: (flow Motion, grand mobility Responses); ``half_turn``
        as in ``_grand_mobility``."""
        # the flow and the loads in one batched GMRES (MobilitySolver.solve_loads), every block
        # factored (_responses)
        return self._grand_mobility(bodies, radii, half_turn, flow=True)

    def _kept(self, key, snapped, solve, store=None):
        """The snapshot ``key`` from ``store`` (default the whole systems' and lone ones; the
        pairs' is ``_pairs``), else, for a lone or pair one, from the disk store; solved at
        ``snapped`` by ``solve`` and kept (on disk too) if new."""
        store = self._snapshots if store is None else store
        if key in store:
            store.move_to_end(key)
            return store[key]
        try:
            check_placement(snapped, self.model.flow.wall)
        except PlacementError:
            raise TooClose from None
        lasting = self.store is not None and key[0] in ("lone", "pair")
        # a solver whose operator form is still open decides it at this solve, and keys the entry by it
        snapshot = self.store.get(self._digest(key, snapped)) if lasting and self._solver.mode is not None else None
        if snapshot is None:
            snapshot = solve(snapped)
            self.snapshots_solved += 1
            if lasting:
                self.store.put(self._digest(key, snapped), snapshot)
        store[key] = snapshot
        while len(store) > (MAX_PAIR_SNAPSHOTS if store is self._pairs else MAX_SNAPSHOTS):
            store.popitem(last=False)
        return snapshot

    def _digest(self, key, snapped) -> str:
        """The disk store's key of the lone or pair snapshot ``key`` solved at ``snapped``: the radii
        are those of the model's bodies the key names (a lone key's mesh index, a pair key's two)."""
        bodies = key[1:2] if key[0] == "lone" else key[1:3]
        return snapshot_digest(key, snapped, self.model.outer_radii[list(bodies)], self.model.solver,
                               self.model.flow, PROBE_FORCE, self.mobility.operator_description, self._solver.device)

    @property
    def _solver(self):
        """The MobilitySolver of the solves (the near-far split wraps it)."""
        return getattr(self.mobility, "inner", self.mobility)

    def _snapped_apart(self, bodies):
        """(key, bodies) of the whole system's snapshot of ``bodies`` (every model body): on the
        lateral lattice, halved (the halvings then in the key) until no gap between two bodies
        moves by more than GAP_SHARE of it; TooClose past LATTICE_HALVINGS. The gaps are those of
        the bodies' outer spheres (exact for spheres); pairs whose outer spheres overlap (a cell
        beside a non-spherical adherent one) are left to the placement check."""
        first, second = np.triu_indices(len(bodies), 1)
        radii = self.model.outer_radii[first] + self.model.outer_radii[second]

        def gaps(placed):
            centres = np.array([b.position for b in placed])
            return np.linalg.norm(centres[first] - centres[second], axis=1) - radii

        actual = gaps(bodies)
        judged = actual > 0
        for halvings in range(LATTICE_HALVINGS + 1):
            key, snapped = self._snapped(bodies, self.interaction, lateral=self.lateral / 2**halvings)
            moved = np.abs(gaps(snapped) - actual)[judged]
            if np.all(moved <= GAP_SHARE * actual[judged]):
                return (key + (("halved", halvings),) if halvings else key), snapped
        raise TooClose

    def _snapped(self, bodies, spacing, indices=None, lateral=None):
        """(key, bodies) of ``bodies`` (model bodies ``indices``) on the lattice of heights
        ``spacing``, orientations spacing / outer radius and lateral positions reuse_lateral.
        When every body is free, the lattice points are shifted by the first body's lateral one
        (free bodies above the wall in shear are invariant under translation along it): the
        snapshot is the same, and configurations that recur shifted by whole lattice steps, as a
        train rolling as a whole, find it again. Each point is still the body's own nearest, so a
        single moving cell changes the key as often as before (rounding the offsets from the first
        body instead would change it when any offset crosses a line: twice as often for a cell
        moving past two resting ones). Fixed bodies pin the frame. ``lateral``: the lateral
        spacing, default reuse_lateral."""
        indices = range(len(bodies)) if indices is None else indices
        lateral = self.lateral if lateral is None else lateral
        lattice = np.array([lateral, lateral, spacing])
        shift = np.zeros(3)
        if not any(b.fixed for b in bodies):
            shift[:2] = np.round(bodies[0].position[:2] / lateral)
        key, snapped = [], []
        for i, b in zip(indices, bodies):
            if b.fixed:
                snapped.append(b)
                continue
            cell = np.round(b.position / lattice) - shift
            entry = tuple(cell)
            orientation = np.array([1.0, 0.0, 0.0, 0.0])
            if not self.spherical[i]:
                q = np.round(b.orientation / (spacing / self.model.outer_radii[i]))
                entry += tuple(q)
                orientation = q / np.linalg.norm(q)
            key.append(entry)
            snapped.append(Body(b.mesh, position=cell * lattice, orientation=orientation, fixed=False, name=b.name))
        return tuple(key), snapped

