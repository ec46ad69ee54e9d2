"""QUAD9 mesh generators, file format and checks."""

import numpy as np
import pytest

import warpbem as wb
from warpbem import mesh
from warpbem.surfaces.quad9 import CENTRE_NODE


def test_seed_sphere_has_96_elements_and_is_closed():
    m = mesh.sphere(5e-6, subdivisions=4).check()
    assert m.n_elements == 96
    assert m.elements.shape == (96, 9)
    np.testing.assert_allclose(np.linalg.norm(m.nodes, axis=1), 5e-6, rtol=1e-14)
    np.testing.assert_allclose(m.centroid(), 0.0, atol=1e-20)


@pytest.mark.parametrize("projection", ["equiangular", "gnomonic"])
def test_sphere_area_and_volume_converge_at_fourth_order(projection):
    # exact values 4 pi a^2 and 4/3 pi a^3; biquadratic geometry gives O(h^4) errors
    ks = [2, 4, 8]
    area_err = [abs(mesh.sphere(1.0, k, projection).area() / (4 * np.pi) - 1) for k in ks]
    vol_err = [abs(mesh.sphere(1.0, k, projection).volume() / (4 * np.pi / 3) - 1) for k in ks]
    for err in (area_err, vol_err):
        orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
        assert np.all(orders > 3.5), orders
    assert vol_err[-1] < 5e-5


@pytest.mark.parametrize("aspect", [0.5, 2.0])
def test_spheroid_volume_and_area(aspect):
    m = mesh.spheroid(1.0, aspect, subdivisions=8).check()
    assert np.isclose(m.volume(), 4 * np.pi / 3 * aspect, rtol=1e-4)
    # exact surface area of a spheroid with equatorial radius 1 and polar radius c
    c = aspect
    if c < 1:
        e = np.sqrt(1 - c**2)
        area = 2 * np.pi * (1 + c**2 / e * np.arctanh(e))
    else:
        e = np.sqrt(1 - 1 / c**2)
        area = 2 * np.pi * (1 + c / e * np.arcsin(e))
    assert np.isclose(m.area(), area, rtol=1e-4)
    assert np.isclose(np.abs(m.nodes[:, 2]).max(), c)


def test_save_load_roundtrip(tmp_path):
    m = mesh.spheroid(3e-6, 0.7, subdivisions=3)
    path = tmp_path / "cell.q9"
    mesh.save(m, path)
    back = mesh.load(path)
    np.testing.assert_array_equal(back.elements, m.elements)
    np.testing.assert_array_equal(back.nodes, m.nodes)


def test_load_rejects_malformed_and_inconsistent_files(tmp_path):
    bad = tmp_path / "bad.q9"
    bad.write_text("warpbem-quad9 1\nunits m\nnodes 2\n0 0 0\n")
    with pytest.raises(mesh.MeshError, match="bad.q9"):
        mesh.load(bad)
    with pytest.raises(mesh.MeshError, match="cannot read"):
        mesh.load(tmp_path / "missing.q9")
    m = mesh.sphere(1.0, 2)
    flipped = mesh.Mesh(m.nodes, np.concatenate([m.elements[:1, [1, 0, 3, 2, 4, 7, 6, 5, 8]], m.elements[1:]]))
    path = tmp_path / "flipped.q9"
    mesh.save(flipped, path)
    with pytest.raises(mesh.MeshError, match="orient|shared"):
        mesh.load(path)


def test_check_detects_open_and_inward_surfaces():
    m = mesh.sphere(1.0, 2)
    with pytest.raises(mesh.MeshError, match="open|shared"):
        mesh.Mesh(m.nodes, m.elements[:-1]).check()
    inward = mesh.Mesh(m.nodes, m.elements[:, [0, 3, 2, 1, 7, 6, 5, 4, 8]])
    with pytest.raises(mesh.MeshError, match="inwards"):
        inward.check()


@pytest.mark.parametrize("kwargs, message", [
    (dict(radius=-1.0), "radius"), (dict(radius=np.nan), "radius"),
    (dict(radius=1.0, subdivisions=0), "subdivisions"), (dict(radius=1.0, subdivisions=2.5), "subdivisions"),
])
def test_generators_reject_bad_sizes(kwargs, message):
    with pytest.raises(ValueError, match=message):
        mesh.sphere(**kwargs)
    with pytest.raises(ValueError, match="aspect_ratio"):
        mesh.spheroid(1.0, 0.0)


def test_a_pole_graded_sphere_crowds_its_elements_at_the_south_pole_and_stays_a_closed_sphere():
    """Stereographic scaling by 1/g (a conformal map): the nodes stay on the sphere, the mesh
    conforms (check passes: every edge shared by two elements), the area still converges, and
    the element at the south pole is ~g times smaller than at the north pole, g^2 in area."""
    uniform, graded = mesh.sphere(1.0, 8), mesh.sphere(1.0, 8, pole_grading=4.0)
    assert graded.n_elements == uniform.n_elements
    np.testing.assert_allclose(np.linalg.norm(graded.nodes, axis=1), 1.0, rtol=1e-12)
    graded.check()
    assert graded.area() == pytest.approx(4 * np.pi, rel=2e-3)
    centres, areas = graded.element_nodes()[:, CENTRE_NODE], graded.element_areas()
    south, north = areas[np.argmin(centres[:, 2])], areas[np.argmax(centres[:, 2])]
    assert 4.0**2 < north / south < 4.0**4  # the pole elements: 1/g and g times the uniform size
    assert areas[np.argmin(centres[:, 2])] == pytest.approx(
        uniform.element_areas()[np.argmin(uniform.element_nodes()[:, 8, 2])] / 16.0, rel=0.05)
    for bad in (0.5, np.nan, True):
        with pytest.raises(ValueError, match="pole_grading"):
            mesh.sphere(1.0, 4, pole_grading=bad)


def test_mesh_rejects_bad_arrays():
    with pytest.raises(mesh.MeshError, match="shape"):
        mesh.Mesh(np.zeros((4, 2)), np.zeros((1, 9), int))
    with pytest.raises(mesh.MeshError, match="indices"):
        mesh.Mesh(np.zeros((4, 3)), np.full((1, 9), 7))
    with pytest.raises(mesh.MeshError, match="non-finite"):
        mesh.Mesh(np.full((9, 3), np.inf), np.arange(9)[None])


def test_contact_refinement_scales_with_the_mesh_so_a_finer_mesh_resolves_the_gap_finer():
    """refinement.refine_near_contact: on the k = 4 sphere the rule is the plain ratio (element
    radius <= gap / ratio next to the wall); on k = 8 the elements there end twice as fine, so
    the gap is resolved as the body is and the error near contact keeps falling with the mesh."""
    from warpbem.surfaces.refinement import element_radius, refine_near_contact

    finest = {}
    for k in (4, 8):
        nodes = wb.mesh.sphere(1.0, k).element_nodes() + np.array([0.0, 0.0, 1.1])
        (refined,), unresolved, _ = refine_near_contact([nodes], wall=True, ratio=3.0)
        gap = refined[:, :, 2].min(axis=1)
        bottom = gap < 0.101
        finest[k] = element_radius(refined[bottom]).max()
        assert not unresolved
    assert finest[4] <= 0.1 / 3 * 1.0001 and finest[4] > 0.1 / 3 / 2.2  # one split short of gap / 3 is too coarse
    assert finest[8] == pytest.approx(finest[4] / 2, rel=0.15)
