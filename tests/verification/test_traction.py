"""Surface traction of rigid bodies by the Completed Adjoint Double Layer (thesis eq. 2.18-2.25;
Phan-Thien & Fan 1995; ``warpbem/hydro/traction.py``) against exact Stokes flow and against the
independent CDL mobility solve:

* a force- and torque-free sphere in unbounded simple shear (strain E plus a rotation it
  follows) carries t = 5 mu E . n (the pressure of the disturbance included; its first moment
  is the stresslet 20/3 pi mu a^3 E, Batchelor 1970; Kim & Karrila 1991 ch. 3);
* a sphere translating at U in unbounded fluid carries the uniform traction -3 mu U / (2 a)
  (Stokes drag 6 pi mu a U spread over 4 pi a^2);
* above the wall and beside another body, the flow of eq. 2.18 built from the traction moves
  each free body's interior at the rigid velocity the CDL mobility gives it, holds a fixed
  body's interior at rest, and the traction integrates to the loads given.
The errors fall under refinement (the density is piecewise constant: first order pointwise).
"""

import numpy as np
import pytest

import warpbem as wb
from warpbem import solve_traction
from warpbem.surfaces.body import Body

A, MU, SHEAR = 5e-6, 1e-3, 100.0


def strain_error(k):
    s = solve_traction([Body(wb.mesh.sphere(A, k))], SHEAR, MU, wall=False)
    e = 0.5 * SHEAR * np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    exact = 5.0 * MU * s.normals @ e
    return np.abs(s.traction - exact).max() / np.abs(exact).max(), s


def test_a_free_sphere_in_unbounded_shear_carries_five_mu_e_dot_n():
    """Pointwise error 8.3e-3 at k = 4 and 4.0e-3 at k = 8 (measured): first order."""
    coarse, s = strain_error(4)
    fine, _ = strain_error(8)
    assert coarse < 1.2e-2 and fine < 0.6 * coarse
    scale = 5.0 * MU * SHEAR * A**2
    assert np.abs(s.force).max() < 1e-12 * scale and np.abs(s.torque).max() < 1e-12 * scale * A


def test_a_translating_sphere_carries_the_uniform_stokes_traction():
    """The external force F on a free sphere in still, unbounded fluid: the CDL solve gives its
    velocity U, the traction problem t = -3 mu U / (2 a) everywhere (to 7.5e-3, k = 4)."""
    mesh = wb.mesh.sphere(A, 4)
    force = np.array([[1e-12, -2e-12, 3e-12]])
    velocity = wb.solve_mobility([Body(mesh)], 0.0, MU, wall=False, forces=force).velocity[0]
    s = solve_traction([Body(mesh)], 0.0, MU, wall=False, forces=force)
    exact = -3.0 * MU * velocity / (2.0 * A)
    assert np.abs(s.traction - exact).max() < 1e-2 * np.abs(exact).max()
    np.testing.assert_allclose(s.force[0], -force[0], rtol=0, atol=1e-3 * np.abs(force).max())


def interior_points(body, offset=0.3 * A):
    return body.position + np.array([[0.0, 0.0, 0.0], [offset, 0.0, 0.0], [0.0, offset, 0.0], [0.0, 0.0, offset]])


def rigid_motion(u, offset=0.3 * A):
    """(U, Omega) of the rigid field sampled at the centre and 0.3 a along each axis."""
    du = (u[1:] - u[0]) / offset  # row l: Omega x e_l
    return u[0], np.array([du[1, 2], du[2, 0], du[0, 1]])


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.parametrize("height, tolerance", [(1.5, 5e-3), (1.1, 8e-3)])
def test_near_the_wall_the_traction_moves_a_free_sphere_as_the_mobility_solve_does(height, tolerance):
    """k = 4 sphere at h/a = 1.5 and 1.1 in wall shear: U from eq. 2.18 inside the body agrees
    with the CDL velocity to 2.5e-3 and 4.9e-3 (7e-4 at k = 8), Omega to 2.3 % and 3.5 %; the
    traction of this force-free sphere integrates to 1.5e-3 and 3.0e-3 of the shear force scale
    6 pi mu a gdot h (the discrete adjoint identity <phi, (1/2 + D*) t> = 0 holds to that)."""
    body = Body(wb.mesh.sphere(A, 4), position=(0.0, 0.0, height * A))
    mobility = wb.solve_mobility([body], SHEAR, MU)
    s = solve_traction([body], SHEAR, MU, forces=mobility.force, torques=mobility.torque)
    velocity, angular_velocity = rigid_motion(s.velocity(interior_points(body)))
    speed = np.abs(mobility.velocity[0]).max()
    assert np.abs(velocity - mobility.velocity[0]).max() < tolerance * speed
    assert np.abs(angular_velocity - mobility.angular_velocity[0]).max() < 0.05 * np.abs(mobility.angular_velocity).max()
    assert np.abs(s.force[0]).max() < 5e-3 * 6 * np.pi * MU * A * SHEAR * height * A


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_a_held_sphere_at_the_wall_rests_inside_and_its_traction_converges():
    """A sphere held at h/a = 1.1 in wall shear, loads from the CDL solve: the interior velocity
    of eq. 2.18 is 4.3e-3 of gdot h a at k = 4 and 1.1e-3 at k = 8 (measured), and the traction
    integrates to minus the holding force to 1.6e-3 and 1.8e-4, to minus the holding torque to
    3.7e-3 and 1.4e-3."""
    errors = []
    for k in (4, 8):
        body = Body(wb.mesh.sphere(A, k), position=(0.0, 0.0, 1.1 * A), fixed=True)
        held = wb.solve_mobility([body], SHEAR, MU)
        s = solve_traction([body], SHEAR, MU, forces=held.force, torques=held.torque)
        interior = np.abs(s.velocity(interior_points(body))).max() / (SHEAR * 1.1 * A)
        force = np.abs(s.force[0] + held.force[0]).max() / np.abs(held.force[0]).max()
        torque = np.abs(s.torque[0] + held.torque[0]).max() / np.abs(held.torque[0]).max()
        errors.append((interior, force, torque))
    (coarse, coarse_force, coarse_torque), (fine, fine_force, fine_torque) = errors
    assert coarse < 6e-3 and fine < 0.4 * coarse
    assert coarse_force < 3e-3 and fine_force < 0.3 * coarse_force
    assert coarse_torque < 6e-3 and fine_torque < 0.5 * coarse_torque


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_two_spheres_near_the_wall_each_move_as_the_mobility_solve_says():
    """Two k = 4 spheres, one sedimenting past the other in wall shear (gap 0.5 a between them):
    the traction of both moves each one's interior at its CDL velocity to 1 % of the fastest
    (1.9e-3 and 2.4e-3 measured) and integrates to the given loads to 5e-3 of the shear force
    scale (1.7e-3 and 1.3e-3)."""
    mesh = wb.mesh.sphere(A, 4)
    bodies = [Body(mesh, position=(0.0, 0.0, 1.3 * A)), Body(mesh, position=(2.5 * A, 0.0, 1.6 * A))]
    forces = np.array([[0.0, 0.0, -2e-13], [0.0, 0.0, 0.0]])
    mobility = wb.solve_mobility(bodies, SHEAR, MU, forces=forces)
    s = solve_traction(bodies, SHEAR, MU, forces=forces)
    speed = np.abs(mobility.velocity).max()
    for p, body in enumerate(bodies):
        velocity, _ = rigid_motion(s.velocity(interior_points(body)))
        assert np.abs(velocity - mobility.velocity[p]).max() < 1e-2 * speed
        np.testing.assert_allclose(s.force[p], -forces[p], rtol=0,
                                   atol=5e-3 * 6 * np.pi * MU * A * SHEAR * body.position[2])


def test_an_extra_contact_traction_is_balanced_by_the_fluid():
    """A Hertz pressure p0 sqrt(1 - rho^2 / a_c^2) (thesis eq. 4.8-4.9; a_c = 2 um, p0 = 10 Pa)
    pushes the bottom of a free sphere in still, unbounded fluid: it is an external force F_c
    on the sphere (the applied pressure integrated over the elements), so the fluid's traction
    is Stokes's uniform -F_c / (4 pi a^2) (to 1e-2 of it at k = 8; 3.2e-3 measured), and the total traction
    (fluid plus contact) is in balance."""
    contact_radius, peak = 2e-6, 10.0

    def hertz(points, normals):
        rho2 = points[:, 0] ** 2 + points[:, 1] ** 2
        inside = (points[:, 2] < 0) & (rho2 < contact_radius**2)
        pressure = np.where(inside, peak * np.sqrt(np.clip(1 - rho2 / contact_radius**2, 0, None)), 0.0)
        return pressure[:, None] * np.array([0.0, 0.0, 1.0])

    s = solve_traction([Body(wb.mesh.sphere(A, 8))], 0.0, MU, wall=False, extra_traction=hertz)
    applied = (s.areas[:, None] * (s.total_traction - s.traction)).sum(axis=0)
    assert applied[2] > 0.5 * peak * np.pi * contact_radius**2  # the patch is resolved
    uniform = -applied / (4 * np.pi * A**2)
    assert np.abs(s.traction - uniform).max() < 1e-2 * np.abs(uniform).max()
    np.testing.assert_allclose(s.force[0], -applied, rtol=0, atol=1e-3 * applied[2])
    assert np.abs((s.areas[:, None] * s.total_traction).sum(axis=0)).max() < 1e-3 * applied[2]


@pytest.mark.parametrize("contact_radius", [2e-6, 0.0])
def test_a_point_load_is_spread_over_its_hertz_patch_exactly(contact_radius):
    """A contact load F at the bottom of a free sphere (k = 8), spread over a 2 um Hertz patch
    (or, with radius 0, on the nearest element): the element tractions sum to F to rounding and
    their moment is F's about the point to rounding on the symmetric patch, within |F| times
    the shift to the nearest collocation point (0.49 um at k = 8) for the single element; they
    peak at the point, and on the patch, whose moment about the centre is nil, the fluid
    answers with Stokes's uniform -F / (4 pi a^2) to 1e-2 (the traction the extra-traction test
    above checks; the shifted single element also turns the sphere)."""
    force = np.array([0.0, 0.0, 1e-11])
    point = np.array([0.0, 0.0, -A])
    s = solve_traction([Body(wb.mesh.sphere(A, 8))], 0.0, MU, wall=False,
                       point_loads=[(0, point, force, contact_radius)])
    contact = s.total_traction - s.traction
    np.testing.assert_allclose((s.areas[:, None] * contact).sum(axis=0), force, rtol=1e-12, atol=1e-24)
    loaded = np.flatnonzero(np.abs(contact[:, 2]) > 0)
    nearest = np.argmin(np.linalg.norm(s.points - point, axis=1))
    shift = 1e-12 * A if contact_radius else 1.01 * np.linalg.norm(s.points[nearest] - point)
    moment = (s.areas[:, None] * np.cross(s.points - point, contact)).sum(axis=0)
    assert np.linalg.norm(moment) <= shift * np.linalg.norm(force)
    assert (len(loaded) > 4 if contact_radius else len(loaded) == 1) and np.argmax(contact[:, 2]) == nearest
    uniform = -force / (4 * np.pi * A**2)
    assert not contact_radius or np.abs(s.traction - uniform).max() < 1e-2 * np.abs(uniform).max()
    with pytest.raises(ValueError, match="point load on body 1: there are 1 bodies"):
        solve_traction([Body(wb.mesh.sphere(A, 2))], 0.0, MU, wall=False, point_loads=[(1, point, force, 0.0)])


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_the_loads_alone_are_the_difference_of_two_solves_and_in_balance():
    """A sphere (k = 4) in wall shear 240 nm above the wall (a rolling cell's gap), under a
    body load and a bond's point load at its bottom: ``load_traction`` (the point load spread,
    with the fluid's answer to both loads, no flow) is by linearity the total traction less the
    total traction of the force-free sphere in the same shear (to the GMRES tolerance), and
    integrates to minus the body load, with the point load's moment balanced, to the
    discretisation error of the adjoint identity this close to the wall (module docstring;
    1.1e-3 of the load measured); the fluid's answer is not uniform next to the wall: it peaks in
    the film under the sphere."""
    body = Body(wb.mesh.sphere(A, 4), position=(0.0, 0.0, A + 240e-9))
    point, bond, weight = np.array([0.0, 0.0, 240e-9]), np.array([-2e-11, 0.0, -1e-10]), np.array([0.0, 0.0, -2e-13])
    loaded = solve_traction([body], 100.0, MU, True, [weight], [[0.0, 0.0, 0.0]],
                            point_loads=[(0, point, bond, 0.0)], load_response=True)
    free = solve_traction([body], 100.0, MU, True)
    alone = loaded.load_traction
    scale = np.abs(alone).max()
    np.testing.assert_allclose(alone, loaded.total_traction - free.total_traction, rtol=0, atol=1e-6 * scale)
    arm = loaded.points - body.position
    np.testing.assert_allclose((loaded.areas[:, None] * alone).sum(axis=0), -weight, rtol=0,
                               atol=3e-3 * np.linalg.norm(bond))
    assert np.abs((loaded.areas[:, None] * np.cross(arm, alone)).sum(axis=0)).max() < 3e-3 * np.linalg.norm(bond) * A
    film = loaded.points[:, 2] < 0.3 * A
    fluid = alone - (loaded.total_traction - loaded.traction)
    assert np.abs(fluid[film]).max() > 5 * np.abs(fluid[~film]).max()
    assert free.load_traction is None
    with pytest.raises(ValueError, match="no 'loads' traction"):
        free.on_mesh(0, "loads")


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_on_the_surface_the_traction_holds_a_held_sphere_at_rest():
    """Eq. 2.18 on the surface itself (the single layer's self element by Duffy triangles): a
    sphere held at h/a = 1.5 in wall shear, loads from the CDL solve; the surface velocity is
    9.7e-3 of gdot h a at k = 4 and 1.8e-3 at k = 8 (measured), the no-slip condition the
    traction solve never imposed."""
    residuals = []
    for k in (4, 8):
        body = Body(wb.mesh.sphere(A, k), position=(0.0, 0.0, 1.5 * A), fixed=True)
        held = wb.solve_mobility([body], SHEAR, MU)
        s = solve_traction([body], SHEAR, MU, forces=held.force, torques=held.torque)
        residuals.append(np.abs(s.surface_velocity()).max() / (SHEAR * 1.5 * A))
    assert residuals[0] < 1.5e-2 and residuals[1] < 0.3 * residuals[0]
