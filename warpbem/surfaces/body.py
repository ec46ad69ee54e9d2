"""Rigid bodies: a reference mesh placed in the world, free or held fixed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from .mesh import Mesh


def _vector(name, value, length):
    try:
        arr = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be {length} numbers, got {value!r}") from err
    if arr.shape != (length,):
        raise ValueError(f"{name} must have {length} components, got shape {np.shape(value)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


def rotation_matrix(quaternion) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = quaternion
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


@dataclass(frozen=True, eq=False)
class Body:
    """A rigid body: ``mesh`` (metres, about its reference point) at ``position`` (m), turned by
    the unit quaternion ``orientation`` (w, x, y, z; normalised here).

    ``fixed=False``: free; its velocity follows from the force and torque applied to it.
    ``fixed=True``: held; it moves with the prescribed ``velocity`` (m/s) and
    ``angular_velocity`` (rad/s), zero by default (an adherent cell at rest), and the solver
    returns the force and torque needed to hold it.

    ``surface_velocity`` (free bodies; (elements, 3), m/s, world frame): the velocity of each
    element's surface on top of the rigid motion (a deforming cell's, a squirmer's slip); only
    its non-rigid part counts, the rigid motion being what the solver finds. None: rigid.

    ``name``: how messages call it ("bodies 'free cell' and 'dome' overlap"); None: by its index
    in the list of bodies.

    Examples
    --------
    A free cell passing an adherent one held at rest 0.25 um above the wall (thesis ch. 5.3),
    and a cell placed through the wall, refused before any solve:

    >>> import warpbem as wb
    >>> sphere = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> free = wb.Body(sphere, position=(-20e-6, 10.5e-6, 7.75e-6), name="free cell")
    >>> adherent = wb.Body(sphere, position=(0.0, 0.0, 5.25e-6), fixed=True, name="adherent cell")
    >>> free.fixed, adherent.fixed, adherent.velocity.tolist()
    (False, True, [0.0, 0.0, 0.0])
    >>> wb.solve_mobility([wb.Body(sphere, position=(0.0, 0.0, 4e-6))], shear_rate=100.0)
    Traceback (most recent call last):
    ...
    warpbem.surfaces.placement.PlacementError: body 0 touches or crosses the wall z = 0: ...
    """

    mesh: Mesh
    position: tuple = (0.0, 0.0, 0.0)
    orientation: tuple = (1.0, 0.0, 0.0, 0.0)
    fixed: bool = False
    velocity: tuple = (0.0, 0.0, 0.0)
    angular_velocity: tuple = (0.0, 0.0, 0.0)
    surface_velocity: np.ndarray | None = None
    name: str | None = None

    def __post_init__(self):
        if not isinstance(self.mesh, Mesh):
            raise TypeError(f"mesh must be a warpbem.mesh.Mesh, got {type(self.mesh).__name__}")
        self.mesh.check()  # closed and outward, else the integral equation has no meaning
        object.__setattr__(self, "position", _vector("position", self.position, 3))
        self._check_scale()
        q = _vector("orientation", self.orientation, 4)
        norm = np.linalg.norm(q)
        if norm < 1e-12:
            raise ValueError("orientation quaternion must be non-zero")
        q = q / norm
        q.setflags(write=False)
        object.__setattr__(self, "orientation", q)
        if not isinstance(self.fixed, (bool, np.bool_)):
            raise TypeError(f"fixed must be True or False, got {self.fixed!r}")
        velocity = _vector("velocity", self.velocity, 3)
        angular_velocity = _vector("angular_velocity", self.angular_velocity, 3)
        if not self.fixed and (np.any(velocity) or np.any(angular_velocity)):
            raise ValueError("a prescribed velocity needs fixed=True; free bodies get theirs from the solver")
        object.__setattr__(self, "velocity", velocity)
        object.__setattr__(self, "angular_velocity", angular_velocity)
        if self.surface_velocity is not None:
            slip = np.array(self.surface_velocity, dtype=float)
            if slip.shape != (len(self.mesh.elements), 3) or not np.all(np.isfinite(slip)):
                raise ValueError(f"surface_velocity must be finite, one 3-vector per element "
                                 f"({len(self.mesh.elements)}, 3), got shape {slip.shape}")
            if self.fixed:
                raise ValueError("a surface_velocity is for free bodies; a fixed body's surface moves rigidly")
            slip.setflags(write=False)
            object.__setattr__(self, "surface_velocity", slip)
        if self.name is not None and not isinstance(self.name, str):
            raise TypeError(f"name must be a string or None, got {self.name!r}")

    def _check_scale(self):
        """Refuse a position and a mesh in different units: a body farther from the origin than
        units.FARTHEST_IN_SIZES of its own sizes (a 5e-6 m sphere placed at 6, meaning 6 um)."""
        farthest = self.position[np.argmax(np.abs(self.position))]
        if abs(farthest) > units.FARTHEST_IN_SIZES * self.mesh.size():
            raise ValueError(f"position: {farthest:g} m is {abs(farthest) / self.mesh.size():.2g} times the body's size"
                             f" ({self.mesh.size():.3g} m): the position and the mesh are in different units; both"
                             f" are in metres (warpbem.units.um = {units.um:g})")

    def rotation(self) -> np.ndarray:
        return rotation_matrix(self.orientation)

    def world_nodes(self) -> np.ndarray:
        """(n_nodes, 3) node positions in the world frame, metres."""
        return self.mesh.nodes @ self.rotation().T + self.position
