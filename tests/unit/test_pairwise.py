"""The grand mobility of several free cells from lone and pair snapshots
(warpbem/dynamics/pairwise.py, ``[solver] grand_mobility = "pairs"``)."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.dynamics.pairwise import lateral_spacing, pair_key
from warpbem.options import OptionError
from warpbem.surfaces.body import Body
from tests.interrupted import run_killed_after

A = 2e-6
MESH = wb.mesh.sphere(A, 2)
HEIGHT = A + 236e-9
EXACT = dict(reuse_tolerance=1e-12, reuse_interaction=1e-12, pair_lateral=1e-12)  # lattices below round-off


def solves(n, meshes=None, fixed=None, **solver):
    model = Model(meshes or [MESH] * n, fixed or [False] * n, Flow(100.0, 1e-3), solver=SolverOptions(**solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))


def motion(flow, grand):
    """(grand mobility Q, the flow's velocity and angular velocity times A) of a snapshot."""
    return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])


def relative_change(a, b):
    return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.parametrize("offset, heights", [((-3 * A, 1.5 * A), (9e-9, -7e-9)), ((3 * A, -1.5 * A), (9e-9, -7e-9)),
                                             ((-3 * A, -1.5 * A), (9e-9, -7e-9)), ((-3 * A, 1.5 * A), (4e-9, 4e-9))],
                         ids=["exchanged-and-mirrored", "mirrored", "exchanged", "half-turn"])
def test_two_cells_from_their_pair_snapshot_are_the_direct_solve(offset, heights):
    """For two cells the pairwise sum is exact: M = M_i + (M^(ij) - M_i), so the assembled grand
    mobility and flow motion equal the direct solve of the two, whatever symmetry maps the pair
    to its stored form (the first cell at the origin, the offset in x >= 0, y >= 0): the
    translation along the wall, the exchange of the cells, the mirror y -> -y (forces and
    velocities change their y components, torques and angular velocities their x and z ones),
    and for two cells at one height the half turn that exchanges them (the loads on the second
    cell from those on the first). A wrong sign in any of them changes entries of the size of
    the coupling (1e-2 here)."""
    hydro = solves(2, **EXACT, grand_mobility="pairs")
    bodies = [Body(MESH, position=(0.7e-6, -0.4e-6, HEIGHT + heights[0])),
              Body(MESH, position=(0.7e-6 + offset[0], -0.4e-6 + offset[1], HEIGHT + heights[1]))]
    direct = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
    assembled = motion(*hydro._snapshot(bodies))
    assert max(relative_change(assembled, direct)) < 1e-7
    alone = motion(*solves(2, **EXACT, grand_mobility="pairs", pair_cutoff=0.0)._snapshot(bodies))
    assert min(relative_change(alone, direct)) > 1e-3  # the coupling the check would miss


def test_the_pair_lattice_grows_as_the_fourth_power_of_the_distance_in_steps_of_2_up_to_an_eighth_of_it():
    contact = 2 * A
    assert lateral_spacing(1.5 * A, 10e-9, contact) == 10e-9  # below contact distance: the base
    assert lateral_spacing(2 * contact, 10e-9, contact) == 10e-9 * 16  # (r / contact)^4 = 16
    assert lateral_spacing(2.5 * contact, 10e-9, contact) == 10e-9 * 32  # 39.06 -> 32
    # and at most 1/8 of the distance: far pairs are never snapped onto one another
    for distance in (10 * contact, 60 * contact, 1e-2):
        assert lateral_spacing(distance, 10e-9, contact) <= distance / 8
        assert lateral_spacing(distance, 10e-9, contact) > distance / 16
    # the same pair seen from either cell, or mirrored, has one key
    keys = {pair_key(np.array(o), (HEIGHT, HEIGHT), (0, 0), 10e-9, contact)[0]
            for o in ((5 * A, 1 * A), (-5 * A, -1 * A), (5 * A, -1 * A), (-5 * A, 1 * A))}
    assert len(keys) == 1


def test_pairs_refuse_fixed_and_non_spherical_cells_and_no_snapshots():
    spheroid = wb.mesh.spheroid(A, 0.5 * A, 2)
    with pytest.raises(OptionError, match="grand_mobility = 'pairs' takes free spherical cells only"):
        solves(2, meshes=[MESH, spheroid], reuse_tolerance=2e-9, grand_mobility="pairs")
    with pytest.raises(OptionError, match="grand_mobility = 'pairs' takes free spherical cells only"):
        solves(2, fixed=[False, True], reuse_tolerance=2e-9, grand_mobility="pairs")
    with pytest.raises(OptionError, match=r"it needs solver.reuse_tolerance > 0 \(2e-9 m"):
        solves(2, grand_mobility="pairs")


PAIRS_SCENE = """
[flow]
shear_rate = 100.0
viscosity = 1.0e-3
[physics]
gravity = true
repulsion = true
adhesion = true
[adhesion]
spring_constant = 5.0e-4
seed = 3
[time]
end = 0.004
dt_max = 2.7e-4
dt_min = 1.0e-7
contact_gap = 1.0e-9
scheme = "euler"
frame_interval = 1.0e-3
[solver]
grand_mobility = "pairs"
[[arrays]]
count = [2, 1]
pitch = [10.0e-6, 0.0]
origin = [0.0, 0.0, 2.236e-6]
density = 1050.0
mesh = { shape = "sphere", radius = 2.0e-6, subdivisions = 2 }
"""


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_a_resumed_run_of_cells_in_pairs_reproduces_the_uninterrupted_one(tmp_path):
    """Two adhesive cells on pair snapshots: a second run with the same seed repeats the first
    bit for bit (the pairs' part is a function of the lattice points alone, so its cache changes
    no number), and a run killed after 2 frames and resumed forms the same bonds and ends within
    1e-9 radii of where the uninterrupted one ends (as one cell's, test_adhesion.py: its solves
    start GMRES from another previous solution)."""
    from warpbem.app import run

    path = tmp_path / "pairs.toml"
    path.write_text(PAIRS_SCENE)
    run.run(path, tmp_path / "straight.h5", progress=lambda line: None)
    run.run(path, tmp_path / "again.h5", progress=lambda line: None)
    run_killed_after(2, path, tmp_path / "killed.h5")
    run.run(None, tmp_path / "killed.h5", resume=True, progress=lambda line: None)
    import h5py

    with h5py.File(tmp_path / "killed.h5") as f, h5py.File(tmp_path / "straight.h5") as g, \
            h5py.File(tmp_path / "again.h5") as h:
        assert f["time"].shape == g["time"].shape == (5,)
        assert g["bond_count"][-1].sum() > 0
        for name in ("position", "velocity", "bond_receptor", "bond_count"):
            np.testing.assert_array_equal(h[name][:], g[name][:])
        np.testing.assert_array_equal(f["bond_receptor"][:], g["bond_receptor"][:])
        # the resumed solves start GMRES from another previous solution (round-off apart)
        np.testing.assert_allclose(f["position"][:], g["position"][:], rtol=0, atol=1e-9 * A)
