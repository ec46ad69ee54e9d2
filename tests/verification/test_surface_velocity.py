"""A body whose surface moves on top of its rigid motion (``Body.surface_velocity``, the slip of
the mobility solve): the deforming cells' surface motion (warpbem/elastic/deformable.py).

Exact check: in the simple shear u = gdot z e_x, with or without the no-slip wall at z = 0
(the flow satisfies it), a body whose surface moves with the ambient flow leaves it undisturbed.
Its surface velocity is then u itself, so the rigid motion the solver returns is the rigid part
of u on the surface: U = u at the reference point and, for an oblate spheroid (semi-axes a, a,
c; symmetry axis z) in the shear plane x-z, Omega_y = gdot I_zz / (I_xx + I_zz), I_jk = int
r_j r_k dA, by the area-weighted least squares of the rigid rotation about y (the vorticity's
gdot / 2 plus the part of the strain E.r that looks like a rotation on a non-sphere). A rigid
spheroid turns at its Jeffery rate instead.
"""

import numpy as np
import pytest

import warpbem as wb
from warpbem.surfaces.body import Body
from warpbem.surfaces.quad9 import CENTRE_NODE

A, C, H, SHEAR = 5e-6, 2.5e-6, 7.5e-6, 100.0


def spheroid_moments():
    """(I_xx, I_zz) of the spheroid surface, by the trapezoidal rule over the polar angle."""
    t = np.linspace(0.0, np.pi, 20001)
    area = 2 * np.pi * A * np.sin(t) * np.sqrt((A * np.cos(t)) ** 2 + (C * np.sin(t)) ** 2)
    return (np.trapezoid(0.5 * (A * np.sin(t)) ** 2 * area, t), np.trapezoid((C * np.cos(t)) ** 2 * area, t))


@pytest.mark.parametrize("wall, height", [(False, 0.0), (True, H)])
def test_a_surface_moving_with_the_shear_flow_leaves_it_undisturbed(wall, height):
    """k = 4 (96 elements): U = gdot h e_x to 1e-9 of gdot a, Omega_y within 1.5 % of gdot
    I_zz / (I_xx + I_zz) (-0.82 % measured; -0.20 % at k = 8: the element-constant slip and
    collocation moments, second order), where the rigid spheroid turns 20 % slower."""
    mesh = wb.mesh.spheroid(A, C / A, 4)
    centres = mesh.nodes[mesh.elements[:, CENTRE_NODE]] + [0.0, 0.0, height]  # the collocation points
    slip = np.zeros_like(centres)
    slip[:, 0] = SHEAR * centres[:, 2]
    moving = wb.solve_mobility([Body(mesh, position=(0, 0, height), surface_velocity=slip)], SHEAR, 1e-3,
                               wall=wall, options=wb.SolverOptions(density_order=1))
    rigid = wb.solve_mobility([Body(mesh, position=(0, 0, height))], SHEAR, 1e-3, wall=wall, options=wb.SolverOptions(density_order=1))
    ixx, izz = spheroid_moments()
    np.testing.assert_allclose(moving.velocity[0], [SHEAR * height, 0, 0], atol=1e-9 * SHEAR * A)
    assert moving.angular_velocity[0, 1] == pytest.approx(SHEAR * izz / (ixx + izz), rel=1.5e-2)
    assert rigid.angular_velocity[0, 1] < 0.85 * moving.angular_velocity[0, 1]


def test_only_the_non_rigid_part_of_a_surface_velocity_counts():
    """A rigid field given as surface velocity (a translation and a turn) changes nothing (3a
    above the wall, where no element is refined: a refined element takes its parent's value,
    which for a rotation is not rigid); a surface velocity of the wrong shape or on a fixed
    body is refused by name."""
    mesh = wb.mesh.sphere(A, 2)
    centres = mesh.nodes[mesh.elements[:, CENTRE_NODE]]
    rigid_field = np.array([1e-6, 2e-6, -1e-6]) + np.cross([0.0, 3.0, 1.0], centres)
    base = wb.solve_mobility([Body(mesh, position=(0, 0, 3 * A))], SHEAR, 1e-3, options=wb.SolverOptions(density_order=1))
    moved = wb.solve_mobility([Body(mesh, position=(0, 0, 3 * A), surface_velocity=rigid_field)], SHEAR, 1e-3,
                              options=wb.SolverOptions(density_order=1))
    with pytest.raises(ValueError, match="density_order=1"):
        wb.solve_mobility([Body(mesh, position=(0, 0, 3 * A), surface_velocity=rigid_field)], SHEAR, 1e-3)
    np.testing.assert_allclose(moved.velocity, base.velocity, atol=1e-9 * SHEAR * A)
    np.testing.assert_allclose(moved.angular_velocity, base.angular_velocity, atol=1e-9 * SHEAR)
    with pytest.raises(ValueError, match="surface_velocity must be finite, one 3-vector per element"):
        Body(mesh, surface_velocity=rigid_field[:-1])
    with pytest.raises(ValueError, match="a surface_velocity is for free bodies"):
        Body(mesh, fixed=True, surface_velocity=rigid_field)
