"""Time stepping of a scene (DESIGN.md, "one time step"): the one place that fixes the order of
a step. This first version moves rigid bodies with the mobility solver under external loads
(gravity with buoyancy); repulsion, bonds and deformation plug in as further load terms.

    geometry (Body list from the state) -> loads -> MobilitySolver (blocks of fixed bodies kept)
    -> integrate (Euler or Heun) with an adaptive step: shorter near contact, and a step that
       would make bodies touch is retried at half the size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import integrate
from .body import Body
from .mobility import MobilitySolver
from .placement import PlacementError, check_placement

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
    """Rigid bodies (meshes, fixed flags, densities in kg/m^3) moved by a MobilitySolver."""

    def __init__(self, meshes, fixed, solver: MobilitySolver, *, densities=None, fluid_density: float = 1000.0,
                 gravity: float = 0.0, scheme: str = "heun", policy: StepPolicy = StepPolicy()):
        self.meshes = list(meshes)
        self.fixed = np.asarray(fixed, dtype=bool)
        if len(self.fixed) != len(self.meshes):
            raise ValueError(f"fixed must have one flag per mesh ({len(self.meshes)}), got {len(self.fixed)}")
        if scheme not in integrate.SCHEMES:
            raise ValueError(f"scheme must be one of {integrate.SCHEMES}, got {scheme!r}")
        self.solver = solver
        self._accepted = None  # the state the last step returned, placement already checked
        self.scheme = scheme
        self.policy = policy
        densities = np.full(len(self.meshes), fluid_density) if densities is None else np.asarray(densities, float)
        # gravity and buoyancy: (rho_cell - rho_fluid) V g, downwards, on free bodies
        volumes = np.array([m.volume() for m in self.meshes])
        self.external_force = np.zeros((len(self.meshes), 3))
        self.external_force[:, 2] = -(densities - fluid_density) * volumes * gravity
        self.external_force[self.fixed] = 0.0

    def bodies(self, state: integrate.State) -> list[Body]:
        return [Body(m, position=p, orientation=q, fixed=bool(f))
                for m, p, q, f in zip(self.meshes, state.positions, state.orientations, self.fixed)]

    def velocities(self, state: integrate.State, checked: bool = False):
        """(U, Omega) of every body; ``checked``: the placement of ``state`` is known valid."""
        sol = self.solver.solve(self.bodies(state), forces=self.external_force,
                                check_placement_first=not checked)
        self.last_solution = sol  # loads and GMRES figures of the latest solve, for the output
        return sol.velocity, sol.angular_velocity

    def smallest_gap(self, state: integrate.State) -> float:
        """A cheap lower bound of the smallest gap that can close: wall clearance of the lowest
        node of each free body, and centre distance minus outer radii for every pair with a
        free body in it (fixed bodies never close a gap between themselves)."""
        nodes = [b.world_nodes() for b in self.bodies(state)]
        free = ~self.fixed
        gap = min((n[:, 2].min() for n, f in zip(nodes, free) if f), default=np.inf) if self.solver.wall else np.inf
        radii = [np.linalg.norm(n - p, axis=1).max() for n, p in zip(nodes, state.positions)]
        for i in range(len(nodes)):
            for j in range(i + 1, len(nodes)):
                if free[i] or free[j]:
                    gap = min(gap, np.linalg.norm(state.positions[i] - state.positions[j]) - radii[i] - radii[j])
        return max(float(gap), 0.0)

    def step(self, state: integrate.State):
        """One adaptive step; returns (new state, (U, Omega), dt).

        The velocities at ``state`` are computed once, even when the step is retried, and
        without a second placement check if ``state`` is the one this simulator just returned.
        A step whose predictor or result would make bodies touch is retried at half the size.
        """
        dt = self.policy.dt(self.smallest_gap(state))
        start = self.velocities(state, checked=state is self._accepted)

        def velocities(s):
            return start if s is state else self.velocities(s)

        while True:
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
