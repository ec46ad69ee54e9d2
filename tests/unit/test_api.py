"""The Python API builds and runs the same model as a scene file: one model builder (the
``Model``'s context defaults), one run function (``warpbem.run``: the same frames, HDF5 writer,
progress lines, resume and summary line for a script and for ``warpbem run``)."""

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import warpbem as wb
from warpbem.app.io import RunFileError
from warpbem.hydro.options import BONDS_REUSE_TOLERANCE
from warpbem.options import declared

SCENES = Path(__file__).resolve().parents[2] / "scenes"
ROLLING = SCENES / "fig4_09_11_soft_bonds.toml"
END, FRAMES = 2e-4, 1e-4  # s: two frames after the first (ten steps), bonds forming from the first steps
A = 5.0e-6  # m: the cell's radius
ON_RATE = 5000.0  # 1/s, for bonds within the ten steps (k dt = 0.1 at dt_max); the scene's 365 /s forms them later


def rolling_cell_in_python(end=END) -> wb.Scene:
    """scenes/fig4_09_11_soft_bonds.toml (Table 4.1, soft bonds) written with the public
    constructors, on the k = 2 sphere and with a faster on-rate (scene_file_cell gives both as
    overrides): every key the scene gives and nothing the scene leaves to its defaults."""
    cell = wb.mesh.sphere(radius=5.0e-6, subdivisions=2)
    bonds = wb.BondOptions(spring_constant=5.0e-4, equilibrium_length=30.0e-9, off_rate=2.4,
                           reactive_compliance=0.39e-10, on_rate=ON_RATE, receptor_density=20.0e12, temperature=310.0,
                           max_bonds=200, seed=1)
    model = wb.Model([cell], [False], wb.Flow(shear_rate=100.0, viscosity=1.0e-3, wall=True),
                     interactions=[wb.Gravity([1050.0], fluid_density=1000.0), wb.Repulsion(),
                                   wb.Adhesion(bonds, shear_modulus=[4.0e3], poisson_ratio=[0.33])],
                     policy=wb.StepPolicy(dt_max=2.0e-5, dt_min=1.0e-7, contact_gap=1.0e-9), scheme="euler",
                     names=["rolling cell"])
    return wb.Scene.of(model, [[0.0, 0.0, 5.24e-6]], end=end, frame_interval=FRAMES)


def scene_file_cell():
    return wb.load_scene(ROLLING, ["bodies.0.mesh.subdivisions=2", f"time.end={END!r}",
                                   f"time.frame_interval={FRAMES!r}", f"adhesion.on_rate={ON_RATE!r}"])


def frames(path) -> dict:
    with h5py.File(path, "r") as f:
        return {name: value[:] for name, value in f.items() if isinstance(value, h5py.Dataset)}


def test_a_script_and_a_scene_file_build_the_same_model():
    """The defaults that depend on what is switched on are resolved once, by the Model: with
    bonds the snapshot lattice (2e-9 m) and the bonds' layers from the repulsion's roughness."""
    python, toml = rolling_cell_in_python().model, scene_file_cell().model
    assert python.solver == toml.solver and python.solver.reuse_tolerance == BONDS_REUSE_TOLERANCE
    assert python.policy == toml.policy and python.flow == toml.flow and python.scheme == toml.scheme
    bonds = python.interaction("bond"), toml.interaction("bond")
    for name, _, _ in declared(wb.BondOptions):  # the parameters as the bond model reads them
        assert getattr(bonds[0], name) == getattr(bonds[1], name), name
    assert bonds[0].roughness == wb.Repulsion().cell_roughness and bonds[0].ligand_layer == wb.Repulsion().wall_roughness
    for mine, theirs in zip(bonds[0].per_body(python), bonds[1].per_body(toml)):
        assert np.array_equal(mine, theirs)
    # without bonds, every state is solved
    assert wb.Model(python.meshes, python.fixed).solver.reuse_tolerance == 0.0


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The rolling cell run from Python (its progress lines kept) and from its scene file."""
    folder, lines = tmp_path_factory.mktemp("runs"), []
    final = wb.run(rolling_cell_in_python(), folder / "python.h5", progress=lines.append)
    wb.run(scene_file_cell(), folder / "toml.h5", progress=None)
    return folder, lines, final


def test_the_same_rolling_cell_from_python_and_from_its_scene_file_gives_the_same_frames(runs):
    folder, lines, _ = runs
    python, toml = frames(folder / "python.h5"), frames(folder / "toml.h5")
    assert python.keys() == toml.keys() and len(python["time"]) == 3
    for name in python:
        assert np.array_equal(python[name], toml[name]), name
    assert python["bond_count"][-1, 0] > 0  # the run reached the bonds it compares
    # the same progress as the command line: a line per frame, then the summary
    assert len(lines) == 3 and lines[0].startswith(f"t = 0.0001 / 0.0002 s  steps {int(python['steps'][1])} ")
    assert lines[-1].startswith(f"done: {int(python['steps'][-1])} steps, t = 0 -> 0.0002 s simulated in")
    assert lines[-1].endswith(f"; 3 frames in {folder / 'python.h5'}")


def test_a_script_resumes_its_run_and_is_told_when_it_is_finished(runs, tmp_path):
    """A resumed run continues the uninterrupted one; its snapshots are solved afresh (the
    GMRES start differs), so it repeats it to round-off, not bit for bit."""
    folder, _, whole = runs
    out = tmp_path / "run.h5"
    wb.run(rolling_cell_in_python(end=FRAMES), out, progress=None)
    resumed = wb.run(rolling_cell_in_python(), out, resume=True, progress=None)
    assert resumed.time == whole.time and resumed.steps == whole.steps
    np.testing.assert_allclose(resumed.positions, whole.positions, rtol=0, atol=1e-9 * A)
    np.testing.assert_array_equal(frames(out)["bond_count"], frames(folder / "python.h5")["bond_count"])
    lines = []
    wb.run(rolling_cell_in_python(), out, resume=True, progress=lines.append)
    assert lines == [f"{out}: finished already (t = 0.0002 s = time.end); nothing to run. To run it on, resume"
                     " with a later end (--set time.end=...)"]
    # the file is the script's: the command line cannot rebuild its model, another scene may not resume it
    with pytest.raises(RunFileError, match=r"was run from a Python script .* warpbem.run\(scene, output, resume=True\)"):
        wb.run(None, out, resume=True)
    with pytest.raises(RunFileError, match="holds a run of another scene than the one given"):
        wb.run(scene_file_cell(), out, resume=True)


def test_an_output_without_a_frame_points_to_overwrite(runs, tmp_path):
    out = tmp_path / "run.h5"
    shutil.copy(runs[0] / "python.h5", out)
    with h5py.File(out, "a") as f:  # as if stopped before its first frame was complete
        f["time"].resize(0, axis=0)
    with pytest.raises(RunFileError, match=r"stopped before its first frame.* --overwrite \(Python: overwrite=True\)"):
        wb.run(rolling_cell_in_python(), out, resume=True)
    with pytest.raises(wb.SceneError, match=r"exists: --resume continues it, --overwrite replaces it"):
        wb.run(rolling_cell_in_python(), out)


def test_scene_of_checks_what_a_scene_file_checks():
    cell = wb.mesh.sphere(radius=5.0e-6, subdivisions=1)
    model = wb.Model([cell, cell], [False, True], names=["free", "adherent"])
    with pytest.raises(ValueError, match=r"positions: expected \(2, 3\)"):
        wb.Scene.of(model, [[0.0, 0.0, 6e-6]], end=1e-3)
    with pytest.raises(wb.PlacementError):
        wb.Scene.of(model, [[0.0, 0.0, 6e-6], [1e-6, 0.0, 6e-6]], end=1e-3)
    with pytest.raises(ValueError, match="frame_interval: give frames by steps"):
        wb.Scene.of(model, [[0.0, 0.0, 6e-6], [0.0, 20e-6, 6e-6]], end=1e-3, frame_every=2, frame_interval=1e-4)
    with pytest.raises(ValueError, match="overrides change a scene file"):
        wb.run(wb.Scene.of(model, [[0.0, 0.0, 6e-6], [0.0, 20e-6, 6e-6]], end=1e-3), "x.h5", ["time.end=1"])


def test_the_bond_kinetics_bound_on_the_step_holds_for_a_script_too():
    """k dt <= kinetics_fraction at dt_min (thesis ch. 4: the step follows the kinetics): the
    Model checks it, so a script is refused as a scene file is."""
    scene = rolling_cell_in_python()
    with pytest.raises(ValueError, match=r"dt_min: 0.001 s is too long for the bond kinetics \(on_rate"):
        wb.Model(scene.model.meshes, scene.model.fixed, scene.model.flow, scene.model.interactions,
                 policy=wb.StepPolicy(dt_max=1e-3, dt_min=1e-3))


def test_a_scripts_run_file_draws_its_bodies_as_a_scene_files_does(runs):
    """The run file holds its meshes (each distinct one once), so plot, animate and xdmf read a
    script's run, whose model no scene table rebuilds, as they read a scene file's."""
    from warpbem.app.io import open_result, read_meshes
    from warpbem.app.xdmf import read_frames

    folder = runs[0]
    cell = rolling_cell_in_python().model.meshes[0]
    for name in ("python.h5", "toml.h5"):
        meshes, time, positions, _, _ = read_frames(folder / name)
        assert len(meshes) == 1 and np.array_equal(meshes[0].nodes, cell.nodes)
        assert np.array_equal(meshes[0].elements, cell.elements) and positions.shape == (3, 1, 3)
    with open_result(folder / "python.h5") as f:
        assert "meshes" in f and read_meshes(f)[0].n_elements == 24


def test_a_scripts_scene_names_its_bodies_in_errors():
    cell = wb.mesh.sphere(radius=5.0e-6, subdivisions=1)
    model = wb.Model([cell, cell], [False, True], names=["free cell", "dome"])
    with pytest.raises(wb.PlacementError, match="'free cell' and 'dome'"):
        wb.Scene.of(model, [[0.0, 0.0, 6e-6], [1e-6, 0.0, 6e-6]], end=1e-3)
