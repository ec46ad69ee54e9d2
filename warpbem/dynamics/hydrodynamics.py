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
mobility does not depend on it) and, with more than one body, their lateral positions to
multiples of ``reuse_lateral`` (default 50 d): a cell's mobility changes with its height over
the gap to the wall (0.2 um when rolling), with another cell's position only over their
distance (microns). A lone body above the wall in shear
(u = gdot z e_x) is invariant under translation along the wall, so its snapshots are keyed by
height alone and computed at x = y = 0. The background for any explicit loads and the stiff
forces follow from a snapshot by linearity, so a step costs no solve while the cells stay within
d of a snapped configuration already seen; the error is first order in d (charted by
``benchmarks/adhesion.py``). The evaluation stays a pure function of the state (resumed runs
reproduce uninterrupted ones). A snapped configuration that is not a valid placement (a gap
below d) is solved exactly.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from ..surfaces.body import Body
from ..surfaces.placement import PlacementError, check_placement

PROBE_FORCE = 1e-12  # N: the scale of a basis load's solve (the response is linear)
MAX_SNAPSHOTS = 256


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
        return tuple(np.einsum("k,kbi->bi", z, a) for a in (self.velocity, self.angular_velocity,
                                                            self.force, self.torque))

    def quadratic(self) -> np.ndarray:
        """Q_kl = (load k) . (motion l), symmetrised (reciprocity; removes the GMRES noise)."""
        q = (np.einsum("kbi,lbi->kl", self.load_force, self.velocity)
             + np.einsum("kbi,lbi->kl", self.load_torque, self.angular_velocity))
        return 0.5 * (q + q.T)


@dataclass(frozen=True)
class Hydrodynamics:
    """The solves at one state: ``background`` (flow and explicit loads, a ``Motion``) and the
    ``basis`` Responses of the stiff forces, of ``kind`` "coordinates" (a unit force along each
    implicit coordinate) or "bodies" (unit forces, and torques of 1 N times the outer radius, on
    each free body in turn)."""

    background: Motion
    basis: Responses | None
    kind: str


def is_spherical(mesh, rtol: float = 1e-9) -> bool:
    """Whether every node lies on one sphere about the reference point (its mobility does not
    depend on its orientation)."""
    r = np.linalg.norm(mesh.nodes, axis=1)
    return bool(r.max() - r.min() <= rtol * r.max())


class HydrodynamicSolves:
    """The mobility solves of a model's states, exact or from snapshots (module docstring)."""

    def __init__(self, model, solver):
        self.model = model
        self.solver = solver
        self.tolerance = model.solver.reuse_tolerance
        self.lateral = model.solver.reuse_lateral or 50.0 * self.tolerance
        self.spherical = [is_spherical(m) for m in model.meshes]
        self.free = np.flatnonzero(~model.fixed_mask)
        self._snapshots: OrderedDict = OrderedDict()
        self.snapshots_solved = 0

    def background(self, bodies, loads, stiff: bool):
        """(Motion of the flow and the explicit ``loads``, the snapshot used or None); snapshots
        serve states with ``stiff`` forces only (bonds), so a free-stream pass, whose
        configurations never repeat, costs one solve per state."""
        if self.tolerance > 0 and stiff:
            snapshot = self._snapshot(bodies)
            flow, basis = snapshot
            u, w, f, t = basis.combine(self.body_coefficients(loads.force, loads.torque))
            motion = Motion(flow.velocity + u, flow.angular_velocity + w, flow.force + f, flow.torque + t,
                            flow.iterations, flow.residual)
            return motion, snapshot
        return Motion.of(self.solver.solve(bodies, forces=loads.force, torques=loads.torque,
                                           check_placement_first=False)), None

    def basis(self, bodies, coordinates, snapshot) -> tuple[Responses, str]:
        """The Responses the implicit forces along ``coordinates`` are combined from."""
        if snapshot is not None:
            return snapshot[1], "bodies"
        if len(coordinates.values) <= 6 * len(self.free):
            mask = ~self.model.fixed_mask[:, None]
            return self._responses(bodies, coordinates.unit_force * mask, coordinates.unit_torque * mask), "coordinates"
        return self._grand_mobility(bodies), "bodies"

    def body_coefficients(self, force, torque) -> np.ndarray:
        """Coefficients (N) of loads on the free bodies in the "bodies" basis."""
        radii = self.model.outer_radii[self.free, None]
        return np.concatenate([force[self.free], torque[self.free] / radii], axis=1).ravel()

    def _body_loads(self):
        n, p = self.model.n_bodies, 6 * len(self.free)
        force, torque = np.zeros((p, n, 3)), np.zeros((p, n, 3))
        for k, b in enumerate(self.free):
            for i in range(3):
                force[6 * k + i, b, i] = 1.0
                torque[6 * k + 3 + i, b, i] = self.model.outer_radii[b]
        return force, torque

    def _responses(self, bodies, load_force, load_torque) -> Responses:
        solves = [self.solver.solve(bodies, forces=PROBE_FORCE * f, torques=PROBE_FORCE * t,
                                    check_placement_first=False, background=False)
                  for f, t in zip(load_force, load_torque)]
        stack = [np.array([getattr(s, name) for s in solves]) / PROBE_FORCE
                 for name in ("velocity", "angular_velocity", "force", "torque")]
        return Responses(*stack, load_force, load_torque, sum(s.iterations for s in solves),
                         max(s.residual for s in solves))

    def _grand_mobility(self, bodies) -> Responses:
        """The "bodies" basis with the free bodies' motion taken from the symmetrised grand
        mobility: the collocation discretisation is reciprocal only to its discretisation error
        (0.5 % in the translation-rotation coupling of a 24-element sphere), and a joint step
        whose rates and dissipation came from different halves would hold a cell at rest with a
        load that is not its holding load."""
        r = self._responses(bodies, *self._body_loads())
        q = r.quadratic()
        velocity, angular_velocity = r.velocity.copy(), r.angular_velocity.copy()
        for j, b in enumerate(self.free):
            velocity[:, b] = q[:, 6 * j:6 * j + 3]
            angular_velocity[:, b] = q[:, 6 * j + 3:6 * j + 6] / self.model.outer_radii[b]
        return Responses(velocity, angular_velocity, r.force, r.torque, r.load_force, r.load_torque,
                         r.iterations, r.residual)

    def _snapshot(self, bodies):
        key, snapped = self._snapped(bodies)
        if key in self._snapshots:
            self._snapshots.move_to_end(key)
            return self._snapshots[key]
        try:
            check_placement(snapped, self.model.flow.wall)
        except PlacementError:
            snapped, key = bodies, None  # too close to snap: solved exactly, not kept
        snapshot = (Motion.of(self.solver.solve(snapped, check_placement_first=False)),
                    self._grand_mobility(snapped))
        self.snapshots_solved += 1
        if key is not None:
            self._snapshots[key] = snapshot
            while len(self._snapshots) > MAX_SNAPSHOTS:
                self._snapshots.popitem(last=False)
        return snapshot

    def _snapped(self, bodies):
        d = self.tolerance
        alone = len(bodies) == 1
        key, snapped = [], []
        for i, b in enumerate(bodies):
            if b.fixed:
                snapped.append(b)
                continue
            spacing = np.array([self.lateral, self.lateral, d])
            cell = np.round(b.position / spacing)
            position = np.array([0.0, 0.0, cell[2] * d]) if alone else cell * spacing
            entry = (cell[2],) if alone else tuple(cell)
            orientation = np.array([1.0, 0.0, 0.0, 0.0])
            if not self.spherical[i]:
                q = np.round(b.orientation / (d / self.model.outer_radii[i]))
                entry += tuple(q)
                orientation = q / np.linalg.norm(q)
            key.append(entry)
            snapped.append(Body(b.mesh, position=position, orientation=orientation, fixed=False))
        return tuple(key), snapped
