"""Adherent cell shapes (thesis ch. 5.3, fig. 5.1): volume kept, centre heights, clearance,
and the mesh files under scenes/ are what the generator makes."""

from pathlib import Path

import numpy as np
import pytest

from warpbem import mesh
from warpbem.surfaces import shapes

SCENES = Path(__file__).resolve().parents[2] / "scenes"


@pytest.mark.parametrize("shape, height", [("sphere", 5.25e-6), ("dome", 4.5e-6), ("box", 3.25e-6)])
def test_shapes_keep_the_volume_and_sit_just_above_the_wall(shape, height):
    m, position = shapes.adherent_cell(shape)
    m.check()
    np.testing.assert_allclose(position, [0, 0, height])
    # volume of the 5 um cell, to the sphere mesh's own discretisation error
    assert abs(m.volume() / (4 / 3 * np.pi * (5e-6) ** 3) - 1) < 2e-4
    assert np.isclose(m.nodes[:, 2].min() + height, 0.25e-6)  # lowest point 0.25 um above the wall
    on_file = mesh.load(SCENES / f"adherent_{shape}.q9")
    np.testing.assert_allclose(on_file.nodes, m.nodes, rtol=0, atol=1e-18)


def test_deformed_shapes_are_flatter_and_wider():
    widths, flat = {}, {}
    for shape in shapes.SHAPES:
        m, position = shapes.adherent_cell(shape)
        widths[shape] = np.abs(m.nodes[:, 0]).max()
        z = m.nodes[:, 2] - m.nodes[:, 2].min()
        flat[shape] = np.mean(z < 0.1 * 5e-6)  # share of nodes within 0.5 um of the base
    assert widths["sphere"] < widths["dome"] < widths["box"]
    assert flat["sphere"] < flat["dome"] <= flat["box"]
    with pytest.raises(ValueError, match="shape must be one of"):
        shapes.adherent_cell("pancake")
