"""Electrostatic repulsion (thesis eq. 3.1) and the exact gaps it is evaluated at."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.surfaces import quad9
from warpbem.surfaces.gaps import WALL, GapFinder
from warpbem.surfaces.placement import signed_distance
from warpbem.dynamics.implicit import DenseResponse, ImplicitSystem
from warpbem.dynamics.model import Model
from warpbem.forces.repulsion import Repulsion


def test_force_law_is_thesis_eq_3_1_and_the_gradient_of_its_potential():
    """F = F0 tau exp(-tau eps) / (1 - exp(-tau eps)) (thesis eq. 3.1, tau = 2000 /um) with F0
    in pN um read as J (1e6 pN um = 1e-12 J); F = -dU/d eps for U = -F0 ln(1 - exp(-tau eps))."""
    rep = Repulsion()
    assert rep.inverse_length == 2000 / 1e-6 and rep.coefficient == 1e6 * 1e-12 * 1e-6
    eps = np.array([1e-10, 1e-9, 5e-9, 1e-8, 2e-8])
    literal = rep.coefficient * rep.inverse_length * np.exp(-rep.inverse_length * eps) / (
        1 - np.exp(-rep.inverse_length * eps))
    np.testing.assert_allclose(rep.force(eps), literal, rtol=1e-12)
    h = 1e-4 * eps
    np.testing.assert_allclose(-(rep.potential(eps + h) - rep.potential(eps - h)) / (2 * h), literal, rtol=1e-5)
    np.testing.assert_allclose((rep.force(eps + h) - rep.force(eps - h)) / (2 * h), rep.slope(eps), rtol=1e-5)
    # close in, the law tends to F0 / eps; the balance separation inverts it
    assert rep.force(1e-13) == pytest.approx(rep.coefficient / 1e-13, rel=1e-3)
    for load in (1e-13, 1e-11, 1e-9):
        assert rep.force(rep.balance_separation(load)) == pytest.approx(load, rel=1e-10)
    assert rep.force(rep.reach) == pytest.approx(1e-18, rel=1e-6)
    # roughness: cell 175 nm, wall 50 nm (thesis ch. 3.1)
    assert rep.separation(400e-9, True) == pytest.approx(175e-9)
    assert rep.separation(400e-9, False) == pytest.approx(50e-9)


def test_repulsion_rejects_bad_parameters():
    with pytest.raises(ValueError, match="coefficient"):
        Repulsion(coefficient=-1.0)
    with pytest.raises(ValueError, match="wall_roughness"):
        Repulsion(wall_roughness=float("nan"))
    energy, force, stiffness = Repulsion().law(np.array([-1e-9, 0.0]))
    assert np.all(np.isinf(energy))  # touching layers: outside the law, a barrier for the step


def test_law_is_the_potential_its_force_and_stiffness():
    """F = -dU/d eps and k = dF/d(-eps) = d^2U/d eps^2 > 0 (convex: the joint backward-Euler
    step of dynamics/implicit.py minimises a convex function), by central differences."""
    rep = Repulsion()
    eps = np.array([2e-9, 10e-9, 30e-9])
    h = 1e-13
    energy, force, stiffness = rep.law(eps)
    up, down = rep.law(eps + h), rep.law(eps - h)
    np.testing.assert_allclose(force, -(up[0] - down[0]) / (2 * h), rtol=1e-5)
    np.testing.assert_allclose(stiffness, -(up[1] - down[1]) / (2 * h), rtol=1e-5)
    assert np.all(stiffness > 0)


def test_joint_step_solves_the_backward_euler_equation():
    """eps' = eps + dt (rate + B F(eps')) for two coupled contacts (basis: a unit force along each,
    Q = R = B); for dt -> infinity the separations go to where the repulsion cancels the
    approach, rate + B F = 0 (as far as the round-off of eps + dt rate lets it)."""
    rep = Repulsion()
    eps, rate = np.array([20e-9, 15e-9]), np.array([-3e-6, -1e-6])
    response = np.array([[4e6, 1e6], [1e6, 2e6]])  # m/(N s)
    system = ImplicitSystem(eps, rate, DenseResponse(response), response, [(slice(0, 2), rep.law)])
    for dt in (1e-5, 1e-3, 1e-1):
        z, force = system.solve(dt, [])
        end = system.end_values(z, dt)
        np.testing.assert_allclose(end, eps + dt * (rate + response @ force), rtol=0, atol=1e-18)
        np.testing.assert_allclose(force, rep.force(end), rtol=1e-10)
        assert np.all(end > 0)
    # a step 1e3 s long: |eps' - eps| / dt < 2e-8 m / 1e3 s, 1e-5 of the rate
    z, force = system.solve(1e3, [])
    np.testing.assert_allclose(rate + response @ force, 0.0, atol=1e-5 * np.abs(rate).max())


@pytest.fixture(scope="module")
def finder():
    return GapFinder()


@pytest.mark.parametrize("gap", [1e-6, 3e-7, 1e-8])
def test_gap_between_spheres_is_exact(finder, gap):
    """Along a coordinate axis the QUAD9 cube-sphere passes through the exact sphere at its face
    centres, so the gap is the analytic one; obliquely the Newton result is the minimum of the
    QUAD9 surfaces: never above a dense sampling (12 x 12 Gauss points per element of the other
    body, independent code in placement.py) and within its sampling error."""
    a = 5e-6
    m = wb.mesh.sphere(a, 4)
    centre = np.array([0.0, 0.0, 20e-6])
    bodies = [wb.Body(m, position=centre), wb.Body(m, position=centre + [2 * a + gap, 0, 0])]
    g = finder.between(bodies, 0, 1)
    assert g.distance == pytest.approx(gap, rel=1e-9)
    np.testing.assert_allclose(g.normal, [-1, 0, 0], atol=1e-9)
    direction = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    bodies = [wb.Body(m, position=centre), wb.Body(m, position=centre + (2 * a + gap) * direction)]
    g = finder.between(bodies, 1, 0)
    samples, _ = quad9.surface_quadrature(bodies[1].world_nodes()[m.elements], 12)
    sampled = signed_distance(samples.reshape(-1, 3), bodies[0].world_nodes()[m.elements]).min()
    assert g.distance <= sampled + 1e-15
    assert sampled - g.distance < 3e-9
    assert abs(g.distance - gap) < 2e-9  # the QUAD9 sphere departs from the exact one by ~1 nm
    np.testing.assert_allclose(g.normal, direction, atol=3e-3)  # faceted: normals of the QUAD9 sphere
    np.testing.assert_allclose(np.linalg.norm(g.point - g.other_point), g.distance, rtol=1e-12)


def test_gap_to_the_wall_is_the_lowest_point(finder):
    a = 5e-6
    m = wb.mesh.sphere(a, 4)
    q = np.array([np.cos(0.3), np.sin(0.3), 0.2, 0.0])
    body = wb.Body(m, position=(1e-6, -2e-6, a + 2e-7), orientation=q)
    g = finder.between([body], 0, WALL)
    samples, _ = quad9.surface_quadrature(body.world_nodes()[m.elements], 12)
    assert g.distance <= samples[..., 2].min()
    assert g.distance == pytest.approx(2e-7, abs=2e-9)
    assert g.point[2] == pytest.approx(g.distance) and g.other_point[2] == 0.0


def test_gaps_to_the_wall_searched_together_are_those_searched_one_by_one(finder):
    """GapFinder.to_wall searches several bodies' candidate elements in one launch: each body's
    gap, points and normal are those of its own search, bit for bit (a sphere tilted at 200 nm,
    an upright one at 1 um and a spheroid turned about y at 50 nm: the elements differ in count
    and shape), and each is the analytic gap of the QUAD9 sphere's lowest node where one lies
    on the axis (the upright sphere)."""
    a = 5e-6
    sphere, spheroid = wb.mesh.sphere(a, 3), wb.mesh.spheroid(a, 0.6 * a, 3)
    tilted = np.array([np.cos(0.3), np.sin(0.3), 0.2, 0.0])
    turned = np.array([np.cos(0.4), 0.0, np.sin(0.4), 0.0])
    bodies = [wb.Body(sphere, position=(1e-6, -2e-6, a + 2e-7), orientation=tilted / np.linalg.norm(tilted)),
              wb.Body(sphere, position=(30e-6, 0.0, a + 1e-6)),
              wb.Body(spheroid, position=(-30e-6, 5e-6, 0.0))]
    lowest = bodies[2].world_nodes()[:, 2].min()
    bodies[2] = wb.Body(spheroid, position=(-30e-6, 5e-6, 5e-8 - lowest), orientation=turned)
    together = finder.to_wall(bodies, [2, 0, 1])
    for gap, i in zip(together, [2, 0, 1]):
        alone = finder.between(bodies, i, WALL)
        assert gap.body == i and gap.distance == alone.distance
        np.testing.assert_array_equal(gap.point, alone.point)
        np.testing.assert_array_equal(gap.other_point, alone.other_point)
    assert together[2].distance == pytest.approx(1e-6, rel=1e-9)
    assert finder.to_wall(bodies, []) == []


def test_contacts_carry_the_points_where_their_forces_act():
    """A cell 10 nm (between roughness layers) from the wall and from another cell: each
    contact's coordinate holds its closest points, so forces along the coordinates become point
    loads on the surfaces (for deforming cells): equal and opposite at the two closest points
    between the cells, the wall's on the low cell alone (the wall is its ``other``); joined with
    coordinates that have no points (bonds), those stay out."""
    from warpbem.forces.interaction import ImplicitCoordinates
    from warpbem.surfaces.gaps import Contacts

    a = 5e-6
    m = wb.mesh.sphere(a, 4)
    rep = Repulsion().bound(Model([m, m], [False, False]))  # it derives nothing from the model
    low = a + 225e-9 + 10e-9
    bodies = [wb.Body(m, position=(0.0, 0.0, low)), wb.Body(m, position=(2 * a + 360e-9, 0.0, low))]
    contacts = Contacts(bodies, np.array([a, a]), True, GapFinder())
    coordinates = rep.implicit_coordinates(bodies, contacts, None, np.zeros((2, 3)), np.zeros((2, 3)), 1e-6)
    joined = ImplicitCoordinates.join([ImplicitCoordinates(np.zeros(1), np.array([[0, 1]]), np.ones((1, 2, 3)),
                                                           np.zeros((1, 2, 3)), 2), coordinates])
    loads = joined.point_loads(np.concatenate([[5e-12], np.full(len(coordinates.values), 1e-10)]))
    pairs = {(b, o) for b, o, _, _ in loads}
    assert pairs == {(0, WALL), (1, WALL), (0, 1), (1, 0)}
    by = {(b, o): (p, f) for b, o, p, f in loads}
    np.testing.assert_allclose(by[(0, WALL)][0], [0, 0, 225e-9 + 10e-9], atol=2e-9)
    np.testing.assert_allclose(by[(0, WALL)][1], [0, 0, 1e-10], rtol=1e-9)
    np.testing.assert_allclose(by[(0, 1)][1], -by[(1, 0)][1], rtol=1e-12)
    np.testing.assert_allclose(by[(0, 1)][1], [-1e-10, 0, 0], atol=1e-18)
    np.testing.assert_allclose(by[(0, 1)][0], [a, 0, low], atol=1e-12)
