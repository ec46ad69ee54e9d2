"""The higher-order density (density_order p = 2: bilinear Lagrange on 2 x 2 Gauss points per
element, discontinuous between elements; kernels/assembly.py, hydro/geometry.py)."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.hydro.geometry import SurfaceGeometry, density_basis, density_points
from warpbem.hydro.operators import BoundaryOperator, discrete_form


@pytest.mark.parametrize("p", [1, 2, 3])
def test_density_basis_is_lagrange_on_its_points_and_sums_to_one(p):
    s, t = density_points(p)
    assert len(s) == p * p and np.all(np.abs(s) < 1) and np.all(np.abs(t) < 1)  # interior points
    np.testing.assert_allclose(density_basis(p, s, t), np.eye(p * p), atol=1e-14)
    u = np.random.default_rng(0).uniform(-1, 1, size=(2, 50))
    np.testing.assert_allclose(density_basis(p, u[0], u[1]).sum(axis=1), 1.0, atol=1e-13)


def _operator(k, p, wall, mode="dense"):
    body = wb.Body(wb.mesh.sphere(1.0, k), position=(0, 0, 1.5) if wall else (0, 0, 0))
    geometry = SurfaceGeometry.from_bodies([body], 2, 1.0, wall, 0.0, density_order=p)
    return geometry, discrete_form(BoundaryOperator(geometry, wall), mode)


def _rotation_residual(k, p, wall):
    """max over axes of |(1/2 + D) (e x rho)| / |e x rho| at the collocation points."""
    geometry, operator = _operator(k, p, wall)
    rho = geometry.collocation - geometry.centres[0]
    fields = [np.cross(np.eye(3)[axis], rho).ravel() for axis in range(3)]
    return max(np.linalg.norm(operator.matvec(f)) / np.linalg.norm(f) for f in fields)


@pytest.mark.parametrize("wall", [False, True])
def test_bilinear_density_annihilates_rigid_rotations_at_fourth_order(wall):
    """(1/2 + D^PV) annihilates every rigid field (Kim & Karrila 1991 ch. 17; thesis eq. 2.7);
    translations exactly by the identity that gives the self blocks, rotations only as far as
    the discretisation resolves them: the constant density at second order (5.2e-3 on k = 4),
    the bilinear one at about fourth (measured 5.2e-4 on k = 2, 4.1e-5 on k = 4). The rotation
    residual exercises every integral of the p = 2 operator: far, adaptive and the Duffy
    rule of each collocation point's own element."""
    constant, coarse, fine = _rotation_residual(4, 1, wall), _rotation_residual(2, 2, wall), _rotation_residual(4, 2, wall)
    assert fine < coarse / 10  # order above 3 in the element size
    assert fine < constant / 50
    assert _rotation_residual(2, 3, wall) < coarse / 5  # biquadratic (p = 3): 4.6e-5 on k = 2


def test_bilinear_density_matrix_free_product_equals_the_assembled_one():
    geometry, dense = _operator(2, 2, True)
    _, free = _operator(2, 2, True, mode="matrix_free")
    x = np.random.default_rng(3).normal(size=3 * geometry.n_points)
    np.testing.assert_allclose(free.matvec(x), dense.matvec(x), rtol=0, atol=1e-12 * np.abs(dense.matvec(x)).max())


def test_density_order_is_checked():
    with pytest.raises(ValueError, match="density_order"):
        wb.MobilitySolver(options=wb.SolverOptions(density_order=4))


def test_bilinear_density_keeps_a_fixed_cells_blocks_and_matches_matrix_free_with_two_bodies():
    """The solver's reuse of a fixed body's blocks (points, not elements, index the kept blocks
    for p = 2) gives the fresh solve's motion to the GMRES tolerance, and the matrix-free
    operator of two bodies gives the assembled one's."""
    import warnings

    sphere = wb.mesh.sphere(1.0, 3)
    fixed = wb.Body(sphere, position=(0, 0, 1.5), fixed=True)
    solver = wb.MobilitySolver(1.0, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        for x in (-3.0, -2.9):
            bodies = [wb.Body(sphere, position=(x, 0.3, 1.6)), fixed]
            kept = solver.solve(bodies)
            fresh = wb.solve_mobility(bodies, 1.0, 1.0)
            np.testing.assert_allclose(kept.velocity, fresh.velocity, rtol=0, atol=1e-7 * np.abs(fresh.velocity).max())
            np.testing.assert_allclose(kept.force, fresh.force, rtol=0, atol=1e-7 * np.abs(fresh.force).max())
        assert kept.reused_bodies.tolist() == [False, True]
        free = wb.solve_mobility(bodies, 1.0, 1.0, options=wb.SolverOptions(operator="matrix_free"))
    np.testing.assert_allclose(free.velocity, fresh.velocity, rtol=0, atol=1e-9 * np.abs(fresh.velocity).max())
