"""The exact series used as references reproduce the published values of validation.md
(Brenner 1961; Goldman, Cox & Brenner 1967a, b) and the far-field limits."""

import numpy as np
import pytest

from . import sphere_wall_series as series

TABLE = {
    1.5: dict(lam=3.205390, Ft=1.595707, Tt=1.65740e-2, Tr=1.110495, U=0.91468, Omega=0.45843),
    3.0: dict(lam=1.569205, Ft=1.227155, Tt=1.02023e-3, Tr=1.011796, U=0.98904, Omega=0.49454),
}


@pytest.mark.parametrize("h", sorted(TABLE))
def test_series_reproduce_published_values(h):
    ref = TABLE[h]
    assert np.isclose(series.brenner_lambda(h), ref["lam"], rtol=1e-6)
    p = series.parallel_resistance(h)
    assert np.isclose(p["Ft"], ref["Ft"], rtol=1e-6)
    assert np.isclose(p["Tr"], ref["Tr"], rtol=1e-6)
    assert np.isclose(p["Tt"], ref["Tt"], rtol=1e-5)
    assert np.isclose(p["Fr"], 4 / 3 * p["Tt"], rtol=1e-10)  # reciprocity
    f = series.free_sphere_in_shear(h)
    assert np.isclose(f["U_over_gdot_h"], ref["U"], rtol=2e-5)
    assert np.isclose(f["Omega_over_gdot"], ref["Omega"], rtol=3e-5)


def test_independent_solvers_agree_and_far_field_limits():
    for h in (1.05, 1.3, 4.0):
        a = series.parallel_resistance(h, method="oneill")
        b = series.parallel_resistance(h, method="general")
        for key in ("Ft", "Tr", "Tt"):
            assert np.isclose(a[key], b[key], rtol=1e-10)
    far = series.free_sphere_in_shear(1e3)
    assert np.isclose(far["U_over_gdot_h"], 1.0, atol=1e-6) and np.isclose(far["Omega_over_gdot"], 0.5, atol=1e-6)
    assert np.isclose(series.brenner_lambda(1e3), 1 + 9 / 8e3, rtol=1e-5)  # Lorentz: 1 + 9a/(8h)
    with pytest.raises(ValueError):
        series.brenner_lambda(1.0)


def test_two_sphere_series_limits():
    # Stimson & Jeffery (1926): touching spheres falling together, lambda = 0.645 (their table)
    assert abs(series.stimson_jeffery_lambda(1.0 + 1e-6) - 0.645) < 1e-3
    # far apart: each sphere moves in the other's Stokeslet, lambda = 1 - 3a/(4h) + O(a/h)^2
    assert abs(series.stimson_jeffery_lambda(100.0) - (1 - 3 / 400)) < 1e-4
    assert abs(series.approaching_spheres_lambda(100.0) - (1 + 3 / 400)) < 1e-4
    # lubrication: approaching spheres, gap eps = 2(h - a): lambda -> a / (2 eps)
    h = 1.0 + 1e-4
    assert abs(series.approaching_spheres_lambda(h) * 2 * (2 * (h - 1)) - 1) < 0.02
