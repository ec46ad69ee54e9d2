"""Time stepping of a scene (DESIGN.md, "one time step"): the one place that fixes the order of
a step. Rigid bodies move with the mobility solver under external loads (gravity with
buoyancy, given forces and torques) and electrostatic repulsion; bonds and deformation plug in
as further load terms.

    geometry (Body list from the state) -> loads -> MobilitySolver (blocks of fixed bodies kept)
    -> repulsion: exact gaps of the contacts within reach, their mobilities (one extra solve per
       contact, same system) and backward-Euler contact forces for the step (repulsion.py)
    -> integrate (Euler or Heun) with an adaptive step: shorter near contact, and a step that
       would make bodies (or their roughness layers) touch is retried at half the size.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import integrate
from .body import Body
from .contact import WALL, GapFinder, candidate_pairs, outer_radius
from .mobility import MobilitySolver
from .placement import PlacementError, check_placement
from .repulsion import Repulsion

PROBE_FORCE = 1e-12  # N: size of the unit load of a contact-mobility solve (the response is linear)

STANDARD_GRAVITY = 9.80665  # m/s^2


@dataclass(frozen=True)
class StepPolicy:
    """Adaptive step: dt = dt_max far from contact, shrinking in proportion to the smallest gap
    below ``contact_gap`` (m) down to dt_min (thesis ch. 3.3: 1e-4 to 1e-5 s)."""

    dt_max: float = 1e-4
    dt_min: float = 1e-5
    contact_gap: float = 0.5e-6

    def __post_init__(self):
        if not (0 < self.dt_min <= self.dt_max) or not np.isfinite(self.dt_max):
            raise ValueError(f"need 0 < dt_min <= dt_max, got dt_min={self.dt_min}, dt_max={self.dt_max}")
        if not self.contact_gap > 0:
            raise ValueError(f"contact_gap must be positive, got {self.contact_gap}")

    def dt(self, gap: float) -> float:
        return float(np.clip(self.dt_max * gap / self.contact_gap, self.dt_min, self.dt_max))


class Simulator:
    """Rigid bodies (meshes, fixed flags, densities in kg/m^3) moved by a MobilitySolver.

    ``forces``/``torques`` (n, 3; N, N m): further constant loads on free bodies.
    ``repulsion``: a Repulsion (thesis eq. 3.1) acting between free bodies and everything
    else, or None.
    """

    def __init__(self, meshes, fixed, solver: MobilitySolver, *, densities=None, fluid_density: float = 1000.0,
                 gravity: float = 0.0, scheme: str = "heun", policy: StepPolicy = StepPolicy(),
                 forces=None, torques=None, repulsion: Repulsion | None = None):
        self.meshes = list(meshes)
        n = len(self.meshes)
        self.fixed = np.asarray(fixed, dtype=bool)
        if len(self.fixed) != n:
            raise ValueError(f"fixed must have one flag per mesh ({n}), got {len(self.fixed)}")
        if scheme not in integrate.SCHEMES:
            raise ValueError(f"scheme must be one of {integrate.SCHEMES}, got {scheme!r}")
        self.solver = solver
        self._accepted = None  # the state the last step returned, placement already checked
        self.scheme = scheme
        self.policy = policy
        self.repulsion = repulsion
        self.gaps = GapFinder(solver.device)
        densities = np.full(n, fluid_density) if densities is None else np.asarray(densities, float)
        # gravity and buoyancy: (rho_cell - rho_fluid) V g, downwards, on free bodies
        volumes = np.array([m.volume() for m in self.meshes])
        self.external_force = np.zeros((n, 3)) if forces is None else np.array(forces, dtype=float).reshape(n, 3)
        self.external_torque = np.zeros((n, 3)) if torques is None else np.array(torques, dtype=float).reshape(n, 3)
        self.external_force[:, 2] -= (densities - fluid_density) * volumes * gravity
        self.external_force[self.fixed] = 0.0
        self.external_torque[self.fixed] = 0.0
        self.outer_radii = np.array([outer_radius(m) for m in self.meshes])
        self.last_contacts = []  # (Gap, separation eps, force) of the latest evaluation

    def bodies(self, state: integrate.State) -> list[Body]:
        return [Body(m, position=p, orientation=q, fixed=bool(f))
                for m, p, q, f in zip(self.meshes, state.positions, state.orientations, self.fixed)]

    def _pairs(self, state: integrate.State, within: float):
        return candidate_pairs(state.positions, self.outer_radii, self.fixed, self.solver.wall, within)

    def velocities(self, state: integrate.State, dt: float | None = None, checked: bool = False):
        """(U, Omega) of every body over a step dt (s) from ``state`` (the contact forces are
        those at the end of the step); ``checked``: the placement of ``state`` is known valid."""
        bodies = self.bodies(state)
        sol = self.solver.solve(bodies, forces=self.external_force, torques=self.external_torque,
                                check_placement_first=not checked)
        self.last_contacts = []
        if self.repulsion is not None:
            dt = self.policy.dt(self.smallest_gap(state)) if dt is None else dt
            sol = self._with_repulsion(state, bodies, sol, dt)
        self.last_solution = sol  # loads and GMRES figures of the latest solve, for the output
        return sol.velocity, sol.angular_velocity

    def _with_repulsion(self, state, bodies, sol, dt):
        rep = self.repulsion
        speed = np.abs(sol.velocity).max() + (np.abs(sol.angular_velocity).max() * self.outer_radii.max())
        reach = rep.reach + 2.0 * rep.cell_roughness + 2.0 * speed * dt
        contacts = []
        for i, j in self._pairs(state, reach):
            gap = self.gaps.between(bodies, i, j)
            eps = rep.separation(gap.distance, j == WALL)
            if eps <= 0.0:
                other = "the wall" if j == WALL else f"body {j}"
                raise PlacementError(f"the roughness layers of body {i} and {other} touch (gap {gap.distance:.4g} m)")
            rate = self._separation_rate(gap, state, sol.velocity, sol.angular_velocity)
            if eps + dt * min(rate, 0.0) < rep.reach:
                contacts.append((gap, eps, rate))
        if not contacts:
            return sol
        # contact mobilities: the motion caused by a unit repulsive force at each contact
        responses = []
        for gap, _, _ in contacts:
            forces, torques = self._contact_loads([gap], [PROBE_FORCE], state)
            r = self.solver.solve(bodies, forces=forces, torques=torques, check_placement_first=False,
                                  background=False)
            responses.append(r)
        matrix = np.array([[self._separation_rate(g, state, r.velocity, r.angular_velocity) / PROBE_FORCE
                            for r in responses] for g, _, _ in contacts])
        response = 0.5 * (matrix + matrix.T)  # symmetric by reciprocity; average out GMRES noise
        eps = np.array([c[1] for c in contacts])
        rate = np.array([c[2] for c in contacts])
        magnitudes, _ = rep.implicit_forces(eps, rate, response, dt)
        velocity, angular_velocity = sol.velocity.copy(), sol.angular_velocity.copy()
        force, torque = sol.force.copy(), sol.torque.copy()
        for f, r in zip(magnitudes, responses):
            scale = f / PROBE_FORCE
            velocity += scale * r.velocity
            angular_velocity += scale * r.angular_velocity
            force += scale * r.force
            torque += scale * r.torque
        # a held body must also be held against the repulsion it receives
        on_fixed_force, on_fixed_torque = self._contact_loads([c[0] for c in contacts], magnitudes, state, fixed=True)
        force -= on_fixed_force
        torque -= on_fixed_torque
        self.last_contacts = [(g, e, f) for (g, e, _), f in zip(contacts, magnitudes)]
        return replace(sol, velocity=velocity, angular_velocity=angular_velocity, force=force, torque=torque)

    def _contact_loads(self, gaps, magnitudes, state, fixed=False):
        """Forces and torques of repulsive forces along each gap's normal on the free bodies (on
        the fixed ones if ``fixed``)."""
        forces = np.zeros((len(self.meshes), 3))
        torques = np.zeros((len(self.meshes), 3))
        for gap, f in zip(gaps, magnitudes):
            for body, point, sign in ((gap.body, gap.point, 1.0), (gap.other, gap.other_point, -1.0)):
                if body != WALL and self.fixed[body] == fixed:
                    forces[body] += sign * f * gap.normal
                    torques[body] += sign * f * np.cross(point - state.positions[body], gap.normal)
        return forces, torques

    def _separation_rate(self, gap, state, velocity, angular_velocity) -> float:
        """d(gap)/dt of the closest points for the given rigid motions."""
        def point_velocity(body, point):
            if body == WALL:
                return np.zeros(3)
            return velocity[body] + np.cross(angular_velocity[body], point - state.positions[body])

        return float(gap.normal @ (point_velocity(gap.body, gap.point) - point_velocity(gap.other, gap.other_point)))

    def closest_gap(self, state: integrate.State) -> float:
        """The exact smallest surface gap (m) between a free body and another body or the wall
        (inf if there is none): the figure that shows no overlap ever occurred."""
        bodies = self.bodies(state)
        return min((self.gaps.between(bodies, i, j).distance for i, j in self._pairs(state, np.inf)), default=np.inf)

    def smallest_gap(self, state: integrate.State) -> float:
        """The smallest surface gap (m) that can close: exact (closest points) for free bodies
        within ``contact_gap`` of another body or the wall by their bounding spheres, the
        bounding-sphere gap otherwise; gaps between fixed bodies never close."""
        pairs = self._pairs(state, self.policy.contact_gap)
        if not pairs:
            return self.policy.contact_gap
        bodies = self.bodies(state)
        return max(min(self.gaps.between(bodies, i, j).distance for i, j in pairs), 0.0)

    def step(self, state: integrate.State):
        """One adaptive step; returns (new state, (U, Omega), dt).

        The velocities at ``state`` are computed once per step size (once in all without
        repulsion), even when the step is retried, and without a second placement check if
        ``state`` is the one this simulator just returned. A step whose predictor or result
        would make bodies touch is retried at half the size.
        """
        dt = self.policy.dt(self.smallest_gap(state))
        start = {}

        while True:
            def velocities(s):
                if s is not state:
                    return self.velocities(s, dt)
                key = dt if self.repulsion is not None else None
                if key not in start:
                    start[key] = self.velocities(state, dt, checked=state is self._accepted)
                return start[key]

            try:
                new, motion = integrate.step(state, velocities, dt, self.scheme)
                check_placement(self.bodies(new), self.solver.wall)
            except PlacementError as err:
                if dt <= self.policy.dt_min * (1 + 1e-12):
                    raise PlacementError(f"at t = {state.time:.6g} s even the smallest step dt_min ="
                                         f" {self.policy.dt_min:g} s makes bodies touch: {err}") from err
                dt = max(0.5 * dt, self.policy.dt_min)
                continue
            self._accepted = new
            return new, motion, dt

    def run(self, state: integrate.State, t_end: float, callback=None) -> integrate.State:
        """Step until t_end; ``callback(state, motion, dt)`` after each step."""
        while state.time < t_end - 1e-12 * max(1.0, abs(t_end)):
            state, motion, dt = self.step(state)
            if callback is not None:
                callback(state, motion, dt)
        return state
