"""The far pairs' coupling from each cell's own traction moments with the wall's images
(warpbem/dynamics/far_field.py, ``[solver] far_field = "moments"``)."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.surfaces.body import Body

A = 2e-6
MESH = wb.mesh.sphere(A, 2)
HEIGHT = A + 236e-9
VISCOSITY, SHEAR = 1e-3, 100.0
EXACT = dict(reuse_tolerance=1e-12, reuse_interaction=1e-12, pair_lateral=1e-12)  # lattices below round-off


def solves(**solver):
    model = Model([MESH] * 2, [False] * 2, Flow(SHEAR, VISCOSITY), solver=SolverOptions(**EXACT, **solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))


def physical_coupling(grand):
    """(6, 6) the motion of cell 1 (velocity, angular velocity) per unit force and torque (N, N m)
    on cell 0, from a "bodies" basis (torques of 1 N times the radius)."""
    scale = np.array([1, 1, 1, 1 / A, 1 / A, 1 / A])[:, None]
    return np.concatenate([grand.velocity[:6, 1], grand.angular_velocity[:6, 1]], axis=1) * scale


def relative_change(a, b):
    return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]


def motion(flow, grand):
    return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_far_apart_the_cells_couple_as_blakes_far_field_of_their_first_moments():
    """Far along the wall (rho >> h) a force F at height h drives u_a = 3 h z rho_a rho_b F_b /
    (2 pi mu rho^5) (Blake 1971, J. Phys. Chem. 70:303, the far field of eq. 12). A cell near the
    wall acts as a point force at its first moment about the wall and is moved by a wall shear
    z gamma as its shear response: the reciprocal theorem gives both from its lone mobility in
    shear, U_x = s gamma (s in m). So the far field between two cells 300 um apart (h / rho =
    0.7 %) must give U_x of the second per F_x on the first of s^2 3 cos^2(30 deg) / (2 pi mu
    rho^3). The traction moments and the mobility are two discretisations of the k = 2 sphere:
    they meet to 6 %. Missing the images would give a coupling 1 / rho (orders of magnitude
    larger), a wrong sign or factor of 2 a ratio of -1 or 2."""
    rho = 300e-6 * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    bodies = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(*rho, HEIGHT))]
    far = solves(grand_mobility="pairs", near_radius=1e-9)
    _, grand = far._snapshot(bodies)
    lone = wb.solve_mobility([Body(MESH, position=(0.0, 0.0, HEIGHT))], shear_rate=SHEAR, viscosity=VISCOSITY)
    s = lone.velocity[0, 0] / SHEAR
    blake = s**2 * 3 * np.outer(rho, rho) / (2 * np.pi * VISCOSITY * np.linalg.norm(rho) ** 5)
    coupling = physical_coupling(grand)
    np.testing.assert_allclose(coupling[:2, :2], blake, rtol=0.06)
    # reciprocal: the first cell's motion under the second's load is the same matrix transposed
    back = np.concatenate([grand.velocity[6:, 0], grand.angular_velocity[6:, 0]], axis=1)
    back *= np.array([1, 1, 1, 1 / A, 1 / A, 1 / A])[:, None]
    np.testing.assert_allclose(back, coupling.T, rtol=1e-12, atol=1e-12 * np.abs(coupling).max())


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_at_the_near_radius_the_far_field_holds_the_pair_to_its_direct_solve():
    """Two cells at the default near radius (7 radii, 14 um) and 10 radii: the far field (each
    cell alone plus the first reflection between them) against the direct two-body solve, in the
    norm of benchmarks/many_cells.py (largest change over largest entry): within 5e-4 / 7e-4 of
    the grand mobility / flow's motion at 14 um and 2e-4 / 1e-4 at 20 um (measured 4.1e-4 / 5.8e-4
    and 1.7e-4 / 2.1e-5), where the coupling itself is 30 to 40 times larger."""
    for distance, bound in ((14e-6, (5e-4, 7e-4)), (20e-6, (2e-4, 1e-4))):
        rho = distance * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
        bodies = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(*rho, HEIGHT + 13e-9))]
        direct_solves = solves()
        direct = motion(Motion.of(direct_solves.mobility.solve(bodies)), direct_solves._grand_mobility(bodies))
        far = relative_change(motion(*solves(grand_mobility="pairs", near_radius=1e-9)._snapshot(bodies)), direct)
        alone = relative_change(motion(*solves(grand_mobility="pairs", pair_cutoff=0.0)._snapshot(bodies)), direct)
        assert far[0] < bound[0] and far[1] < bound[1]
        assert min(alone) > 20 * max(far)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_the_cells_tractions_are_kept_on_disk_and_read_back_bit_for_bit():
    """The far field's traction sets go to the snapshot store (snapshot_store.py) with the lone and
    pair snapshots: a second model of the same cells solves none and couples them identically."""
    rho = 40e-6 * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    bodies = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(*rho, HEIGHT + 13e-9))]
    first, second = (solves(grand_mobility="pairs", near_radius=1e-9) for _ in range(2))
    snapshots = [motion(*hydro._snapshot(bodies)) for hydro in (first, second)]
    assert first.pairwise.far.solved == 2 and second.pairwise.far.solved == 0
    assert all(np.array_equal(a, b) for a, b in zip(*snapshots))
