"""Mobility snapshots of several bodies (warpbem/dynamics/hydrodynamics.py): the interaction
snapshot on the coarse height lattice (``reuse_interaction``) with each free body's self part
moved to its own height by its lone snapshots."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion, Responses
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.surfaces.body import Body

A = 2e-6
MESH = wb.mesh.sphere(A, 2)
FINE, COARSE, LATERAL = 1e-9, 40e-9, 1e-6
HEIGHT = np.round((A + 236e-9) / COARSE) * COARSE  # on the coarse lattice


def solves(interaction):
    model = Model([MESH, MESH], [False, False], Flow(100.0, 1e-3),
                  solver=SolverOptions(reuse_tolerance=FINE, reuse_lateral=LATERAL, reuse_interaction=interaction))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))


def motion(hydro, flow, grand):
    """(grand mobility Q, the flow's velocity and angular velocity times A) of a snapshot."""
    return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])


def exact(hydro, bodies):
    return motion(hydro, Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))


def relative_change(a, b):
    return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_far_apart_cells_take_their_self_part_at_their_own_heights():
    """Two cells 100 radii apart barely interact, so their mobility is each one's lone mobility
    at its own height: 16 nm above and below the coarse lattice point (on the fine lattice) the
    split snapshot matches the exact solve to 1e-6 (4e-8 measured), while the interaction
    snapshot alone, at the lattice point, is off by the self mobility's change over 16 nm of a
    0.24 um gap (1.0e-2 in the grand mobility, 1.7e-2 in the motion in the flow).
    The two cells share a mesh, so they share their lone snapshots: one at the coarse lattice
    point, one at each cell's fine height."""
    hydro = solves(COARSE)
    bodies = [Body(MESH, position=(0.0, 0.0, HEIGHT + 16e-9)), Body(MESH, position=(100 * A, 0.0, HEIGHT - 16e-9))]
    split = motion(hydro, *hydro._snapshot(bodies))
    reference = exact(hydro, bodies)
    assert max(relative_change(split, reference)) < 1e-6
    coarse = motion(hydro, *hydro._kept(*hydro._snapped(bodies, COARSE), lambda b: None))
    assert min(relative_change(coarse, reference)) > 5e-3
    assert hydro.snapshots_solved == 1 + 1 + 2  # interaction, lone coarse, lone fine at each height


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_interaction_lattice_equal_to_the_fine_one_is_the_full_snapshot():
    """reuse_interaction = reuse_tolerance: the snapshot is the exact solve of the whole system
    snapped to the fine lattice (heights to 1 nm, lateral positions to 1 um), no lone part."""
    hydro = solves(FINE)
    bodies = [Body(MESH, position=(0.2e-6, 0.0, HEIGHT + 0.3e-9)), Body(MESH, position=(6 * A, 0.4e-6, HEIGHT))]
    snapped = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(6 * A, 0.0, HEIGHT))]
    np.testing.assert_allclose(np.concatenate([m.ravel() for m in motion(hydro, *hydro._snapshot(bodies))]),
                               np.concatenate([m.ravel() for m in exact(hydro, snapped)]), rtol=0, atol=1e-12 * 1e6)
    assert hydro.snapshots_solved == 1


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_free_cells_moved_together_along_the_wall_keep_their_snapshot():
    """Free cells above the wall in shear (u = gdot z e_x) are invariant under translation along
    it, so their lattice points are keyed shifted by the first cell's: two cells moved together by
    37.1 um along the flow and -5.77 um across it (no multiple of the 1 um lattice; each cell's
    nearest lattice point moves by 37 and -6 um alike) take the snapshot already solved, bit for
    bit, and it is the exact solve of the cells' snapped offset."""
    hydro = solves(FINE)
    offset = np.array([6 * A, 0.1e-6, 0.0])
    first = np.array([0.2e-6, 0.0, HEIGHT])
    snapshot = motion(hydro, *hydro._snapshot([Body(MESH, position=first), Body(MESH, position=first + offset)]))
    moved = first + np.array([37.1e-6, -5.77e-6, 0.0])
    again = motion(hydro, *hydro._snapshot([Body(MESH, position=moved), Body(MESH, position=moved + offset)]))
    assert hydro.snapshots_solved == 1
    for a, b in zip(again, snapshot):
        np.testing.assert_array_equal(a, b)
    snapped = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(6 * A, 0.0, HEIGHT))]
    np.testing.assert_allclose(np.concatenate([m.ravel() for m in snapshot]),
                               np.concatenate([m.ravel() for m in exact(hydro, snapped)]), rtol=0, atol=1e-12 * 1e6)


def test_near_contact_the_lateral_lattice_is_halved_until_no_gap_moves_by_more_than_half_of_it():
    """Two cells 0.5 um apart (surface to surface) on the 1 um lattice: their nearest lattice
    points would set them 1.0 um apart, twice the gap, so the snapshot takes the lattice halved
    once (0.5 um), where the snapped gap is the gap; 2 um apart the 1 um lattice's 0.4 um
    shift is within half the gap and the key is the lattice's own (hydrodynamics.GAP_SHARE)."""
    hydro = solves(FINE)

    def snapped_gap(gap):
        bodies = [Body(MESH, position=(0.4e-6, 0.0, HEIGHT)), Body(MESH, position=(0.4e-6 + 2 * A + gap, 0.0, HEIGHT))]
        key, snapped = hydro._snapped_apart(bodies)
        return key, np.linalg.norm(snapped[1].position - snapped[0].position) - 2 * A

    key, gap = snapped_gap(0.5e-6)
    assert key[-1] == ("halved", 1) and gap == pytest.approx(0.5e-6, abs=1e-12)
    plain = hydro._snapped([Body(MESH, position=(0.4e-6, 0.0, HEIGHT)),
                            Body(MESH, position=(0.4e-6 + 2 * A + 0.5e-6, 0.0, HEIGHT))], FINE)
    assert np.linalg.norm(plain[1][1].position - plain[1][0].position) - 2 * A == pytest.approx(1.0e-6, abs=1e-12)
    key, gap = snapped_gap(2.0e-6)
    assert key == hydro._snapped([Body(MESH, position=(0.4e-6, 0.0, HEIGHT)),
                                  Body(MESH, position=(0.4e-6 + 2 * A + 2e-6, 0.0, HEIGHT))], FINE)[0]
    assert abs(gap - 2.0e-6) <= 0.5 * 2.0e-6


def test_interaction_lattice_finer_than_the_fine_one_is_refused():
    with pytest.raises(ValueError, match=r"reuse_interaction: 1e-09 is outside the allowed range \[2e-09, 1e-06\] \(>= reuse_tolerance > 0\)"):
        SolverOptions(reuse_tolerance=2e-9, reuse_interaction=1e-9)


def test_the_dissipation_of_a_basis_is_load_dot_motion_symmetrised():
    """Responses.quadratic, Q_kl = (load k) . (motion l) symmetrised: for the "bodies" basis (one
    force or torque component per load) taken by a gather, bit for bit the product of the loads
    with the motions; for loads of several components (a bond's direction on two bodies) the
    product itself; against np.einsum over bodies and components, for random (seeded) motions."""
    rng = np.random.default_rng(5)
    n = 4
    p = 6 * n
    velocity, angular = rng.normal(size=(p, n, 3)), rng.normal(size=(p, n, 3))
    single_force, single_torque = np.zeros((p, n, 3)), np.zeros((p, n, 3))
    for b in range(n):
        for i in range(3):
            single_force[6 * b + i, b, i] = 1.0
            single_torque[6 * b + 3 + i, b, i] = A * (1.0 + b)
    spread_force, spread_torque = rng.normal(size=(p, n, 3)), rng.normal(size=(p, n, 3))
    for force, torque in ((single_force, single_torque), (spread_force, spread_torque)):
        q = (np.einsum("kbi,lbi->kl", force, velocity) + np.einsum("kbi,lbi->kl", torque, angular))
        expected = 0.5 * (q + q.T)
        got = Responses(velocity, angular, velocity, angular, force, torque, 0, 0.0).quadratic()
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
        if force is single_force:
            product = force.reshape(p, -1) @ velocity.reshape(p, -1).T + torque.reshape(p, -1) @ angular.reshape(p, -1).T
            assert np.array_equal(got, 0.5 * (product + product.T))
