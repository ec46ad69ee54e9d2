"""The coupling of far pairs of cells from each cell's own surface traction, with the wall's
images: no pair snapshot for them (``SolverOptions.far_field``).

Two cells far apart couple, to first order in the method of reflections (Happel & Brenner 1965,
ch. 6; Kim & Karrila 1991, sec. 8.2), through the flow each drives alone: cell a under a load
(or in the ambient flow) exerts its surface traction t_a on the fluid, whose velocity at x is
u(x) = -int G(x, y) t_a(y) dS / mu (thesis eq. 2.18, G the wall's Green's function, Blake 1971);
cell b, free, moves in that flow as the reciprocal theorem gives it (the generalised Faxen law,
Kim & Karrila sec. 5.3): along its basis load r, U_r = -int u . t_b^(r) dS, t_b^(r) its own
traction when it moves alone under that load. So

    M_ba[r, c] = int int t_b^(r)(x) . G(x, y) t_a^(c)(y) dS_x dS_y / mu,

symmetric (G(x, y) = G(y, x)^T), and the flow's motion of b gains the term of a's traction in the
ambient flow. The next reflection changes each cell's own mobility, as r^-6: 4.8e-4 of the grand
mobility at 25 um between two 5 um cells, 1.3e-5 at 50 um (benchmarks/many_cells.py --parts far),
which the near radius leaves to the pair snapshots.

Each cell's tractions come from seven solves of the cell alone above the wall
(``hydro/traction.py``): a unit force and torque along each axis, and the ambient flow with no
load, at the heights of the pair snapshots' height lattice (``reuse_interaction``; cells sharing a
mesh share them; kept in the snapshot store across runs, ``snapshot_store.py``), interpolated linearly to the cell's own height between the two around it (the
coupling is linear in each cell's tractions, so a pair is the bilinear blend of its four height
combinations). Far from the cell its traction is felt through its moments about the centre;
they are kept to second order (force, torque and stresslet, and the second moments that carry
the wall's r^-4 terms) on a stencil of STENCIL_POINTS point forces at STENCIL_RADIUS, the force and
torque set to their exact values (the load itself, or none in the flow) so that no discretisation
error of the traction turns into a spurious Stokeslet. A pair then costs 19 x 19 evaluations of G
per height combination in one Warp kernel (``kernels/far_field.py``) over the far pairs; a
combination is evaluated again only when its cells' lattice heights or the pair's offset on the
lateral lattice FAR_LATERAL change, so the coupling is a function of the state alone (resumed runs
repeat uninterrupted ones).

Against the direct two-body solve (``tests/unit/test_far_field.py``; 2 um cells, k = 2): far
apart the coupling is Blake's far field of the cells' first moments to 6 %; at 7 radii the pair
errs by 4.1e-4 of the grand mobility, at 10 radii by 1.7e-4, where the coupling is 30-40 times
larger.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..hydro.mobility import ContactResolutionWarning
from ..hydro.traction import solve_traction
from ..surfaces.body import Body
from .snapshot_store import SnapshotStore, snapshot_digest

# a height this close to a lattice height, in lattice spacings, lies on it (FarField._height_sets)
ROUND_OFF = 1e-9
# m: a far pair's lateral offset is rounded to this lattice before its coupling is evaluated
FAR_LATERAL = 0.5e-6
# the stencil's points: the centre, six along the axes, twelve along the edges' diagonals, at this
# share of the outer radius; 57 force components hold the 30 moments to second order per column
STENCIL_RADIUS = 0.5
_AXES = np.eye(3)
STENCIL = np.concatenate([
    np.zeros((1, 3)),
    [s * _AXES[i] for i in range(3) for s in (1.0, -1.0)],
    [(s * _AXES[i] + t * _AXES[j]) / np.sqrt(2.0) for i in range(3) for j in range(i + 1, 3)
     for s in (1.0, -1.0) for t in (1.0, -1.0)],
])
STENCIL_POINTS = len(STENCIL)
SOURCES = 7  # unit force x, y, z, unit torque x, y, z (N m), the ambient flow
# a far pair's row: the flow's velocity and angular velocity of each cell (2, 3) each, then the
# velocity and angular velocity of the other cell under each cell's 6 basis loads (2, 6, 3) each
# (the loads on the first moving the second, then the reverse); what a pair snapshot's row
# (pairwise.part_row) holds besides these, each cell's own motion under its own loads, is zero
COUPLING_SHAPES = ((2, 3), (2, 3), (2, 6, 3), (2, 6, 3))
COUPLING_SIZE = sum(int(np.prod(s)) for s in COUPLING_SHAPES)
LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    LEVI_CIVITA[_i, _j, _k], LEVI_CIVITA[_i, _k, _j] = 1.0, -1.0


def monomials(relative) -> np.ndarray:
    """(N, 10) the monomials 1, x, y, z, xx, xy, xz, yy, yz, zz of points ``relative`` to the
    centre (in outer radii): the moments of a force distribution are its forces' sums against them."""
    x = np.asarray(relative, dtype=float)
    columns = [np.ones(len(x))] + [x[:, i] for i in range(3)]
    columns += [x[:, i] * x[:, j] for i in range(3) for j in range(i, 3)]
    return np.stack(columns, axis=1)


def exact_loads(moments: np.ndarray, force: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """``moments`` (10, 3) of a traction distribution (rows: monomials, columns: force components)
    with its total force and the antisymmetric part of its first moment (the torque, about the
    centre, over the outer radius) replaced by the exact ``force`` and ``torque`` / radius."""
    moments = moments.copy()
    moments[0] = force
    first = moments[1:4]  # D_ij = sum (x - c)_i f_j
    symmetric = 0.5 * (first + first.T)
    moments[1:4] = symmetric + 0.5 * np.einsum("kij,k->ij", LEVI_CIVITA, torque)
    return moments


@dataclass(frozen=True)
class CellTractions:
    """The compressed tractions (module docstring) of one cell at one height: ``points`` (P, 3)
    m, relative to the cell's lateral position, and ``weights`` (P, 3, 7) N per unit load (the
    force the fluid exerts on the stencil point; the flow's column at the model's shear rate)."""

    points: np.ndarray
    weights: np.ndarray

    @classmethod
    def solved(cls, mesh, height: float, radius: float, flow, options, device) -> "CellTractions":
        """The seven traction solves of the cell of ``mesh`` (outer ``radius``) alone at ``height``
        above the wall, compressed to the stencil."""
        cell = Body(mesh, position=(0.0, 0.0, height))
        solves = []
        with warnings.catch_warnings():  # refined as the mobility solves are; charted elsewhere
            warnings.simplefilter("ignore", ContactResolutionWarning)
            for c in range(6):
                load = np.zeros((2, 3))
                load[c // 3, c % 3] = 1.0
                solves.append(solve_traction([cell], viscosity=flow.viscosity, wall=flow.wall, forces=[load[0]],
                                             torques=[load[1]], device=device, options=options))
            solves.append(solve_traction([cell], shear_rate=flow.shear_rate, viscosity=flow.viscosity,
                                         wall=flow.wall, device=device, options=options))
        centre = cell.position
        # least-norm stencil forces with the given moments (the stencil in outer radii)
        to_weights = np.linalg.pinv(monomials(STENCIL_RADIUS * STENCIL).T)
        weights = np.zeros((STENCIL_POINTS, 3, SOURCES))
        for c, solution in enumerate(solves):
            forces = solution.traction * solution.areas[:, None]
            moments = monomials((solution.points - centre) / radius).T @ forces  # (10, 3)
            load = np.zeros(6)
            if c < 6:
                load[c] = -1.0  # the fluid's force or torque on the cell is minus the load
            moments = exact_loads(moments, load[:3], load[3:] / radius)
            weights[:, :, c] = to_weights @ moments
        return cls(STENCIL * (STENCIL_RADIUS * radius) + centre, weights)


class FarField:
    """The far pairs' part of the grand mobility and of the flow's motion (module docstring) for
    the model of ``hydro`` (a ``HydrodynamicSolves``), as rows of COUPLING_SHAPES: what the pair
    adds to the cells alone, which is all coupling (its cells' own blocks are zero, so they are
    not kept)."""

    def __init__(self, hydro):
        from .. import runtime
        from ..kernels import far_field as kernels

        model = hydro.model
        self.model, self.lone_of = model, hydro.lone_of
        self.height_lattice = hydro.interaction  # the pair snapshots' heights
        self.device = runtime.resolve_device(hydro.mobility.device)
        self.options = model.solver.without_accuracy()
        self._launch = kernels.pair_couplings
        self._kernels = kernels.build_far_field_kernels(runtime.init().float64 if model.solver.dtype == "float64"
                                                        else runtime.init().float32, model.flow.wall)
        self.store = (SnapshotStore((CellTractions,), size_limit=model.solver.snapshot_store_size)
                      if model.solver.snapshot_store == "on" else None)
        self.solved = 0  # traction sets solved (not read from the store)
        self._sets: dict = {}  # (mesh index, height index) -> row of the arrays below
        self._tractions: list[CellTractions] = []
        # of the last evaluation: (pairs (2, P), their keys (P, 4 height combinations, 4), rows (P, 4, row))
        self._last = None

    def rows(self, bodies, first, second, offsets) -> np.ndarray:
        """(P, COUPLING_SIZE) the far pairs (first[p], second[p]) at lateral ``offsets`` (m, of the
        second cell from the first), rows of COUPLING_SHAPES: the coupling of each one's traction
        in the flow onto each cell's motion and of each cell's loads onto the other's motion. Each
        cell's tractions are interpolated linearly between the two lattice heights around its
        own (the coupling is linear in either cell's), so a pair is the bilinear blend of its
        four height combinations, each kept until its key changes."""
        n_pairs = len(first)
        radii = self.model.outer_radii
        sets, shares = self._height_sets(bodies)  # (n, 2) below / above, (n, 2) their weights
        lattice = np.round(np.asarray(offsets, dtype=float).reshape(-1, 2) / FAR_LATERAL).astype(int)
        # (P, 4 combinations, key): the first cell's set below or above, the second's likewise
        combination = np.array([(0, 0), (0, 1), (1, 0), (1, 1)])
        keys = np.concatenate([sets[first][:, combination[:, 0], None], sets[second][:, combination[:, 1], None],
                               np.repeat(lattice[:, None, :], 4, axis=1)], axis=2)
        weights = shares[first][:, combination[:, 0]] * shares[second][:, combination[:, 1]]
        pairs = np.stack([first, second])
        last = self._last
        if last is None or not np.array_equal(last[0], pairs):
            last = self._last = (pairs, np.full_like(keys, -1), np.zeros((n_pairs, 4, COUPLING_SIZE)))
        _, kept_keys, rows = last
        stale = np.any(keys != kept_keys, axis=2) & (weights > 0.0)
        if np.any(stale):
            pair_of, _ = np.nonzero(stale)
            unique, which = np.unique(keys[stale], axis=0, return_inverse=True)
            rows[stale] = self._evaluated(unique, radii[first[pair_of]], radii[second[pair_of]], which.ravel())
            kept_keys[stale] = keys[stale]
        return np.einsum("pc,pcr->pr", weights, rows)  # combinations never evaluated hold zeros and weigh 0

    def _height_sets(self, bodies):
        """((n, 2) the traction sets at the lattice heights below and above each cell, (n, 2) their
        linear interpolation weights); a cell on a lattice height (to ROUND_OFF) takes it alone."""
        radii = self.model.outer_radii
        level = np.array([b.position[2] for b in bodies]) / self.height_lattice
        nearest = np.round(level)
        level = np.where(np.abs(level - nearest) < ROUND_OFF, nearest, level)
        below = np.floor(level)
        above_share = level - below
        sets = np.array([[self._set(self.lone_of[i], int(h) + step, bodies[i].mesh, radii[i]) if share > 0 or step == 0
                          else -1 for step, share in ((0, 1.0), (1, above_share[i]))]
                         for i, h in enumerate(below)])
        return sets, np.column_stack([1.0 - above_share, above_share])

    def _set(self, mesh_index: int, height_index: int, mesh, radius: float) -> int:
        """The row of the tractions of ``mesh`` at lattice height ``height_index``: kept, else from
        the disk store (``snapshot_store.py``, as the lone and pair snapshots), else solved."""
        key = (mesh_index, height_index)
        if key not in self._sets:
            height = height_index * self.height_lattice
            digest = None
            if self.store is not None:
                digest = snapshot_digest(("tractions",) + key, [Body(mesh, position=(0.0, 0.0, height))], [radius],
                                         self.model.solver, self.model.flow, 0.0, "traction", self.device)
            found = self.store.get(digest) if digest else None
            if found is None:
                found = (CellTractions.solved(mesh, height, radius, self.model.flow, self.options, self.device),)
                self.solved += 1
                if digest:
                    self.store.put(digest, found)
            self._sets[key] = len(self._tractions)
            self._tractions.append(found[0])
        return self._sets[key]

    def _evaluated(self, keys, radius_first, radius_second, which) -> np.ndarray:
        """The rows of the pairs whose keys are ``keys[which]`` (the kernel runs once per key)."""
        tractions = self._tractions
        points = np.array([t.points for t in tractions])
        weights = np.array([t.weights for t in tractions])
        offset = np.column_stack([keys[:, 2:] * FAR_LATERAL, np.zeros(len(keys))])
        coupling, reverse = self._launch(self._kernels, self.device, points, weights, weights[..., :6],
                                         keys[:, 0], keys[:, 1], offset, self.model.flow.viscosity)
        coupling, reverse = coupling[which], reverse[which]
        # basis loads: unit forces and torques of 1 N times the outer radius (hydrodynamics._body_loads)
        columns = np.concatenate([np.ones((len(which), 3)), np.repeat(radius_first[:, None], 3, axis=1)], axis=1)
        on_second = coupling[:, :, :6] * columns[:, None, :]  # (P, motion of the second, load on the first)
        # the second's loads on the first's motion: the same matrix transposed (reciprocity), its
        # torque loads scaled by the second's radius
        columns[:, 3:] = radius_second[:, None]
        on_first = np.swapaxes(coupling[:, :, :6], 1, 2) * columns[:, None, :]
        n = len(which)
        flow_v, flow_w = np.zeros((n, 2, 3)), np.zeros((n, 2, 3))
        flow_v[:, 0], flow_w[:, 0] = reverse[:, :3], reverse[:, 3:]
        flow_v[:, 1], flow_w[:, 1] = coupling[:, :3, 6], coupling[:, 3:, 6]
        # (pair, loaded cell, load component, 3): the motion of the other cell
        grand_v, grand_w = np.zeros((n, 2, 6, 3)), np.zeros((n, 2, 6, 3))
        grand_v[:, 0], grand_w[:, 0] = np.swapaxes(on_second[:, :3], 1, 2), np.swapaxes(on_second[:, 3:], 1, 2)
        grand_v[:, 1], grand_w[:, 1] = np.swapaxes(on_first[:, :3], 1, 2), np.swapaxes(on_first[:, 3:], 1, 2)
        return np.concatenate([a.reshape(n, -1) for a in (flow_v, flow_w, grand_v, grand_w)], axis=1)
