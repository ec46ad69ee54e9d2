"""QUAD9 surface meshes of closed bodies: generators, file I/O and consistency checks.

A mesh is a set of nodes and, per element, the indices of its 9 nodes in the order of
``warpbem.surfaces.quad9.REFERENCE_NODES``. Elements are oriented so that x_s x x_t points out of the
body. Coordinates are in metres, relative to the body's reference point (its centre for
torques and rotations; it must lie inside the body).

File format (``save``/``load``, plain text, ``#`` starts a comment)::

    warpbem-quad9 1
    units m
    nodes N
    x y z            (N lines)
    elements E
    n0 n1 ... n8     (E lines, 0-based node indices)

Examples
--------
A cell of radius 5 um on the k = 2 cube-sphere (6 k^2 = 24 elements), its volume and area
against the exact sphere's, written to a file and read back:

>>> import math, tempfile, pathlib
>>> import warpbem as wb
>>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
>>> cell.n_elements, len(cell.nodes)
(24, 98)
>>> print(f"{cell.volume() / (4 / 3 * math.pi * 5e-6**3):.4f} {cell.area() / (4 * math.pi * 5e-6**2):.4f}")
0.9983 0.9989
>>> path = pathlib.Path(tempfile.mkdtemp()) / "cell.quad9"
>>> wb.mesh.save(cell, path)
>>> bool((wb.mesh.load(path).nodes == cell.nodes).all())
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from . import quad9
from .placement import surface_samples, winding_number


class MeshError(ValueError):
    """A mesh that is not a closed, consistently outward-oriented QUAD9 surface."""


@dataclass(frozen=True, eq=False)
class Mesh:
    """``nodes`` and ``elements`` (module docstring). A library mesh (``sphere``, ``spheroid``,
    ``shapes.adherent_cell``) also knows its ``subdivisions`` k and the ``recipe`` that builds
    the same surface at another k (``at_subdivisions``), so that a solve with an accuracy target
    can choose the mesh (hydro/accuracy.py); a mesh read from a file or deformed has neither."""

    nodes: np.ndarray  # (n_nodes, 3) float64, metres
    elements: np.ndarray  # (n_elements, 9) int64
    subdivisions: int | None = None
    recipe: Callable[[int], "Mesh"] | None = field(default=None, repr=False)

    def __post_init__(self):
        nodes = np.ascontiguousarray(self.nodes, dtype=float)
        elements = np.ascontiguousarray(self.elements, dtype=np.int64)
        if nodes.ndim != 2 or nodes.shape[1] != 3:
            raise MeshError(f"nodes must have shape (n, 3), got {nodes.shape}")
        if elements.ndim != 2 or elements.shape[1] != 9 or len(elements) == 0:
            raise MeshError(f"elements must have shape (n, 9) with n > 0, got {elements.shape}")
        if not np.all(np.isfinite(nodes)):
            raise MeshError("nodes contain non-finite coordinates")
        if elements.min() < 0 or elements.max() >= len(nodes):
            raise MeshError(f"element node indices must lie in [0, {len(nodes) - 1}]")
        nodes.setflags(write=False)
        elements.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "elements", elements)

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    def is_spherical(self, rtol: float = 1e-9) -> bool:
        """Whether every node lies on one sphere about the reference point, within ``rtol`` of
        the largest node distance (its mobility then does not depend on its orientation)."""
        r = np.linalg.norm(self.nodes, axis=1)
        return bool(r.max() - r.min() <= rtol * r.max())

    def element_nodes(self) -> np.ndarray:
        """(E, 9, 3) node coordinates of every element."""
        return self.nodes[self.elements]

    def element_areas(self, order: int = 4) -> np.ndarray:
        _, vector_weights = quad9.surface_quadrature(self.element_nodes(), order)
        return np.linalg.norm(vector_weights, axis=-1).sum(axis=1)

    def area(self, order: int = 4) -> float:
        return float(self.element_areas(order).sum())

    def volume(self, order: int = 4) -> float:
        """Enclosed volume by the divergence theorem, V = (1/3) int x . n dS."""
        positions, vector_weights = quad9.surface_quadrature(self.element_nodes(), order)
        return float(np.einsum("eqi,eqi->", positions, vector_weights) / 3.0)

    def centroid(self, order: int = 4) -> np.ndarray:
        """Centre of volume, x_c = (1/2V) int ``|x|^2`` n dS (divergence theorem on x ``|x|^2`` / 2... per axis)."""
        positions, vector_weights = quad9.surface_quadrature(self.element_nodes(), order)
        # int_V x_i dV = (1/2) int_S x_i^2 n_i dS (no sum over i)
        moments = 0.5 * np.einsum("eqi,eqi->i", positions**2, vector_weights)
        return moments / self.volume(order)

    def equivalent_radius(self) -> float:
        """Radius of the sphere of the same volume (remembered: a Mesh is immutable)."""
        if getattr(self, "_equivalent_radius", None) is None:
            object.__setattr__(self, "_equivalent_radius", float((3.0 * self.volume() / (4.0 * np.pi)) ** (1.0 / 3.0)))
        return self._equivalent_radius

    def surface_samples(self) -> np.ndarray:
        """placement.surface_samples of the mesh, in its own coordinates (remembered, read-only)."""
        if getattr(self, "_surface_samples", None) is None:
            samples = surface_samples(self.element_nodes())
            samples.setflags(write=False)
            object.__setattr__(self, "_surface_samples", samples)
        return self._surface_samples

    def encloses_origin(self) -> bool:
        """Whether the reference point (the origin of the mesh coordinates) lies inside the
        surface, by its winding number; remembered, since a rigid motion of the body moves its
        reference point with it."""
        if getattr(self, "_encloses_origin", None) is None:
            object.__setattr__(self, "_encloses_origin", bool(winding_number(np.zeros((1, 3)), self.element_nodes())[0] >= 0.5))
        return self._encloses_origin

    def size(self) -> float:
        """Largest distance of a node from the reference point (the origin); remembered (each
        Body checks its position against it)."""
        if getattr(self, "_size", None) is None:
            object.__setattr__(self, "_size", float(np.linalg.norm(self.nodes, axis=1).max()))
        return self._size

    def check(self) -> "Mesh":
        """Raise MeshError unless the surface is closed, consistently oriented and outward.
        Returns the mesh; the result is remembered (a Mesh is immutable)."""
        if getattr(self, "_checked", False):
            return self
        edges = self.elements[:, [0, 4, 1, 1, 5, 2, 2, 6, 3, 3, 7, 0]].reshape(-1, 3)  # (corner, mid, corner)
        n = len(self.nodes)
        forward = edges[:, 0] * n + edges[:, 2]  # each directed edge as one integer
        order = np.argsort(forward)
        if np.any(np.diff(forward[order]) == 0):
            raise MeshError("an edge is used twice in the same direction: inconsistent orientation")
        # every edge's reverse must be an edge of another element, with the same mid node
        backward = edges[:, 2] * n + edges[:, 0]
        at = order[np.minimum(np.searchsorted(forward, backward, sorter=order), len(order) - 1)]
        unmatched = (forward[at] != backward) | (edges[at, 1] != edges[:, 1])
        if unmatched.any():
            a, _, b = edges[np.argmax(unmatched)]
            raise MeshError(
                f"edge {a}-{b} is not shared (with its mid node) by exactly two oppositely"
                " oriented elements: the surface is open or its elements disagree"
            )
        if np.any(self.element_areas() <= 0.0):
            raise MeshError("an element has zero area")
        if self.volume() <= 0.0:
            raise MeshError("enclosed volume is not positive: the normals point inwards")
        object.__setattr__(self, "_checked", True)
        return self

    def at_subdivisions(self, k: int) -> "Mesh":
        """The same library surface with k subdivisions (this mesh itself at its own k)."""
        if k == self.subdivisions:
            return self
        if self.recipe is None:
            raise MeshError("this mesh was not built by a library generator (sphere, spheroid, adherent_cell),"
                            " so it cannot be rebuilt at another number of subdivisions")
        return self.recipe(k)

    def transformed(self, rotation: np.ndarray | None = None, scale=1.0) -> "Mesh":
        """Mesh with nodes x -> rotation @ (scale * x); scale may be a number or a 3-vector."""
        nodes = self.nodes * np.asarray(scale, dtype=float)
        if rotation is not None:
            nodes = nodes @ np.asarray(rotation, dtype=float).T
        return Mesh(nodes, self.elements)


# Cube faces: outward axis n and in-face axes (a, b) with a x b = n, so elements are outward.
_CUBE_FACES = [
    ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
    ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
    ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
]


def _positive_number(name, value):
    if not np.isscalar(value) or not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return float(value)


def _subdivisions(value):
    if int(value) != value or value < 1:
        raise ValueError(f"subdivisions must be a positive integer, got {value!r}")
    return int(value)


def sphere(radius: float, subdivisions: int = 4, projection: str = "equiangular", pole_grading: float = 1.0) -> Mesh:
    """Cube-projected sphere (thesis ch. 2.3, fig. 2.4a): 6 k^2 QUAD9 elements.

    Each cube face is split into k x k elements whose 9 nodes are projected radially onto the
    sphere; k = 4 gives the seed's 96 elements. ``projection="equiangular"`` spaces the nodes
    evenly in angle (u -> tan(pi u / 4)), which makes the elements more uniform than the plain
    ``"gnomonic"`` projection of an evenly split cube.

    ``pole_grading`` g > 1 crowds the elements towards the south pole (-z, where a cell meets
    the wall): the nodes' stereographic coordinates from the north pole are divided by g, a
    conformal map (the elements keep their shapes), so the elements at the south pole are g
    times smaller and those at the north pole g times larger, with the count unchanged and the
    mesh conforming. It resolves a contact patch narrower than the uniform elements (a Hertz
    patch of 0.3-1 um on a 5 um cell) at no extra unknowns.

    Examples
    --------
    >>> import warpbem as wb
    >>> wb.mesh.sphere(radius=5e-6, subdivisions=4).n_elements   # the seed's mesh
    96
    >>> graded = wb.mesh.sphere(5e-6, subdivisions=4, pole_grading=3.0)
    >>> print(f"{graded.nodes[:, 2].min():.3g} m")   # still a sphere of 5 um, finer at its south pole
    -5e-06 m
    """
    radius = _positive_number("radius", radius)
    k = _subdivisions(subdivisions)
    if projection not in ("equiangular", "gnomonic"):
        raise ValueError(f"projection must be 'equiangular' or 'gnomonic', got {projection!r}")
    if isinstance(pole_grading, bool) or not (np.isfinite(pole_grading) and 1.0 <= pole_grading <= 100.0):
        raise ValueError(f"pole_grading must be a number from 1 to 100, got {pole_grading!r}")
    grid = np.linspace(-1.0, 1.0, 2 * k + 1)
    if projection == "equiangular":
        grid = np.tan(0.25 * np.pi * grid)
    offsets = quad9.REFERENCE_NODES.astype(int) + 1  # (9, 2): each node's offsets 0..2 in the face grid
    n = 2 * k + 1
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    # element (i, j) of a face: its nodes' rows and columns in the face's n x n grid of points
    on_face = ((2 * i.reshape(-1, 1) + offsets[:, 0]) * n + 2 * j.reshape(-1, 1) + offsets[:, 1])
    points, elements = [], []
    for f, (normal, a, b) in enumerate(_CUBE_FACES):
        normal, a, b = (np.array(v, dtype=float) for v in (normal, a, b))
        u, v = np.meshgrid(grid, grid, indexing="ij")
        cube = normal + u[..., None] * a + v[..., None] * b
        points.append((cube / np.linalg.norm(cube, axis=-1, keepdims=True)).reshape(-1, 3))
        elements.append(f * n * n + on_face)
    points = _graded_towards_south_pole(np.concatenate(points), pole_grading) * radius
    # merge the nodes that adjacent faces share
    _, first, inverse = np.unique(
        np.round(points / radius, 12), axis=0, return_index=True, return_inverse=True
    )
    return Mesh(points[first], np.asarray(inverse).ravel()[np.concatenate(elements)], k,
                partial(sphere, radius, projection=projection, pole_grading=pole_grading))


def _graded_towards_south_pole(points: np.ndarray, grading: float) -> np.ndarray:
    """Unit-sphere points moved by the conformal map zeta -> zeta / grading of their
    stereographic coordinates zeta = (x, y) / (1 - z) (from the north pole, which stays)."""
    if grading == 1.0:
        return points
    north = points[:, 2] > 1.0 - 1e-12
    zeta = points[:, :2] / np.where(north, 1.0, 1.0 - points[:, 2])[:, None] / grading
    r2 = np.sum(zeta**2, axis=1)
    out = np.column_stack([2.0 * zeta / (1.0 + r2)[:, None], (r2 - 1.0) / (r2 + 1.0)])
    out[north] = points[north]
    return out


def spheroid(radius: float, aspect_ratio: float, subdivisions: int = 4) -> Mesh:
    """Spheroid with symmetry axis z: equatorial radius ``radius``, polar radius
    ``aspect_ratio * radius`` (oblate below 1, prolate above; thesis fig. 2.4b).

    Examples
    --------
    An oblate cell, half as tall as it is wide: its volume against (4/3) pi a^2 c.

    >>> import math
    >>> import warpbem as wb
    >>> disc = wb.mesh.spheroid(radius=5e-6, aspect_ratio=0.5, subdivisions=2)
    >>> print(f"{disc.nodes[:, 2].max():.3g} {disc.volume() / (4 / 3 * math.pi * 5e-6**2 * 2.5e-6):.4f}")
    2.5e-06 0.9983
    """
    radius = _positive_number("radius", radius)
    aspect_ratio = _positive_number("aspect_ratio", aspect_ratio)
    scaled = sphere(radius, subdivisions).transformed(scale=(1.0, 1.0, aspect_ratio))
    return Mesh(scaled.nodes, scaled.elements, scaled.subdivisions, partial(spheroid, radius, aspect_ratio))


def save(mesh: Mesh, path) -> None:
    """Write ``mesh`` in the warpbem QUAD9 text format (see the module docstring)."""
    path = Path(path)
    with path.open("w") as f:
        f.write("warpbem-quad9 1\nunits m\n")
        f.write(f"nodes {len(mesh.nodes)}\n")
        np.savetxt(f, mesh.nodes, fmt="%.17g")
        f.write(f"elements {mesh.n_elements}\n")
        np.savetxt(f, mesh.elements, fmt="%d")


def load(path) -> Mesh:
    """Read a mesh written by ``save`` (or by hand in that format) and check it."""
    path = Path(path)
    try:
        lines = [ln.split("#", 1)[0].split() for ln in path.read_text().splitlines()]
    except (OSError, UnicodeDecodeError) as err:
        raise MeshError(f"{path}: cannot read mesh file ({err})") from err
    lines = [ln for ln in lines if ln]
    try:
        if lines[0] != ["warpbem-quad9", "1"] or lines[1] != ["units", "m"]:
            raise MeshError(f"{path}: expected header 'warpbem-quad9 1' and 'units m'")
        n_nodes = int(lines[2][1]) if lines[2][0] == "nodes" else -1
        nodes = np.array(lines[3 : 3 + n_nodes], dtype=float)
        header = lines[3 + n_nodes]
        n_elements = int(header[1]) if header[0] == "elements" else -1
        elements = np.array(lines[4 + n_nodes : 4 + n_nodes + n_elements], dtype=np.int64)
        if n_nodes < 0 or n_elements < 0 or len(lines) != 4 + n_nodes + n_elements:
            raise MeshError(f"{path}: node or element count does not match the file")
    except (IndexError, ValueError) as err:
        if isinstance(err, MeshError):
            raise
        raise MeshError(f"{path}: malformed QUAD9 mesh file ({err})") from err
    try:
        return Mesh(nodes, elements).check()
    except MeshError as err:
        raise MeshError(f"{path}: {err}") from err
