"""Explicit loads that do not depend on the configuration: gravity with buoyancy, and given
forces and torques. Both act on free bodies only: a fixed body is held against whatever acts
on it, and its holding load is the solver's answer to the flow and the contacts."""

from __future__ import annotations

import numpy as np

from .interaction import Interaction, Loads

STANDARD_GRAVITY = 9.80665  # m/s^2
FLUID_DENSITY = 1000.0  # kg/m^3: plasma, about water's; also a cell's density by default (neutrally buoyant)


def _rows(name, value, n):
    arr = np.array(value, dtype=float)
    if arr.shape != (n, 3) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be {n} finite rows of 3 numbers, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


class Gravity(Interaction):
    """Weight less buoyancy, (rho_body - rho_fluid) V g, downwards (-z), on each free body
    (thesis fig. 2.5: a cell of 1.05 g/cc in plasma of 1.0 g/cc sinks)."""

    name = "gravity"

    def __init__(self, meshes, fixed, densities, fluid_density: float = FLUID_DENSITY,
                 acceleration: float = STANDARD_GRAVITY):
        densities = np.asarray(densities, dtype=float)
        if densities.shape != (len(meshes),) or not np.all(densities > 0):
            raise ValueError(f"densities must be {len(meshes)} positive numbers (kg/m^3), got {densities.tolist()}")
        if not (np.isfinite(fluid_density) and fluid_density > 0):
            raise ValueError(f"fluid_density must be positive (kg/m^3), got {fluid_density!r}")
        if not (np.isfinite(acceleration) and acceleration >= 0):
            raise ValueError(f"gravity acceleration must be >= 0 (m/s^2), got {acceleration!r}")
        weight = (densities - fluid_density) * np.array([m.volume() for m in meshes]) * acceleration
        force = np.zeros((len(meshes), 3))
        force[:, 2] = -np.where(np.asarray(fixed, dtype=bool), 0.0, weight)
        self.force = _rows("gravity force", force, len(meshes))

    def explicit_loads(self, bodies, contacts) -> Loads:
        return Loads(self.force.copy(), np.zeros_like(self.force))


class ExternalLoads(Interaction):
    """Given constant forces (N) and torques (N m, about the reference point) on free bodies."""

    name = "external"

    def __init__(self, fixed, forces, torques):
        fixed = np.asarray(fixed, dtype=bool)
        self.force = _rows("forces", forces, len(fixed))
        self.torque = _rows("torques", torques, len(fixed))
        for i in np.flatnonzero(fixed):
            if np.any(self.force[i]) or np.any(self.torque[i]):
                raise ValueError(f"body {i} is fixed: its load is the solver's output; give loads for free bodies only")

    def explicit_loads(self, bodies, contacts) -> Loads:
        return Loads(self.force.copy(), self.torque.copy())
