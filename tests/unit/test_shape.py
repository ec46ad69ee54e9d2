"""Deformed surfaces and shape measures (warpbem/elastic/shape.py)."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.elastic.shape import deformed, nodal_displacement, shear_plane_deformation
from warpbem.surfaces.quad9 import CENTRE_NODE

A = 5e-6


def test_the_shape_measure_of_a_stretched_sphere_is_exact():
    """A sphere stretched by 1.1 and 0.9 along axes turned 30 degrees about y in the x-z plane is
    an ellipsoid with L / a = 1.1, B / a = 0.9: D = 0.1, inclination pi / 6."""
    turn = np.radians(30.0)
    rotation = np.array([[np.cos(turn), 0, -np.sin(turn)], [0, 1, 0], [np.sin(turn), 0, np.cos(turn)]])
    stretch = rotation @ np.diag([1.1, 1.0, 0.9]) @ rotation.T
    d, angle = shear_plane_deformation(wb.mesh.sphere(A, 4).nodes @ stretch.T)
    assert d == pytest.approx(0.1, abs=1e-12) and angle == pytest.approx(np.pi / 6, abs=1e-12)


@pytest.mark.parametrize("k", [2, 4])
def test_nodes_take_a_linear_displacement_exactly(k):
    """Element-centre values of u = eps x give u at every node (the linear fit over the element
    ring), corner, edge and centre nodes alike; the deformed mesh moves by it."""
    mesh = wb.mesh.sphere(A, k)
    eps = np.array([[1e-3, 0.0, 2e-3], [0.0, -1e-3, 0.0], [2e-3, 0.0, 5e-4]])
    u = nodal_displacement(mesh, mesh.element_nodes()[:, CENTRE_NODE] @ eps.T)
    np.testing.assert_allclose(u, mesh.nodes @ eps.T, rtol=0, atol=1e-12 * A)
    moved = deformed(mesh, mesh.element_nodes()[:, CENTRE_NODE] @ eps.T)
    np.testing.assert_allclose(moved.nodes, mesh.nodes @ (np.eye(3) + eps).T, rtol=0, atol=1e-12 * A)
    with pytest.raises(ValueError, match="element_displacement must have shape"):
        nodal_displacement(mesh, np.zeros((3, 3)))


def test_a_concentrated_load_is_balanced_by_a_smooth_traction_and_a_balanced_one_is_left_alone():
    """elastic/deformable.py ``balanced``: after it the traction has no resultant force or moment
    (to 1e-12 of the load), the added traction is a + b x (x - c); a traction already in
    equilibrium (a uniform pressure) comes back unchanged."""
    from warpbem.elastic.deformable import balanced

    mesh = wb.mesh.sphere(5e-6, 4)
    centres, areas = mesh.element_nodes()[:, CENTRE_NODE], mesh.element_areas()
    load = np.zeros((mesh.n_elements, 3))
    bottom = np.argmin(centres[:, 2])
    load[bottom] = np.array([1e-12, 0.0, 3e-10]) / areas[bottom]  # 0.3 nN up, 1 pN along x, off-centre
    out = balanced(mesh, load)
    force, moment = areas @ out, areas @ np.cross(centres, out)
    assert np.abs(force).max() < 1e-12 * 3e-10 and np.abs(moment).max() < 1e-12 * 3e-10 * 5e-6
    pressure = -100.0 * centres / np.linalg.norm(centres, axis=1, keepdims=True)
    np.testing.assert_allclose(balanced(mesh, pressure), pressure, atol=1e-6 * 100.0)
