"""Adherent cell shapes (thesis ch. 5.3, fig. 5.1): volume kept, centre heights, clearance,
and the mesh files under scenes/ are what the generator makes."""

from pathlib import Path

import numpy as np
import pytest

from warpbem import mesh
from warpbem.surfaces import shapes

SCENES = Path(__file__).resolve().parents[2] / "scenes"


def half_volume(a, c, p):
    """Volume of the half body ((x^2 + y^2)/a^2)^(p/2) + (z/c)^p <= 1, 0 <= z <= c: the disc of
    radius a (1 - u^p)^(1/p) at height z = c u integrates to pi a^2 c G(1+1/p) G(1+2/p) / G(1+3/p)
    (G the gamma function; p = 2 gives the half ellipsoid 2/3 pi a^2 c)."""
    from scipy.special import gamma

    return np.pi * a**2 * c * gamma(1 + 1 / p) * gamma(1 + 2 / p) / gamma(1 + 3 / p)


@pytest.mark.parametrize("shape, height, volume_error", [("sphere", 5.25e-6, 1e-12), ("dome", 4.5e-6, 5e-4),
                                                         ("box", 3.25e-6, 3e-3)])
def test_shapes_keep_the_volume_and_sit_just_above_the_wall(shape, height, volume_error):
    """The volume of the surface the mesh is drawn on, from the shape's own half-widths read
    off the mesh nodes (which lie on it) and the closed form of ``half_volume``, not from the
    mesh quadrature the generator fitted: 4/3 pi (5 um)^3 to 0 (sphere), 3.4e-4 (dome) and
    2.1e-3 (box; the biquadratic elements cut its flatter rims short, so the fit widens it)."""
    m, position = shapes.adherent_cell(shape)
    m.check()
    np.testing.assert_allclose(position, [0, 0, height])
    _, p_top, p_bottom = shapes.SHAPES[shape]
    on_equator = np.abs(m.nodes[:, 2]) < 1e-15
    a = np.hypot(m.nodes[on_equator, 0], m.nodes[on_equator, 1]).max()
    exact = half_volume(a, m.nodes[:, 2].max(), p_top) + half_volume(a, -m.nodes[:, 2].min(), p_bottom)
    assert abs(exact / (4 / 3 * np.pi * (5e-6) ** 3) - 1) < volume_error
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
