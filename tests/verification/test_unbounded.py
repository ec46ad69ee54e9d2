"""Unbounded Stokes flow: sphere and oblate spheroid resistances, rigid motion in shear.
Reference values: ../shared/reference/validation.md (Stokes; Oberbeck / Kim & Karrila 1991
ch. 3, closed forms for spheroids)."""

import numpy as np
import pytest

import warpbem as wb

from .conftest import grand_resistance, resistance


@pytest.mark.parametrize("k, tol", [(4, 2e-3), (8, 5e-4)])
def test_sphere_stokes_drag_and_torque(sphere_mesh, k, tol):
    # F = -6 pi mu a U, T = -8 pi mu a^3 Omega (hydrodynamic); the holding load is minus that
    f, _ = resistance(sphere_mesh(k), (0, 0, 0), np.array([0.3, -1.0, 0.5, 0, 0, 0]), wall=False)
    np.testing.assert_allclose(f, 6 * np.pi * np.array([0.3, -1.0, 0.5]), rtol=tol)
    _, t = resistance(sphere_mesh(k), (0, 0, 0), np.array([0, 0, 0, 0.2, 1.0, -0.7]), wall=False)
    np.testing.assert_allclose(t, 8 * np.pi * np.array([0.2, 1.0, -0.7]), rtol=tol)


def test_free_sphere_in_shear_moves_with_the_fluid_exactly(sphere_mesh):
    """A torque- and force-free sphere in unbounded simple shear u = gdot z e_x translates with
    the fluid at its centre and spins at gdot/2 (Jeffery 1922). The translation is the rigid
    part of the ambient flow, which the deflated CDL operator reproduces to GMRES tolerance."""
    body = wb.Body(sphere_mesh(4), position=(1.0, -2.0, 3.0))
    sol = wb.solve_mobility([body], shear_rate=2.0, viscosity=1.0, wall=False, options=wb.SolverOptions(tolerance=1e-12))
    np.testing.assert_allclose(sol.velocity[0], [6.0, 0.0, 0.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.angular_velocity[0], [0.0, 1.0, 0.0], rtol=0, atol=5e-4)


OBLATE_HALF = dict(XA=0.905305, YA=0.792707, XC=0.705020, YC=0.565816)  # c/a = 0.5


@pytest.mark.parametrize("k, tol", [(4, 1e-2), (8, 5e-3)])
def test_oblate_spheroid_resistance(k, tol):
    """Oblate spheroid c/a = 0.5 (validation.md): F = -6 pi mu a (X^A or Y^A) U,
    T = -8 pi mu a^3 (X^C or Y^C) Omega, along / perpendicular to the symmetry axis z.
    The 6x6 grand resistance matrix is also symmetric (Lorentz reciprocity)."""
    r = grand_resistance(wb.mesh.spheroid(1.0, 0.5, subdivisions=k), (0, 0, 0), wall=False)
    expected = np.diag([6 * np.pi * OBLATE_HALF["YA"]] * 2 + [6 * np.pi * OBLATE_HALF["XA"]]
                       + [8 * np.pi * OBLATE_HALF["YC"]] * 2 + [8 * np.pi * OBLATE_HALF["XC"]])
    np.testing.assert_allclose(np.diag(r), np.diag(expected), rtol=tol)
    assert np.abs(r - np.diag(np.diag(r))).max() < 1e-3 * np.abs(r).max()


def test_prolate_spheroid_resistance_closed_forms():
    """Prolate spheroid, semi-axes a (along z) and b = a/2: Kim & Karrila (1991) table 3.4 with
    eccentricity e = sqrt(1 - b^2/a^2) and L = ln((1 + e)/(1 - e)):
        X^A = 8/3 e^3 / (-2e + (1 + e^2) L),      Y^A = 16/3 e^3 / (2e + (3e^2 - 1) L),
        X^C = 4/3 e^3 (1 - e^2) / (2e - (1 - e^2) L),  Y^C = 4/3 e^3 (2 - e^2) / (-2e + (1 + e^2) L),
    F = -6 pi mu a X^A U (axial), T = -8 pi mu a^3 X^C Omega (axial); Y for transverse.
    A shape and values outside validation.md; errors fall as h^2 (k = 4: 7e-3, k = 8: 1.7e-3)."""
    e = np.sqrt(1 - 0.25)
    big_l = np.log((1 + e) / (1 - e))
    xa = 8 / 3 * e**3 / (-2 * e + (1 + e**2) * big_l)
    ya = 16 / 3 * e**3 / (2 * e + (3 * e**2 - 1) * big_l)
    xc = 4 / 3 * e**3 * (1 - e**2) / (2 * e - (1 - e**2) * big_l)
    yc = 4 / 3 * e**3 * (2 - e**2) / (-2 * e + (1 + e**2) * big_l)
    r = grand_resistance(wb.mesh.spheroid(0.5, 2.0, subdivisions=8), (0, 0, 0), wall=False)
    expected = [6 * np.pi * ya, 6 * np.pi * ya, 6 * np.pi * xa, 8 * np.pi * yc, 8 * np.pi * yc, 8 * np.pi * xc]
    np.testing.assert_allclose(np.diag(r), expected, rtol=3e-3)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")  # conservative for co-moving spheres
@pytest.mark.parametrize("half_distance", [1.5, 1.1, 1.02])
def test_two_spheres_along_their_line_of_centres(sphere_mesh, half_distance):
    """Stimson & Jeffery (1926): two equal spheres, centres 2h apart, each pushed with the same
    force along the line of centres, move together at U = F / (6 pi mu a lambda); lambda from
    the exact series (sphere_wall_series.stimson_jeffery_lambda; 0.645 at contact). A two-body
    check with nearly touching bodies (gap 0.04 radius at h = 1.02): measured errors 6.0e-4,
    3.6e-4 and 6.9e-4 (192, 456 and 1488 elements after contact refinement)."""
    from .sphere_wall_series import stimson_jeffery_lambda

    bodies = [wb.Body(sphere_mesh(4), position=(0, 0, 0)), wb.Body(sphere_mesh(4), position=(2 * half_distance, 0, 0))]
    sol = wb.solve_mobility(bodies, wall=False, viscosity=1.0, forces=[[6 * np.pi, 0, 0]] * 2)
    assert abs(6 * np.pi / (6 * np.pi * sol.velocity[0, 0]) / stimson_jeffery_lambda(half_distance) - 1) < 5e-3
    np.testing.assert_allclose(sol.velocity[1], sol.velocity[0], atol=1e-8)
    assert np.abs(sol.velocity[:, 1:]).max() < 1e-8 and np.abs(sol.angular_velocity).max() < 1e-8


@pytest.mark.parametrize("half_distance, tol", [(1.5, 2e-3), (1.1, 0.03)])
def test_two_spheres_squeezing_the_gap(sphere_mesh, half_distance, tol):
    """Two equal spheres pushed towards each other with equal and opposite forces (Maude 1961;
    Brenner 1961): U = F / (6 pi mu a lambda), lambda from the exact series
    (sphere_wall_series.approaching_spheres_lambda). The squeeze flow in the gap is the hard
    case for a density constant per element, as for Brenner's sphere and wall: measured errors
    3e-4 at h = 1.5 and 1.8 % at h = 1.1 (gap 0.2 radius) with the default contact refinement."""
    from .sphere_wall_series import approaching_spheres_lambda

    bodies = [wb.Body(sphere_mesh(4), position=(0, 0, 0)), wb.Body(sphere_mesh(4), position=(2 * half_distance, 0, 0))]
    sol = wb.solve_mobility(bodies, wall=False, viscosity=1.0, forces=[[6 * np.pi, 0, 0], [-6 * np.pi, 0, 0]])
    assert abs(1 / sol.velocity[0, 0] / approaching_spheres_lambda(half_distance) - 1) < tol
    np.testing.assert_allclose(sol.velocity[1], -sol.velocity[0], atol=1e-8)
