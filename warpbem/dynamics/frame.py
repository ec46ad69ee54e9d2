"""The record of one state (a row of a run's HDF5 file). Every column describes the frame's own
state: positions and orientations, and the motion, loads and GMRES figures solved at those
positions with every load evaluated there (the repulsion by its law at the state's own gaps,
not the backward-Euler force of the step that follows)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


class Column(NamedTuple):
    """An HDF5 column: its unit, the shape of one row and what it holds."""

    unit: str
    shape: tuple
    description: str = ""


AT_STATE = "solved at this frame's positions, with every load evaluated there"


# frame column -> what it holds, of the accuracy target's ChosenSettings (its field of the same
# name without the prefix; 0 subdivisions: the meshes as given)
ACCURACY_COLUMNS = {"accuracy_error_estimate": "the estimated largest relative error",
                    "accuracy_subdivisions": "the library meshes' subdivisions k (0: as given)",
                    "accuracy_density_order": "the density order", "accuracy_contact_refinement": "the refinement ratio"}


def frame_columns(model) -> dict[str, Column]:
    """The columns of a run's frames for ``model``: the core ones, each interaction's loads
    (``<name>_force``, ``<name>_torque``) and each interaction's own state (``<name>_<column>``)."""
    n = model.n_bodies
    columns = {
        "time": Column("s", ()),
        "dt": Column("s", (), "length of the step that ended at this frame (0 for the first)"),
        "steps": Column("1", (), "steps taken since t = 0"),
        "position": Column("m", (n, 3), "reference point of each body"),
        "orientation": Column("1 (unit quaternion w, x, y, z)", (n, 4)),
        "velocity": Column("m/s", (n, 3), f"of each reference point, {AT_STATE}; prescribed for fixed bodies"),
        "angular_velocity": Column("rad/s", (n, 3), AT_STATE),
        "force": Column("N", (n, 3), "free bodies: the sum of the interactions' loads; fixed bodies: the load"
                        f" that holds them (minus the hydrodynamic force and the contact forces); {AT_STATE}"),
        "torque": Column("N m", (n, 3), f"as force, about each reference point; {AT_STATE}"),
        "gmres_iterations": Column("1", (), "GMRES iterations of all solves at this state"),
        "gmres_residual": Column("1", (), "largest relative residual of the solves at this state"),
        "closest_gap": Column("m", (), "exact smallest surface gap of a free body to another body or the wall"),
        "closest_body_gap": Column("m", (), "exact smallest surface gap of a free body to another body (inf: no"
                                   " other body)"),
        "wall_gap": Column("m", (), "exact smallest surface gap of a free body to the wall (inf: no wall)"),
    }
    if model.solver.accuracy is not None:  # what the accuracy target chose (hydro/accuracy.py)
        columns.update({name: Column("1", (), f"{what} of the last mobility solve at or before this state, as the"
                                     " accuracy target chose it")
                        for name, what in ACCURACY_COLUMNS.items()})
    for x in model.bound_interactions:
        columns[f"{x.name}_force"] = Column("N", (n, 3), f"load of the {x.name} interaction on each body, {AT_STATE}")
        columns[f"{x.name}_torque"] = Column("N m", (n, 3), f"its torque about each reference point, {AT_STATE}")
        for name, (unit, shape) in x.state_columns().items():
            columns[f"{x.name}_{name}"] = Column(unit, tuple(shape), f"state of the {x.name} interaction")
        for name, (unit, shape, description) in x.derived_columns().items():
            columns[name] = Column(unit, tuple(shape), description)
    return columns


@dataclass(frozen=True)
class Frame:
    """One state's record (units as in ``frame_columns``); ``loads``: {interaction name: Loads}.

    Examples
    --------
    >>> import warpbem as wb
    >>> model = wb.Model([wb.mesh.sphere(radius=5e-6, subdivisions=2)], [False], wb.Flow(shear_rate=100.0))
    >>> frame = wb.Simulator(model).frame(model.initial_state([[0.0, 0.0, 10e-6]]))
    >>> round(float(frame.velocity[0, 0]) / (100.0 * 10e-6), 2)   # U / (shear rate x height), h/a = 2
    0.97
    >>> sorted(frame.columns())[:4]
    ['angular_velocity', 'closest_body_gap', 'closest_gap', 'dt']
    """

    time: float
    dt: float
    steps: int
    positions: np.ndarray
    orientations: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    gmres_iterations: int
    gmres_residual: float
    closest_gap: float
    closest_body_gap: float
    wall_gap: float
    loads: dict
    parts: dict
    derived: dict

    def columns(self) -> dict[str, np.ndarray]:
        row = {"time": self.time, "dt": self.dt, "steps": self.steps, "position": self.positions,
               "orientation": self.orientations, "velocity": self.velocity,
               "angular_velocity": self.angular_velocity, "force": self.force, "torque": self.torque,
               "gmres_iterations": self.gmres_iterations, "gmres_residual": self.gmres_residual,
               "closest_gap": self.closest_gap, "closest_body_gap": self.closest_body_gap,
               "wall_gap": self.wall_gap}
        for name, loads in self.loads.items():
            row[f"{name}_force"], row[f"{name}_torque"] = loads.force, loads.torque
        for name, part in self.parts.items():
            row.update({f"{name}_{column}": value for column, value in part.items()})
        row.update(self.derived)
        return row
