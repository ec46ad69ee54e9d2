"""The near-far split of frozen adherent arrays (warpbem/hydro/frozen.py): exact when every
adherent cell is near, an error that falls with the cut-off, the background flow by the tree
against the direct sum and against the no-slip condition, and its checks."""

import warnings

import h5py
import numpy as np
import pytest

import warpbem as wb
from warpbem.hydro.frozen import FrozenArraySolver
from warpbem.hydro.treecode import TreecodeOptions
from warpbem.surfaces.quad9 import CENTRE_NODE

SHEAR, VISCOSITY = 1.0, 1.0


def adherent_grid(side, pitch=3.0, height=1.2, refinement=2):
    sphere = wb.mesh.sphere(1.0, refinement)
    return [wb.Body(sphere, position=(pitch * (i % side), pitch * (i // side), height), fixed=True)
            for i in range(side * side)]


def solver():
    # no contact refinement: the near systems then hold exactly the full system's elements
    return wb.MobilitySolver(SHEAR, VISCOSITY, options=wb.SolverOptions(density_order=1, contact_refinement=0))


@pytest.fixture(scope="module")
def scene_4x4():
    """A free sphere pulled along and down between the cells of a 4 x 4 adherent array, and the
    full solve of it (every body in one system)."""
    bodies = [wb.Body(wb.mesh.sphere(1.0, 2), position=(4.5, 3.1, 3.0))] + adherent_grid(4)
    forces = np.zeros((len(bodies), 3))
    forces[0] = [0.1, 0.0, -0.3]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        return bodies, forces, solver().solve(bodies, forces=forces)


def relative(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def test_the_split_with_every_adherent_cell_near_is_the_full_solve(scene_4x4):
    """With the cut-off past the array, dq is solved for every adherent cell: q = q0 + dq is the
    full system's solution (frozen.py, exact by linearity), so motion and holding loads agree to
    the GMRES tolerance."""
    bodies, forces, full = scene_4x4
    split = FrozenArraySolver(solver(), cutoff=1e3)
    sol = split.solve(bodies, forces=forces)
    assert len(split.near_bodies) == 16
    assert relative(sol.velocity[0], full.velocity[0]) < 1e-6
    assert relative(sol.angular_velocity[0], full.angular_velocity[0]) < 1e-6
    assert np.abs(sol.force[1:] - full.force[1:]).max() < 1e-6 * np.abs(full.force[1:]).max()
    assert np.abs(sol.torque[1:] - full.torque[1:]).max() < 1e-6 * np.abs(full.torque[1:]).max()


def test_the_error_of_the_split_falls_as_the_cut_off_grows(scene_4x4):
    """Far cells that do not answer the free cell's disturbance: the error of the free cell's
    velocity falls as more cells are near, from O(1e-1) with none (the free cell in the
    background flow alone) to below 1e-3 with the cells within 4 radii."""
    bodies, forces, full = scene_4x4
    split = FrozenArraySolver(solver(), cutoff=0.0)
    errors, counts = [], []
    for cutoff in (0.0, 1.0, 4.0):
        split.cutoff = cutoff
        errors.append(relative(split.solve(bodies, forces=forces).velocity[0], full.velocity[0]))
        counts.append(len(split.near_bodies))
    assert counts[0] == 0 and counts[0] < counts[1] < counts[2] < 16
    assert errors[0] > 1e-2 and errors[0] > errors[1] > errors[2] and errors[2] < 1e-3


def test_far_cells_keep_their_background_loads_and_solves_of_loads_alone_give_them_none(scene_4x4):
    bodies, forces, unused = scene_4x4
    split = FrozenArraySolver(solver(), cutoff=0.5)
    sol = split.solve(bodies, forces=forces)
    field = split.background_field
    far = [i for i in range(1, len(bodies)) if i not in split.near_bodies]
    np.testing.assert_array_equal(sol.force[far], field.force[np.array(far) - 1])
    loads_alone = split.solve(bodies, forces=forces, background=False)
    np.testing.assert_array_equal(loads_alone.force[far], 0.0)
    assert np.all(loads_alone.reused_bodies[far])


def test_solves_of_several_loads_give_the_background_then_each_load_alone(scene_4x4):
    """FrozenArraySolver.solve_loads, which the snapshots of bonded scenes call
    (dynamics/hydrodynamics.py): the background's motion first, then each load's alone, as
    solve gives them one by one."""
    bodies, forces, unused = scene_4x4
    split = FrozenArraySolver(solver(), cutoff=0.5)
    background, alone = split.solve_loads(bodies, [forces], [np.zeros_like(forces)], with_background=True)
    for got, expected in ((background, split.solve(bodies)), (alone, split.solve(bodies, forces=forces,
                                                                                  background=False))):
        np.testing.assert_allclose(got.velocity, expected.velocity, rtol=0, atol=1e-7 * np.abs(expected.velocity).max())


@pytest.fixture(scope="module")
def background_8x8():
    """The background flow of 8 x 8 adherent spheres: a tree with a far field."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        return _background_8x8()


def _background_8x8():
    bodies = adherent_grid(8, height=1.5)
    split = FrozenArraySolver(solver(), cutoff=1.0, treecode=TreecodeOptions(tolerance=1e-6), tree_elements=0)
    free = wb.Body(wb.mesh.sphere(1.0, 2), position=(10.5, 10.5, 2.8))
    split.solve([free] + bodies)
    return bodies, split.background_field


def test_background_flow_by_the_tree_matches_the_direct_sum(background_8x8):
    """Interpolated far field plus the exact near field of each point's leaf (treecode.py)
    against the double layer and completions of the same density summed over every element:
    the error over all points within the tree's tolerance (1e-6) of the disturbance, as for a
    product (docs/benchmarks.md, "Large arrays"), and at the worst point within a few times it (the point
    forces' share of the far field is larger, treecode.py)."""
    bodies, field = background_8x8
    assert field.far.has_far_field
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-2, 23, 300), rng.uniform(-2, 23, 300), rng.uniform(2.6, 4.5, 300)])
    tree = field.velocity(points)
    disturbance = field.operator.field_at(points / field.length, field.density, field.pole_forces) * field.speed
    direct = disturbance.copy()
    direct[:, 0] += SHEAR * points[:, 2]
    assert np.linalg.norm(tree - direct) < 1e-6 * np.linalg.norm(disturbance)
    assert np.abs(tree - direct).max() < 5e-6 * np.abs(disturbance).max()
    assert np.abs(disturbance).max() > 0.1 * SHEAR  # the array disturbs the flow: a test with teeth


def test_points_beyond_the_tree_are_summed_directly_with_a_warning(background_8x8):
    bodies, field = background_8x8
    outside = np.array([[60.0, 10.0, 3.0], [10.0, 10.0, 9.0]])
    assert not field.far.covers(outside / field.length).any()
    with pytest.warns(UserWarning, match="summed directly"):
        u = field.velocity(outside)
    direct = field.operator.field_at(outside / field.length, field.density, field.pole_forces) * field.speed
    direct[:, 0] += SHEAR * outside[:, 2]
    np.testing.assert_allclose(u, direct, rtol=1e-12)


def test_background_flow_vanishes_on_the_adherent_cells(background_8x8):
    """No slip: u_inf + w0 = 0 on every adherent surface (the background's boundary condition,
    thesis eq. 2.5), so off a cell's element centres along the normal the flow grows linearly
    with the distance d (its slope the wall shear rate there), and its linear extrapolation to
    d = 0 is a discretisation error, small against the shear flow at the cell (a corner cell
    and an inner one)."""
    bodies, field = background_8x8
    for cell in (bodies[0], bodies[27]):
        centres = cell.world_nodes()[cell.mesh.elements][:, CENTRE_NODE]
        normals = (centres - cell.position) / np.linalg.norm(centres - cell.position, axis=1)[:, None]
        near, farther = (field.velocity(centres + d * normals) for d in (0.01, 0.02))
        assert np.abs(farther).max() > 0.04  # the flow about the cell is not zero,
        np.testing.assert_allclose(np.abs(near).max(), 0.5 * np.abs(farther).max(), rtol=0.05)  # but linear in d
        assert np.abs(2.0 * near - farther).max() < 1e-2 * SHEAR * centres[:, 2].max()


def test_the_split_refuses_moving_adherent_cells_and_changed_arrays(scene_4x4):
    bodies, forces, unused = scene_4x4
    with pytest.raises(ValueError, match="cutoff"):
        FrozenArraySolver(solver(), cutoff=-1.0)
    moving = list(bodies)
    moving[3] = wb.Body(bodies[3].mesh, position=bodies[3].position, fixed=True, velocity=(1.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="at rest"):
        FrozenArraySolver(solver(), cutoff=1.0).solve(moving)
    split = FrozenArraySolver(solver(), cutoff=1.0)
    split.solve(bodies, forces=forces)
    shifted = list(bodies)
    shifted[5] = wb.Body(bodies[5].mesh, position=bodies[5].position + 0.1, fixed=True)
    with pytest.raises(ValueError, match="same places"):
        split.solve(shifted)
    held = forces.copy()
    held[2] = [1.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="fixed"):
        split.solve(bodies, forces=held)


def test_a_run_with_the_split_steps_as_the_full_one_when_every_cell_is_near():
    """The split plugged into the time step (SolverOptions.near_far_split): with every
    adherent cell near, two Heun steps of a sedimenting cell in shear past a 2 x 2 array, its
    repulsion from the wall implicit, land where those of the full solve land."""
    from warpbem.dynamics import Flow, Model, Simulator, SolverOptions, StepPolicy
    from warpbem.forces import STANDARD_GRAVITY, Gravity, Repulsion

    cell = wb.mesh.sphere(5e-6, 2)
    fixed = [False] + [True] * 4
    positions = [[-12e-6, 7.5e-6, 5.3e-6]] + [[15e-6 * i, 15e-6 * j, 6e-6] for i in range(2) for j in range(2)]
    ends = {}
    for split in ("off", "on"):
        options = SolverOptions(contact_refinement=0.0, near_far_split=split, near_far_cutoff=1e-3)
        model = Model([cell] * 5, fixed, Flow(100.0, 1.2e-3),
                      interactions=[Gravity([1050.0] * 5, 1000.0, STANDARD_GRAVITY), Repulsion()],
                      solver=options, policy=StepPolicy(2e-3, 1e-6, 5e-7))
        sim = Simulator(model)
        state = model.initial_state(positions)
        for _ in range(2):
            state, frame = sim.step(state)
        ends[split] = (state.positions[0] - positions[0], frame.force[1:])
    assert ("near-far" in sim.mobility.operator_description)
    moved, held = ends["off"]
    np.testing.assert_allclose(ends["on"][0], moved, rtol=0, atol=1e-6 * np.abs(moved).max())
    np.testing.assert_allclose(ends["on"][1], held, rtol=0, atol=1e-6 * np.abs(held).max())


def test_the_split_switches_itself_on_from_the_threshold_and_is_reported(tmp_path):
    """near_far_split = "auto" takes the split for models with NEAR_FAR_FIXED_CELLS fixed cells
    and more, not below; "off" and "on" override it; a run reports it in its progress line and
    its HDF5 attributes."""
    from warpbem.app import run
    from warpbem.dynamics.model import build_solver
    from warpbem.hydro.options import NEAR_FAR_FIXED_CELLS, Flow, SolverOptions

    flow = Flow(100.0, 1.2e-3)
    auto = SolverOptions()
    assert isinstance(build_solver(auto, flow, "cpu", NEAR_FAR_FIXED_CELLS), FrozenArraySolver)
    assert not isinstance(build_solver(auto, flow, "cpu", NEAR_FAR_FIXED_CELLS - 1), FrozenArraySolver)
    assert not isinstance(build_solver(SolverOptions(near_far_split="off"), flow, "cpu", 10**4), FrozenArraySolver)
    assert isinstance(build_solver(SolverOptions(near_far_split="on"), flow, "cpu", 1), FrozenArraySolver)
    side = int(np.ceil(np.sqrt(NEAR_FAR_FIXED_CELLS)))
    scene = tmp_path / "array.toml"
    scene.write_text(f"""
[flow]
shear_rate = 100.0
[time]
end = 1e-4
dt_max = 1e-4
[solver]
contact_refinement = 0.0
[[bodies]]
position = [-20e-6, 5e-6, 8e-6]
mesh = {{ shape = "sphere", radius = 5e-6, subdivisions = 1 }}
[[arrays]]
count = [{side}, {side}]
pitch = [30e-6, 30e-6]
origin = [0.0, 0.0, 6e-6]
fixed = true
mesh = {{ shape = "sphere", radius = 5e-6, subdivisions = 1 }}
""")
    lines = []
    run.run(scene, tmp_path / "array.h5", progress=lines.append)
    assert any("near-far 40 um" in line for line in lines)
    with h5py.File(tmp_path / "array.h5", "r") as f:
        assert f.attrs["near_far_split"] == f"on (auto: {side * side} fixed cells)"
        assert "near-far 40 um" in f.attrs["operator"]
