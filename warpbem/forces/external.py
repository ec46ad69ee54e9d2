"""Explicit loads that do not depend on the configuration: gravity with buoyancy, and given
forces and torques. Both act on free bodies only: a fixed body is held against whatever acts
on it, and its holding load is the solver's answer to the flow and the contacts."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .interaction import BoundInteraction, Interaction, Loads

STANDARD_GRAVITY = 9.80665  # m/s^2
FLUID_DENSITY = 1000.0  # kg/m^3: plasma, about water's; also a cell's density by default (neutrally buoyant)


def _rows(name, value, n):
    arr = np.array(value, dtype=float)
    if arr.shape != (n, 3) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be {n} finite rows of 3 numbers, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


def _frozen(value) -> np.ndarray:
    """A read-only float array of ``value`` (a configuration's numbers, checked against the
    model by ``check``)."""
    arr = np.array(value, dtype=float)
    arr.setflags(write=False)
    return arr


class ConstantLoads(BoundInteraction):
    """The same ``force`` (n, 3) N and ``torque`` (n, 3) N m on the model's bodies at every state."""

    def __init__(self, interaction, model, force, torque):
        super().__init__(interaction, model)
        self.force, self.torque = force, torque

    def explicit_loads(self, bodies, contacts) -> Loads:
        return Loads(self.force.copy(), self.torque.copy())


@dataclass(frozen=True, eq=False)
class Gravity(Interaction):
    """Weight less buoyancy, (rho_body - rho_fluid) V g, downwards (-z), on each free body
    (thesis fig. 2.5: a cell of 1.05 g/cc in plasma of 1.0 g/cc sinks): ``densities`` (kg/m^3,
    one per body of the model), ``fluid_density`` (kg/m^3), ``acceleration`` g (m/s^2).

    Examples
    --------
    >>> import warpbem as wb
    >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> gravity = wb.Gravity([1070.0], fluid_density=1000.0)
    >>> weight = gravity.bound(wb.Model([cell], [False], interactions=[gravity])).force
    >>> round(float(weight[0, 2]) * 1e12, 3)     # pN: 70 kg/m^3 x the mesh's volume x g, downwards
    -0.359
    """

    name = "gravity"

    densities: np.ndarray
    fluid_density: float = FLUID_DENSITY
    acceleration: float = STANDARD_GRAVITY

    def __post_init__(self):
        object.__setattr__(self, "densities", _frozen(self.densities))
        if not (np.isfinite(self.fluid_density) and self.fluid_density > 0):
            raise ValueError(f"fluid_density must be positive (kg/m^3), got {self.fluid_density!r}")
        if not (np.isfinite(self.acceleration) and self.acceleration >= 0):
            raise ValueError(f"gravity acceleration must be >= 0 (m/s^2), got {self.acceleration!r}")

    def check(self, model):
        n = model.n_bodies
        if self.densities.shape != (n,) or not np.all(self.densities > 0):
            raise ValueError(f"densities must be {n} positive numbers (kg/m^3), got {self.densities.tolist()}")

    def bound(self, model, device=None) -> ConstantLoads:
        """The weight of each free body of ``model``, from its mesh's volume (``force``)."""
        weight = (self.densities - self.fluid_density) * np.array([m.volume() for m in model.meshes]) * self.acceleration
        force = np.zeros((model.n_bodies, 3))
        force[:, 2] = -np.where(model.fixed_mask, 0.0, weight)
        force = _rows("gravity force", force, model.n_bodies)
        return ConstantLoads(self, model, force, _frozen(np.zeros_like(force)))


@dataclass(frozen=True, eq=False)
class ExternalLoads(Interaction):
    """Given constant ``forces`` (N) and ``torques`` (N m, about the reference point), one row
    of 3 per body of the model, on free bodies.

    Examples
    --------
    >>> import warpbem as wb
    >>> push = wb.ExternalLoads(forces=[[0.0, 0.0, -1e-12]], torques=[[0.0, 0.0, 0.0]])   # 1 pN down
    >>> model = wb.Model([wb.mesh.sphere(radius=5e-6, subdivisions=2)], [False], interactions=[push])
    >>> model.interaction("external").forces.tolist()
    [[0.0, 0.0, -1e-12]]
    """

    name = "external"

    forces: np.ndarray
    torques: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "forces", _frozen(self.forces))
        object.__setattr__(self, "torques", _frozen(self.torques))

    def check(self, model):
        force = _rows("forces", self.forces, model.n_bodies)
        torque = _rows("torques", self.torques, model.n_bodies)
        for i in np.flatnonzero(model.fixed_mask):
            if np.any(force[i]) or np.any(torque[i]):
                raise ValueError(f"body {i} is fixed: its load is the solver's output; give loads for free bodies only")

    def bound(self, model, device=None) -> ConstantLoads:
        return ConstantLoads(self, model, self.forces, self.torques)
