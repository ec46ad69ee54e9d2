"""The lubrication forces of thesis eq. 3.4-3.8 (``warpbem/forces/lubrication.py``)."""

import sys
from pathlib import Path

import numpy as np
import pytest

from warpbem.forces.lubrication import shear_force, squeeze_force

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verification"))
import sphere_wall_series as series  # noqa: E402

A, MU = 5e-6, 1.2e-3


@pytest.mark.parametrize("eps_over_a, tolerance", [(1e-3, 1e-2), (1e-4, 1.5e-3)])
def test_the_squeeze_force_is_the_exact_one_as_the_gap_closes(eps_over_a, tolerance):
    """Eq. 3.7 against the exact squeeze of two equal spheres (Maude 1961 / Brenner 1961,
    ``approaching_spheres_lambda``: F = 6 pi mu a U lambda each, relative speed 2U): within 1 %
    at eps = 1e-3 a (0.89 % measured) and 0.15 % at 1e-4 a (0.11 %), the leading term of the
    exact force, resisting the approach along the line of centres."""
    eps, u = eps_over_a * A, 1e-4
    line = np.array([0.6, 0.0, 0.8])
    force = squeeze_force(A, MU, eps, 2 * u * line, line)
    exact = 6 * np.pi * MU * A * u * series.approaching_spheres_lambda(1 + eps_over_a / 2)
    assert np.linalg.norm(force) == pytest.approx(exact, rel=tolerance)
    np.testing.assert_allclose(force / np.linalg.norm(force), -line, atol=1e-12)


def test_the_shear_force_resists_the_sliding_only():
    """Eq. 3.8: pi mu a ln(a / eps) times the sliding part of the relative velocity, against it;
    the approach along l adds nothing, also for a vertical line of centres, where eq. 3.5-3.6
    are undefined (p p + q q = I - l l)."""
    eps = 1e-2 * A
    for line in ([0.0, 0.0, 1.0], [1.0, 2.0, 2.0]):
        l = np.asarray(line) / np.linalg.norm(line)
        sliding = np.cross(l, [0.3, -0.5, 0.1])
        force = shear_force(A, MU, eps, 1e-4 * (sliding + 2.0 * l), l)
        np.testing.assert_allclose(force, -np.pi * MU * A * np.log(100.0) * 1e-4 * sliding, rtol=1e-12, atol=1e-30)


@pytest.mark.parametrize("separation, message", [(0.0, "separation must be positive"),
                                                 (6e-6, "a separation below the radius")])
def test_lubrication_refuses_what_it_does_not_model(separation, message):
    with pytest.raises(ValueError, match=message):
        squeeze_force(A, MU, separation, [1e-4, 0, 0], [1, 0, 0])
