"""The grand mobility of several free cells from lone and pair snapshots
(warpbem/dynamics/pairwise.py, ``[solver] grand_mobility = "pairs"``)."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.dynamics.pairwise import canonical, lateral_spacing, lattice_corners
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


def test_the_pair_lattice_grows_as_the_distance_to_the_five_halves_in_steps_of_2_up_to_an_eighth_of_it():
    contact = 2 * A
    assert lateral_spacing(1.5 * A, 10e-9, contact) == 10e-9  # below contact distance: the base
    assert lateral_spacing(2 * contact, 10e-9, contact) == 10e-9 * 4  # (r / contact)^2.5 = 5.66 -> 4
    assert lateral_spacing(2.5 * contact, 10e-9, contact) == 10e-9 * 8  # 9.88 -> 8
    # and at most 1/8 of the distance: far pairs are never interpolated across the distance itself
    for distance in (10 * contact, 60 * contact, 1e-2):
        assert lateral_spacing(distance, 10e-9, contact) <= distance / 8
        assert lateral_spacing(distance, 10e-9, contact) > distance / 16
    # arrays alike
    spacings = lateral_spacing(np.array([1.5 * A, 4 * A]), 10e-9, np.full(2, contact))
    np.testing.assert_array_equal(spacings, [10e-9, 40e-9])
    # the same lattice point seen from either cell, or mirrored, has one stored form
    points, heights, meshes, swapped, mirrored = canonical([(5, 1), (-5, -1), (5, -1), (-5, 1)],
                                                           [(1.0, 2.0)] * 4, [(0, 1)] * 4)
    np.testing.assert_array_equal(points, [(5, 1)] * 4)
    np.testing.assert_array_equal(swapped, [False, True, False, True])
    np.testing.assert_array_equal(mirrored, [False, False, True, True])
    np.testing.assert_array_equal(heights, [(1.0, 2.0), (2.0, 1.0), (1.0, 2.0), (2.0, 1.0)])
    np.testing.assert_array_equal(meshes, [(0, 1), (1, 0), (0, 1), (1, 0)])


def test_the_bilinear_weights_sum_to_one_and_points_beyond_a_lattice_line_weigh_nothing():
    points, weights = lattice_corners(np.array([(3.25e-6, -1.5e-6), (3.25e-6, 2e-6), (3e-6, 2e-6)]), np.full(3, 1e-6))
    by_point = [{tuple(p): w for p, w in zip(ps, ws) if w > 0} for ps, ws in zip(points, weights)]
    assert by_point[0] == pytest.approx({(3, -2): 0.375, (4, -2): 0.125, (3, -1): 0.375, (4, -1): 0.125})
    assert by_point[1] == pytest.approx({(3, 2): 0.75, (4, 2): 0.25})  # on a lattice line in y
    assert by_point[2] == {(3, 2): 1.0}  # on a lattice point (2e-6 / 1e-6 to round-off): that point alone
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, rtol=0, atol=1e-15)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_between_lattice_points_the_pair_is_interpolated_to_second_order_in_the_spacing():
    """Between its lattice points a pair's snapshot is the bilinear interpolation of theirs,
    whose error at fractions t, u of the lattice square is -(s^2 / 2) [t (1 - t) f_xx + u (1 - u)
    f_yy] + O(s^3) (the interpolation remainder), second order in the spacing s, where the
    nearest point's is first order. The offset (-6133, 1333) nm lies at fractions 2/3, 1/3 of
    the 400 nm lattice and 1/3, 2/3 of the 200 nm one (t (1 - t) = 2/9 in both), so halving the
    spacing must cut the error 4 times (3-5 allowed for the O(s^3) rest); the lattice points are
    exchanged and mirrored ones (x < 0, then y < 0), so their signs are checked too."""
    offset = np.array([-6133.333333e-9, 1333.333333e-9])
    second = (0.3e-6 + offset[0], 0.2e-6 + offset[1], HEIGHT)  # one height: 7 solves a point (half turn)
    bodies = [Body(MESH, position=(0.3e-6, 0.2e-6, HEIGHT)), Body(MESH, position=second)]
    exact_heights = dict(reuse_tolerance=1e-12, reuse_interaction=1e-12, grand_mobility="pairs")
    hydro = solves(2, **exact_heights, pair_lateral=1e-12)
    direct = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
    errors = {}
    for base in (200e-9, 100e-9):  # lattices of 400 and 200 nm at this distance
        assert lateral_spacing(np.hypot(*offset), base, 2 * A) == 2 * base
        pairs = solves(2, **exact_heights, pair_lateral=base)
        interpolated = motion(*pairs._snapshot(bodies))
        errors[base] = max(relative_change(interpolated, direct))
    nearest = [Body(MESH, position=bodies[0].position),
               Body(MESH, position=bodies[0].position + np.append(np.round(offset / 200e-9) * 200e-9, 0.0))]
    # the rows kept from one assembly to the next change no number: another lattice square (the
    # nearest point, one of this square's corners), then this one again, bit for bit
    pairs._snapshot(nearest)
    assert all(np.array_equal(a, b) for a, b in zip(motion(*pairs._snapshot(bodies)), interpolated))
    snapped = max(relative_change(motion(Motion.of(hydro.mobility.solve(nearest)), hydro._grand_mobility(nearest)),
                                  direct))
    assert 3.0 < errors[200e-9] / errors[100e-9] < 5.0
    assert errors[100e-9] < snapped / 10  # the nearest point of the finer lattice, 67 nm away, errs 10x more


def patch(side, pitch=10e-6, seed=1):
    """side x side cells ``pitch`` apart at the rolling height, heights spread by +-20 nm."""
    rng = np.random.default_rng(seed)
    return [Body(MESH, position=(pitch * (i % side), pitch * (i // side), HEIGHT + rng.uniform(-20e-9, 20e-9)))
            for i in range(side * side)]


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_the_coarse_remainder_brings_the_pairs_of_a_patch_to_the_whole_system():
    """The pairs leave out the coupling through third cells; the coarse cells' whole system minus
    their pairs puts it back (many_body.py: M ~ M_pairs + [M_system(coarse) - M_pairs(coarse)]).
    On 2 x 2 cells five radii apart, against the whole system's direct solve on the same mesh,
    the pairs err by 8.9e-4 / 7.9e-4 (grand mobility / flow's motion) and with the remainder by
    5.6e-5 / 2.8e-5 (16 and 28 times less; the coarse cells with the constant density instead
    of the biquadratic one gave 8.7e-5 / 1.3e-4, 10 and 6 times). Every solve but the coarse one
    refined with contact ratio 1, as benchmarks/many_cells.py --refinement 1, to keep the test
    short; every pair from its snapshot (no far field: the diagonal pair is 7.07 radii apart)."""
    bodies = patch(2)
    hydro = solves(4, contact_refinement=1.0)
    direct = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
    pairs, corrected = (relative_change(motion(*solves(4, **EXACT, grand_mobility="pairs", contact_refinement=1.0,
                                                       far_field="none", many_body=mode)._snapshot(bodies)), direct)
                        for mode in ("none", "coarse"))
    assert pairs[1] > 5e-4  # the part the pairs leave out, which the check would miss
    assert corrected[0] < pairs[0] / 10 and corrected[1] < pairs[1] / 15


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_the_remainder_is_kept_on_its_lattice_relative_to_the_first_cell():
    """The remainder is a snapshot of the state snapped to many_body_lateral along the wall (and
    heights rounded up to 50 nm), keyed relative to the first cell: the patch moved as a whole, or
    one cell by less than half the lattice, takes the kept one (the same numbers, no solve); one
    cell moved by a lattice spacing solves a new one that differs."""
    hydro = solves(4, reuse_tolerance=2e-9, grand_mobility="pairs", many_body="coarse", many_body_lateral=1e-6)
    remainder = hydro.pairwise.remainder
    bodies = patch(2)
    first = remainder.parts(bodies)

    def moved(shifts):
        return [Body(MESH, position=b.position + np.append(s, 0.0)) for b, s in zip(bodies, shifts)]

    for shifts in ([(7e-6, -3e-6)] * 4, [(0.0, 0.0)] * 3 + [(0.3e-6, -0.3e-6)]):
        again = remainder.parts(moved(shifts))
        assert remainder.solved == 1
        for a, b in zip(again, first):
            np.testing.assert_array_equal(a, b)
    other = remainder.parts(moved([(0.0, 0.0)] * 3 + [(1e-6, 0.0)]))
    assert remainder.solved == 2
    assert np.abs(other[0] - first[0]).max() > 1e-3 * np.abs(first[0]).max()


def test_the_remainder_takes_the_constant_density_where_the_biquadratic_system_is_not_dense(monkeypatch):
    """The coarse cells' density is biquadratic (648 unknowns per k = 2 cell) while their whole
    system fits a dense matrix by "auto"'s rule (operators/forms.py), else the constant density
    with a warning (many_body.py): the biquadratic system of many cells would fall to the
    treecode, one product per load and per iteration for 6 n + 1 loads."""
    from warpbem.hydro.operators import forms

    options = dict(reuse_tolerance=2e-9, grand_mobility="pairs", many_body="coarse")
    assert solves(4, **options).pairwise.remainder.coarse.model.solver.density_order == 3
    monkeypatch.setattr(forms, "DENSE_MEMORY_SHARE", 1e-12)
    with pytest.warns(RuntimeWarning, match="does not fit a dense matrix on cpu; the remainder is taken with the"
                                            " constant density"):
        remainder = solves(4, **options).pairwise.remainder
    assert remainder.coarse.model.solver.density_order == 1


def test_the_many_body_remainder_needs_the_pairs():
    with pytest.raises(OptionError, match="many_body: 'coarse' corrects the pairs' grand mobility; it needs"):
        SolverOptions(reuse_tolerance=2e-9, many_body="coarse")


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
end = 0.003
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
@pytest.mark.parametrize("count, pitch, many_body", [((2, 1), (10e-6, 0.0), "none"), ((2, 1), (4.6e-6, 0.0), "none"),
                                                     ((4, 4), (10e-6, 10e-6), "none"),
                                                     ((3, 1), (10e-6, 0.0), "coarse"), ((3, 1), (4.6e-6, 0.0), "none")],
                         ids=["two cells", "two close cells", "a 4 x 4 patch", "three in a line with the remainder",
                              "three close cells"])
def test_a_resumed_run_of_cells_in_pairs_reproduces_the_uninterrupted_one(tmp_path, monkeypatch, count, pitch,
                                                                          many_body):
    """Adhesive cells on pair snapshots (two, two near contact, sixteen in a patch, three in a
    line with the many-body remainder, and three near contact, a close cluster): a run killed
    after 2 frames and resumed forms the same bonds and ends within 1e-9 radii of where the
    uninterrupted one ends (as one cell's, test_adhesion.py: its solves start GMRES from another
    previous solution); for two cells and the close cluster a second run with the same seed also
    repeats the first bit for bit (the pairs' part is a function of the state alone: the lattice
    points' snapshots and their weights, so which snapshots a run happens to keep changes no
    number; the remainder's likewise, many_body.py, and the cluster's, close_clusters.py)."""
    from warpbem.app import run

    path = tmp_path / "pairs.toml"
    scene = PAIRS_SCENE.replace("count = [2, 1]", f"count = [{count[0]}, {count[1]}]")
    if many_body != "none":
        scene = scene.replace('grand_mobility = "pairs"', f'grand_mobility = "pairs"\nmany_body = "{many_body}"')
    if pitch[0] < 3 * A:  # 0.6 um between the surfaces: a close pair (close_pairs.py), its film added
        scene = scene.replace("pitch = [10.0e-6, 0.0]", f"pitch = [{pitch[0]}, {pitch[1]}]")
    elif count != (2, 1):  # four or sixteen cells, each with pair snapshots of its nearest neighbours (the pairs 10 um
        # apart) on coarser lattices (2 um at 10 um, heights to 200 nm), the farther pairs from the far field
        scene = scene.replace("pitch = [10.0e-6, 0.0]", f"pitch = [{pitch[0]}, {pitch[1]}]").replace(
            'grand_mobility = "pairs"',
            'grand_mobility = "pairs"\npair_lateral = 2.0e-6\nnear_radius = 1.2e-5\nreuse_interaction = 2.0e-7')
    path.write_text(scene)
    from warpbem.dynamics.close_clusters import CloseClusters

    clusters_taken = []
    part = CloseClusters.part
    monkeypatch.setattr(CloseClusters, "part", lambda self, *a: clusters_taken.append(a) or part(self, *a))
    run.run(path, tmp_path / "straight.h5", progress=lambda line: None)
    assert bool(clusters_taken) == (count == (3, 1) and pitch[0] < 3 * A)  # three close cells are a cluster
    repeated = count == (2, 1) or pitch[0] < 3 * A  # the kept rows are tested bit for bit above
    if repeated:  # the same seed's rerun
        run.run(path, tmp_path / "again.h5", progress=lambda line: None)
    run_killed_after(2, path, tmp_path / "killed.h5")
    run.run(None, tmp_path / "killed.h5", resume=True, progress=lambda line: None)
    import h5py

    with h5py.File(tmp_path / "killed.h5") as f, h5py.File(tmp_path / "straight.h5") as g:
        assert f["time"].shape == g["time"].shape == (4,)
        assert g["position"].shape[1] == count[0] * count[1]
        bound = g["bond_count"][:].max(axis=0) > 0
        assert bound.sum() >= 0.75 * bound.size  # most cells bind: their kinetics are compared
        if repeated:
            with h5py.File(tmp_path / "again.h5") as h:
                for name in ("position", "velocity", "bond_receptor", "bond_count"):
                    np.testing.assert_array_equal(h[name][:], g[name][:])
        np.testing.assert_array_equal(f["bond_receptor"][:], g["bond_receptor"][:])
        # the resumed solves start GMRES from another previous solution (round-off apart)
        np.testing.assert_allclose(f["position"][:], g["position"][:], rtol=0, atol=1e-9 * A)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_sixteen_cells_step_alike_with_the_newton_step_solved_by_gmres(tmp_path, monkeypatch):
    """The 4 x 4 patch above with the implicit step's Newton step solved without its matrix
    (implicit.MobilityResponse, GMRES on (I + dt A Q) s = b; made to serve 96 coefficients by
    lowering STRUCTURED_FROM) and formed and factored (the default at 96): the same bonds, and
    positions within 1e-9 radii (GMRES's 1e-12 against the factor's round-off). At every state
    the response's motion D Q is the basis's own motion V to 1e-12 (the pairs' grand mobility is
    symmetric: V = D Q is what lets the Newton step skip its matrix)."""
    from warpbem.app import run
    from warpbem.dynamics import implicit
    from warpbem.dynamics.simulator import Simulator

    deviations = []
    evaluate = Simulator._implicit

    def checked(self, *args):
        hydro, found = evaluate(self, *args)
        if found is not None:
            response, basis = found.system.rate_response, hydro.basis
            motion = np.concatenate([basis.velocity, basis.angular_velocity], axis=2).reshape(len(basis.velocity), -1).T
            deviations.append(np.abs(response.motion - motion).max() / np.abs(motion).max())
        return hydro, found

    monkeypatch.setattr(Simulator, "_implicit", checked)

    path = tmp_path / "patch.toml"
    path.write_text(PAIRS_SCENE.replace("count = [2, 1]", "count = [4, 4]").replace(
        "pitch = [10.0e-6, 0.0]", "pitch = [10.0e-6, 10.0e-6]").replace(
        'grand_mobility = "pairs"',
        'grand_mobility = "pairs"\npair_lateral = 2.0e-6\npair_cutoff = 1.2e-5\nreuse_interaction = 2.0e-7'))
    run.run(path, tmp_path / "formed.h5", progress=lambda line: None)
    steps = []
    original = implicit.MobilityResponse.newton_step

    def counted(self, *args):
        step = original(self, *args)
        steps.append(step is not None)
        return step

    monkeypatch.setattr(implicit, "STRUCTURED_FROM", 0)
    monkeypatch.setattr(implicit.MobilityResponse, "newton_step", counted)
    run.run(path, tmp_path / "structured.h5", progress=lambda line: None)
    import h5py

    assert steps and all(steps)  # every Newton step of the second run came from GMRES
    assert deviations and max(deviations) < 1e-12
    with h5py.File(tmp_path / "structured.h5") as f, h5py.File(tmp_path / "formed.h5") as g:
        assert g["bond_count"][-1].sum() > 0
        np.testing.assert_array_equal(f["bond_receptor"][:], g["bond_receptor"][:])
        np.testing.assert_allclose(f["position"][:], g["position"][:], rtol=0, atol=1e-9 * A)


def test_on_pairs_the_operator_is_chosen_for_a_pair_not_the_whole_patch():
    """With grand_mobility = "pairs" no solve holds more than two cells (the whole system is never
    solved), so the operator's form is chosen for a pair: 400 cells of the k = 3 sphere (64 800
    unknowns, a 34 GB dense matrix) still solve their pair snapshots dense, as two cells do."""
    mesh = wb.mesh.sphere(5e-6, 3)
    pairs, system = (Model([mesh] * 400, [False] * 400, Flow(100.0, 1e-3), solver=SolverOptions(grand_mobility=mode))
                     for mode in ("pairs", "system"))
    assert pairs.unknowns == 2 * 3 * len(mesh.elements) and system.unknowns == 400 * 3 * len(mesh.elements)
    assert build_solver(pairs.solver, pairs.flow, "cpu", unknowns=pairs.unknowns).mode == "dense"
    assert build_solver(system.solver, system.flow, "cpu", unknowns=system.unknowns).mode != "dense"
