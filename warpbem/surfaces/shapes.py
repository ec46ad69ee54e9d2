"""Adherent cell shapes of thesis ch. 5.3 (fig. 5.1): a 5 um cell held against the wall as a
sphere (centre 5.25 um), a moderately deformed "dome" (centre 4.5 um) and a highly deformed
"box" (centre 3.25 um), all of the same volume (4/3) pi a^3 (the thesis conserves volume).

The thesis shows the shapes only in a figure, so this generator fixes a documented family:
each shape is the cube-sphere mesh mapped radially onto the surface

    ((x^2 + y^2) / A^2)^(p/2) + |z / C|^p = 1,

with p = 2 (an ellipsoid) on the upper half and p_bottom below: p_bottom = 2 for the sphere,
4 for the dome (round top, flattened base) and 4 on both halves for the box (a rounded box).
The half-height C = centre height - gap puts the lowest point ``gap`` above the wall (0.25 um:
the cell and wall roughness of thesis ch. 3.1, 175 + 50 nm, plus 25 nm); A follows from the
volume. The reference point is the shape's centre (0, 0, 0) of the mesh, placed at the centre
height.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from functools import partial

from .mesh import Mesh, sphere

SHAPES = {  # centre height (m), exponent above, exponent below
    "sphere": (5.25e-6, 2.0, 2.0),
    "dome": (4.5e-6, 2.0, 4.0),
    "box": (3.25e-6, 4.0, 4.0),
}


def _mapped(unit: Mesh, a: float, c: float, p_top: float, p_bottom: float) -> Mesh:
    d = unit.nodes
    p = np.where(d[:, 2] >= 0, p_top, p_bottom)
    level = (np.hypot(d[:, 0], d[:, 1]) / a) ** p + np.abs(d[:, 2] / c) ** p
    return Mesh(d * level[:, None] ** (-1.0 / p[:, None]), unit.elements)


def adherent_cell(shape: str, radius: float = 5e-6, gap: float = 0.25e-6, subdivisions: int = 4):
    """Mesh (about its centre) and centre position (0, 0, h) of an adherent cell shape."""
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {sorted(SHAPES)}, got {shape!r}")
    height, p_top, p_bottom = SHAPES[shape]
    height *= radius / 5e-6  # the thesis heights are for a 5 um cell
    c = height - gap
    if not 0 < gap < height:
        raise ValueError(f"gap must lie in (0, {height:g}) m for the {shape}, got {gap!r}")
    unit = sphere(1.0, subdivisions)
    target = 4.0 / 3.0 * np.pi * radius**3
    if shape == "sphere":
        return sphere(radius, subdivisions), np.array([0.0, 0.0, radius + gap])
    a = brentq(lambda a: _mapped(unit, a, c, p_top, p_bottom).volume() - target, 0.2 * radius, 5 * radius,
               xtol=1e-15 * radius)
    mapped = _mapped(unit, a, c, p_top, p_bottom)
    # checked as the mesh returned (with its recipe), so a Body of it does not check it again
    mesh = Mesh(mapped.nodes, mapped.elements, unit.subdivisions, partial(adherent_mesh, shape, radius, gap)).check()
    return mesh, np.array([0.0, 0.0, height])


def adherent_mesh(shape: str, radius: float, gap: float, subdivisions: int) -> Mesh:
    """The mesh of ``adherent_cell`` alone: its recipe at another number of subdivisions."""
    return adherent_cell(shape, radius, gap, subdivisions)[0]


def write_meshes(folder, subdivisions: int = 4) -> list:
    """Write adherent_<shape>.q9 for every shape into ``folder`` (the files under scenes/)."""
    from pathlib import Path

    from .mesh import save

    paths = []
    for shape in SHAPES:
        mesh, _ = adherent_cell(shape, subdivisions=subdivisions)
        path = Path(folder) / f"adherent_{shape}.q9"
        save(mesh, path)
        paths.append(path)
    return paths


if __name__ == "__main__":  # python -m warpbem.shapes scenes/
    import sys

    for written in write_meshes(sys.argv[1] if len(sys.argv) > 1 else "."):
        print(written)
