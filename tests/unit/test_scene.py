"""Scene files: validation messages name the field; runs write flushed frames and resume."""

import json

import h5py
import numpy as np
import pytest

from warpbem import mesh
from warpbem.app import run, scene
from tests.interrupted import run_killed_after
from tests.scene_points import sweep_scenes

BASE = {
    "flow": {"shear_rate": 0.0, "viscosity": 1e-3},
    "physics": {"gravity": True},
    "time": {"end": 0.6, "dt_max": 0.2, "dt_min": 0.05, "contact_gap": 1e-6},
    "bodies": [{"position": [0.0, 0.0, 8e-6], "density": 1050.0,
                "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 2}}],
}


def write(tmp_path, table):
    lines = []

    def emit(prefix, value):
        return f"{prefix} = {json.dumps(value)}"

    for key in ("flow", "physics", "repulsion", "time", "solver"):
        if key in table:
            lines.append(f"[{key}]")
            lines += [emit(k, v) for k, v in table[key].items()]
    for entry, body in [("bodies", b) for b in table.get("bodies", [])] + [("arrays", a) for a in table.get("arrays", [])]:
        lines.append(f"[[{entry}]]")
        for k, v in body.items():
            if isinstance(v, dict):
                lines.append(f"{k} = {{ " + ", ".join(emit(a, b) for a, b in v.items()) + " }")
            else:
                lines.append(emit(k, v))
    path = tmp_path / "scene.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


ARRAY = {"name": "dome", "count": [3, 2], "pitch": [20e-6, 25e-6], "origin": [30e-6, -10e-6, 6e-6], "fixed": True,
         "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 2}}


def test_arrays_expand_into_named_bodies_on_their_grid_sharing_one_mesh(tmp_path):
    """[[arrays]]: count[0] x count[1] bodies at origin + (i pitch_x, j pitch_y, 0), after the
    [[bodies]], named "<name> i j", with the array's body keys, one mesh for all."""
    loaded = scene.load(write(tmp_path, dict(BASE, arrays=[ARRAY], solver={"near_far_cutoff": 3e-5})))
    members = loaded.bodies[1:]
    assert [b.name for b in members] == [f"dome {i} {j}" for i in range(3) for j in range(2)]
    np.testing.assert_allclose([b.position for b in members],
                               [(30e-6 + 20e-6 * i, -10e-6 + 25e-6 * j, 6e-6) for i in range(3) for j in range(2)])
    assert all(b.fixed for b in members) and not loaded.bodies[0].fixed
    assert all(b.mesh is members[0].mesh for b in members)
    assert loaded.model.solver.near_far_cutoff == 3e-5


@pytest.mark.parametrize("change, message", [
    (lambda a: a.update(count=[0, 2]), r"arrays.0.count\[0\]: 0 is outside the allowed range"),
    (lambda a: a.update(count=4), r"arrays.0.count: expected a list of 2 integers"),
    (lambda a: a.update(position=[0.0, 0.0, 1e-5]), r"arrays.0: unknown key 'position'"),
    (lambda a: a.pop("pitch"), r"arrays.0: missing required key 'pitch'"),
    (lambda a: a.update(pitch=[5e-6, 25e-6]), r"initial placement: bodies 'dome 0 0' and 'dome 1 0' overlap"),
])
def test_bad_arrays_name_the_field(tmp_path, change, message):
    array = json.loads(json.dumps(ARRAY))
    change(array)
    with pytest.raises(scene.SceneError, match=message):
        scene.load(write(tmp_path, dict(BASE, arrays=[array])))


@pytest.mark.parametrize("change, message", [
    (lambda t: t["flow"].update(shear_rat=1.0), r"flow: unknown key 'shear_rat'"),
    (lambda t: t["time"].pop("end"), r"time: missing required key 'end'"),
    (lambda t: t["flow"].update(viscosity=-1.0), r"flow.viscosity: -1 is outside the allowed range \(0, 1000\]"),
    (lambda t: t["bodies"][0]["mesh"].update(shape="cube"), r"bodies.0.mesh.shape: 'cube' is not one of"),
    (lambda t: t["bodies"][0].update(position=[0.0, 1.0]), r"bodies.0.position: expected a list of 3 numbers"),
    (lambda t: t["time"].update(dt_min=1.0), r"time.dt_min: 1 is outside the allowed range"),
    (lambda t: t["bodies"][0]["mesh"].update(shape="file", path="missing.q9"), r"bodies.0.mesh.path: .*cannot read"),
    (lambda t: t["bodies"].append(dict(t["bodies"][0], position=[1e-6, 0.0, 8e-6])), r"initial placement: bodies 0 and 1 overlap"),
    (lambda t: t.update(repulsion={"tau": 1.0}), r"repulsion: unknown key 'tau'"),
    (lambda t: t.update(repulsion={"cell_roughness": -1e-9}), r"repulsion.cell_roughness: -1e-09 is outside"),
    (lambda t: t["bodies"][0].update(force=[0.0, 1e-12]), r"bodies.0.force: expected a list of 3 numbers"),
    # 200 nm above the wall is inside the 175 + 50 nm roughness layers: eq. 3.1 has no value there
    (lambda t: (t["physics"].update(repulsion=True), t["bodies"][0].update(position=[0.0, 0.0, 5.2e-6])),
     r"bodies.0.position: its roughness layer touches that of the wall"),
    (lambda t: (t["physics"].update(repulsion=True), t["bodies"][0].update(name="free cell"),
                t["bodies"].append(dict(t["bodies"][0], name="dome", position=[10.1e-6, 0.0, 8e-6]))),
     r"bodies.0.position \('free cell'\): its roughness layer touches that of bodies.1 \('dome'\)"),
])
def test_bad_scenes_name_the_field(tmp_path, change, message):
    table = json.loads(json.dumps(BASE))
    change(table)
    with pytest.raises(scene.SceneError, match=message):
        scene.load(write(tmp_path, table))


@pytest.mark.parametrize("change, message", [
    (lambda t: t["bodies"][0].update(position=[0.0, 0.0, 6.0]),
     r"bodies.0.position\[2\]: 6 m is over the plausible 0.01 m; lengths are in metres \(6 um is 6e-06 m\)"),
    (lambda t: t["bodies"][0]["mesh"].update(radius=5.0), r"bodies.0.mesh.radius: 5 m is over the plausible 0.001 m"),
    (lambda t: t["bodies"][0]["mesh"].update(radius=5e-12), r"bodies.0.mesh.radius: 5e-12 m is under the plausible 1e-08"),
    (lambda t: t["flow"].update(viscosity=1.2),
     r"flow.viscosity: 1.2 Pa s is over the plausible 0.1 Pa s; viscosities are in Pa s \(1.2 cP is 0.0012 Pa s\)"),
    (lambda t: t["flow"].update(shear_rate=-2e5), r"flow.shear_rate: -200000 1/s is over the plausible magnitude 100000"),
    (lambda t: t["bodies"][0].update(force=[0.0, 0.0, -10.0]), r"bodies.0.force\[2\]: -10 N is over the plausible"
                                                                 r" magnitude 1e-06 N; forces are in newtons \(-10 pN"),
])
def test_implausible_magnitudes_are_refused_with_their_unit_unless_the_scene_allows_any_scale(change, message):
    """A value typed in another unit (6 meaning 6 um is 6 m) is refused naming the field, the
    bound (warpbem/units.py) and the unit; with any_scale = true the same scene is read as given."""
    table = json.loads(json.dumps(BASE))
    change(table)
    with pytest.raises(scene.SceneError, match=message + ".*; a scene meaning it says any_scale = true"):
        scene.parse(table)
    read, given = scene.parse(dict(table, any_scale=True)), table["bodies"][0]
    assert (read.model.flow.shear_rate, read.model.flow.viscosity) == (table["flow"]["shear_rate"],
                                                                       table["flow"]["viscosity"])
    body = read.bodies[0]
    assert body.position == tuple(given["position"]) and body.force == tuple(given.get("force", (0.0, 0.0, 0.0)))
    assert body.mesh.size() == pytest.approx(given["mesh"]["radius"], rel=1e-12)


def test_a_mesh_file_in_micrometres_is_refused(tmp_path):
    table = json.loads(json.dumps(BASE))
    mesh.save(mesh.sphere(5.0, subdivisions=1), tmp_path / "cell_um.q9")
    table["bodies"][0]["mesh"] = {"shape": "file", "path": "cell_um.q9"}
    with pytest.raises(scene.SceneError, match=r"bodies.0.mesh.path: its size 5 m is over the plausible 0.001 m"):
        scene.load(write(tmp_path, table))
    with pytest.raises(scene.SceneError, match=r"any_scale: expected true or false, got 'yes'"):
        scene.parse(dict(table, any_scale="yes"), tmp_path)


def test_overrides_and_mesh_files(tmp_path):
    table = json.loads(json.dumps(BASE))
    mesh.save(mesh.spheroid(5e-6, 0.7, subdivisions=2), tmp_path / "cell.q9")
    table["bodies"][0]["mesh"] = {"shape": "file", "path": "cell.q9"}
    s = scene.load(write(tmp_path, table), ["flow.shear_rate=80", "bodies.0.position=[0.0, 2e-6, 9e-6]"])
    assert s.model.flow.shear_rate == 80.0 and s.bodies[0].position == (0.0, 2e-6, 9e-6)
    assert s.bodies[0].mesh.n_elements == 24
    with pytest.raises(scene.SceneError, match="expected key=value"):
        scene.load(write(tmp_path, table), ["flow.shear_rate"])


def test_interrupted_run_resumes_to_the_same_end(tmp_path):
    path = write(tmp_path, BASE)
    straight = run.run(path, tmp_path / "straight.h5", progress=lambda line: None)
    run_killed_after(2, path, tmp_path / "resumed.h5")
    with h5py.File(tmp_path / "resumed.h5") as f:
        assert f["time"].shape[0] == 3  # frame 0 and the two frames written before the interruption
    resumed = run.run(None, tmp_path / "resumed.h5", resume=True, progress=lambda line: None)
    np.testing.assert_allclose(resumed.positions, straight.positions, rtol=0, atol=1e-6 * 5e-6)
    with h5py.File(tmp_path / "resumed.h5") as f, h5py.File(tmp_path / "straight.h5") as g:
        np.testing.assert_allclose(f["time"][:], g["time"][:])
        assert f["position"].attrs["unit"] == "m" and json.loads(f.attrs["scene"])["flow"]["viscosity"] == 1e-3
        assert np.all(np.diff(f["position"][:, 0, 2]) < 0)  # the heavy cell sinks


def test_cli_run_reports_bad_scenes_and_runs_good_ones(tmp_path, capsys):
    from warpbem.app import cli

    path = write(tmp_path, BASE)
    assert cli.main(["run", str(path), "--output", str(tmp_path / "bad.h5"), "--set", "flow.viscosty=1"]) == 2
    assert "flow: unknown key 'viscosty'" in capsys.readouterr().err
    assert not (tmp_path / "bad.h5").exists()  # nothing written before the scene is valid
    assert cli.main(["run", str(path), "--output", str(tmp_path / "good.h5")]) == 0
    with h5py.File(tmp_path / "good.h5") as f:
        assert f["time"][0] == 0.0 and f["time"][-1] == pytest.approx(0.6) and f["force"].shape[1:] == (1, 3)
    assert cli.main(["plot", str(tmp_path / "good.h5")]) == 0
    assert (tmp_path / "good.png").stat().st_size > 10_000
    # an earlier run is never replaced by mistake
    frames = h5py.File(tmp_path / "good.h5", "r")["time"].shape
    assert cli.main(["run", str(path), "--output", str(tmp_path / "good.h5"), "--set", "time.end=0.2"]) == 2
    assert "exists: --resume continues it, --overwrite replaces it" in capsys.readouterr().err
    assert h5py.File(tmp_path / "good.h5", "r")["time"].shape == frames
    assert cli.main(["run", str(path), "--output", str(tmp_path / "good.h5"), "--set", "time.end=0.2", "--overwrite"]) == 0
    assert h5py.File(tmp_path / "good.h5", "r")["time"][-1] == pytest.approx(0.2)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")  # the adherent cell, as in the README
def test_demo_writes_units_and_metadata_and_a_chart(tmp_path):
    """The main job on two positions: HDF5 with units, scene, versions and seed, and its PNG."""
    from warpbem.app import cli

    out = tmp_path / "demo.h5"
    assert cli.main(["demo", "--output", str(out), "--positions", "2"]) == 0
    with h5py.File(out) as f:
        assert f["free_velocity"].shape == (2, 3) and f["free_velocity"].attrs["unit"] == "m/s"
        assert f["adherent_force"].attrs["unit"] == "N"
        assert json.loads(f.attrs["versions"])["warpbem"] == "0.1.0" and f.attrs["seed"]
        assert json.loads(f.attrs["scene"])["shear_rate"] == 100.0
        # symmetric pass: the lateral velocity at x = -30 um mirrors the one at +30 um
        v = f["free_velocity"][:, 1]
        assert v[0] > 0 and np.isclose(v[0], -v[1], rtol=1e-6)
    assert (tmp_path / "demo.png").stat().st_size > 10_000


def test_sweep_runs_the_grid_and_summarises(tmp_path):
    """Two viscosities x two heights: four files and a summary. Settling speed goes as 1/mu:
    doubling the viscosity halves the height lost (within the wall correction's change)."""
    from warpbem.app import sweep

    assert sweep.split_values("1,[2,3],4") == ["1", "[2,3]", "4"]
    with pytest.raises(scene.SceneError, match="cannot split"):
        sweep.split_values("1,[2,3")
    path = write(tmp_path, BASE)
    with pytest.raises(scene.SceneError, match="flow.viscosity"):  # every point checked before work
        sweep.sweep(path, ["flow.viscosity=1e-3,-1"], tmp_path / "bad")
    summary = sweep.sweep(path, ["flow.viscosity=1e-3,2e-3", "bodies.0.position=[0,0,8e-6],[0,0,9e-6]"],
                          tmp_path / "grid", progress=lambda line: None)
    import csv

    rows = list(csv.DictReader(summary.open()))
    assert len(rows) == 4 and all((tmp_path / "grid" / f"point{i:03d}.h5").exists() for i in range(4))
    dz = {(r["flow.viscosity"], r["bodies.0.position"]): float(r["body0_dz_m"]) for r in rows}
    ratio = dz[("2e-3", "[0,0,9e-6]")] / dz[("1e-3", "[0,0,9e-6]")]
    assert 0.45 < ratio < 0.55


def test_sweep_in_worker_processes_matches_serial(tmp_path):
    from warpbem.app import sweep

    path = write(tmp_path, BASE)
    varies = ["flow.viscosity=1e-3,2e-3"]
    serial = sweep.sweep(path, varies, tmp_path / "serial", progress=lambda line: None)
    parallel = sweep.sweep(path, varies, tmp_path / "parallel", workers=2, progress=lambda line: None)
    import csv

    a = [float(r["body0_dz_m"]) for r in csv.DictReader(serial.open())]
    b = [float(r["body0_dz_m"]) for r in csv.DictReader(parallel.open())]
    # equal to round-off: a worker's BLAS may sum the preconditioner's LU in another order
    assert b == pytest.approx(a, rel=1e-9) and a[0] < 0 and len(a) == 2


def test_every_shipped_scene_is_valid():
    from pathlib import Path

    folder = Path(__file__).resolve().parents[2] / "scenes"
    files = sorted(folder.glob("*.toml"))
    assert len(files) >= 14
    from warpbem.app.sweep import grid

    for path in files:
        s = scene.load(path)
        assert s.end > 0 and len(s.bodies) >= 1
        for _, overrides in grid([], s.sweep):  # every case of the scene's sweep axes
            scene.load(path, overrides)


# thesis ch. 5.3: (scene, free cell start x, z in um, glances in um, adherent centre heights in um)
THESIS_CASES = [
    ("fig5_03_sphere_glance", -9, 13, [2, 3.5, 5, 6.5], {5.25}),
    ("fig5_04_05_shapes", -9, 13, [2, 3.5], {5.25, 4.5, 3.25}),
    ("fig5_07_dome_glance", -9, 12.25, [3.5, 5, 6.5], {4.5}),
    ("fig5_09_box_glance", -9, 11, [3.5, 5, 6.5], {3.25}),
    ("fig5_11_two_domes", -9, 12.25, [3.5, 6.5], {4.5}),
    ("fig5_12_two_boxes", -9, 11, [3.5, 6.5], {3.25}),
    ("fig5_19_20_glance", -9, 6, [15, 25], {5.25, 4.5, 3.25}),
]


@pytest.mark.parametrize("name, x, z, glances, heights", THESIS_CASES)
def test_thesis_scenes_place_the_cells_as_the_thesis_does(name, x, z, glances, heights):
    seen_glances, seen_heights = set(), set()
    for s in sweep_scenes(name):
        free = [b for b in s.bodies if not b.fixed]
        assert len(free) == 1 and free[0].position[0] == pytest.approx(x * 1e-6)
        assert free[0].position[2] == pytest.approx(z * 1e-6)
        seen_glances.add(round(free[0].position[1] * 1e6, 6))
        fixed = [b for b in s.bodies if b.fixed]
        seen_heights |= {round(b.position[2] * 1e6, 6) for b in fixed}
        repulsion = s.model.interaction("repulsion")
        assert s.model.flow.shear_rate == 100.0 and repulsion is not None and repulsion.inverse_length == 2e9
        if name.startswith("fig5_1") and "two" in name:  # two adherent cells 30 um apart in the flow
            assert sorted(b.position[0] for b in fixed) == pytest.approx([0.0, 30e-6])
    assert seen_glances == set(glances) and seen_heights == heights


# thesis ch. 2.3 B and appendix B: (scene, viscous numbers Vi = mu gdot / eta, aspect ratios, wall)
SHAPE_DYNAMICS = [
    ("fig2_09_11_tank_treading", {0.2, 0.1, round(0.1 / 23, 6)}, {1.0}, True),
    ("fig2_13_14_tumbling", {0.1, 0.2}, {0.5, 0.75}, True),
    ("tumbling_trembling", {0.1, 0.2}, {0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9}, False),
]


@pytest.mark.parametrize("name, vis, kappas, wall", SHAPE_DYNAMICS)
def test_shape_dynamics_scenes_set_the_thesis_cells(name, vis, kappas, wall):
    """a = 5 um, nu = 0.33, mu = 1 mPa s, a free deformable cell relaxing through the fluid,
    every Vi and aspect ratio of the thesis's figures (figs. 2.9-2.14, B-1, B-2)."""
    seen_vi, seen_kappa = set(), set()
    for s in sweep_scenes(name):
        (cell,) = s.bodies
        deformation = s.model.interaction("deformation")
        assert cell.deformable and not cell.fixed and cell.poisson_ratio == 0.33 and deformation.options.relaxation
        assert s.model.flow.viscosity == 1e-3 and s.model.flow.wall == wall
        extent = cell.mesh.nodes.max(axis=0) - cell.mesh.nodes.min(axis=0)
        assert extent[0] == pytest.approx(10e-6)
        seen_kappa.add(round(extent[2] / extent[0], 6))
        seen_vi.add(round(s.model.flow.viscosity * s.model.flow.shear_rate / cell.shear_modulus, 6))
    assert seen_vi == vis and seen_kappa == kappas
