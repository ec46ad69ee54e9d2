"""Nothing lost on interruption: a run resumes from its last frame complete in every column
(also when the process died between two column writes) and reproduces the uninterrupted run;
a resumed run may be extended, but not changed; sweeps resume point by point."""

import contextlib
import csv
import json
import multiprocessing
import os
import pathlib
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from warpbem.app import cli, run, scene, sweep
from warpbem.app.io import complete_rows, open_result

from tests.interrupted import run_killed_after

from .test_scene import BASE, write

A = 5e-6


def test_a_run_killed_between_column_writes_resumes_to_the_uninterrupted_one(tmp_path):
    path = write(tmp_path, BASE)
    straight = run.run(path, tmp_path / "straight.h5", progress=lambda line: None)
    out = tmp_path / "killed.h5"
    run_killed_after(1, path, out)
    with h5py.File(out, "a") as f:  # died while writing frame 2: two columns have it, the rest do not
        assert f["time"].shape == (2,)
        for name, value in (("time", 123.0), ("position", np.zeros((1, 3)))):
            f[name].resize(3, axis=0)
            f[name][2] = value
    resumed = run.run(None, out, resume=True, progress=lambda line: None)
    assert resumed.time == straight.time == 0.6 and resumed.steps == straight.steps == 3
    np.testing.assert_allclose(resumed.positions, straight.positions, rtol=0, atol=1e-9 * A)
    with h5py.File(out) as f, h5py.File(tmp_path / "straight.h5") as g:
        assert {k: f[k].shape[0] for k in frame_columns(f)} == {k: 4 for k in frame_columns(g)}  # the partial row is gone
        np.testing.assert_array_equal(f["time"][:], g["time"][:])
        for name in ("position", "velocity", "force"):
            np.testing.assert_allclose(f[name][:], g[name][:], rtol=1e-7, atol=1e-9 * np.abs(g[name][:]).max())
        history = json.loads(f.attrs["resumed"])
        assert len(history) == 1 and history[0]["time"] == pytest.approx(0.2)


def test_a_resumed_run_can_be_extended_but_not_changed(tmp_path, capsys):
    path = write(tmp_path, BASE)
    out = tmp_path / "run.h5"
    run.run(path, out, progress=lambda line: None)
    with pytest.raises(scene.SceneError, match=r"--set flow.shear_rate: a resumed run cannot change 'flow.shear_rate'"):
        run.run(None, out, ["flow.shear_rate=5"], resume=True, progress=lambda line: None)
    with pytest.raises(scene.SceneError, match=r"time.end: 0.4 s is before the run's last frame \(t = 0.6 s\)"):
        run.run(None, out, ["time.end=0.4"], resume=True, progress=lambda line: None)
    assert cli.main(["run", "--resume", "--output", str(out), "--set", "time.end=1.0"]) == 0
    longer = run.run(path, tmp_path / "longer.h5", ["time.end=1.0"], progress=lambda line: None)
    with h5py.File(out) as f:
        assert f["time"][-1] == 1.0 and json.loads(f.attrs["scene"])["time"]["end"] == 1.0
        np.testing.assert_allclose(f["position"][-1], longer.positions, rtol=0, atol=1e-9 * A)
    assert cli.main(["run", "--resume", "--output", str(out), "--set", "solver.tolerance=1e-3"]) == 2
    assert "cannot change 'solver.tolerance'" in capsys.readouterr().err


def summary_rows(folder):
    return list(csv.DictReader((folder / "summary.csv").open()))


def test_a_sweep_resumes_point_by_point(tmp_path):
    """Run again into the same folder, a sweep keeps its complete points (untouched), resumes a
    stopped one and summarises all, as the uninterrupted sweep did; a folder holding runs of
    another scene is refused before any work."""
    path = write(tmp_path, BASE)
    varies = ["flow.viscosity=1e-3,2e-3"]
    folder = tmp_path / "grid"
    sweep.sweep(path, varies, folder, progress=lambda line: None)
    first = summary_rows(folder)
    kept = (folder / "point000.h5").stat().st_mtime_ns
    with h5py.File(folder / "point001.h5", "a") as f:  # as if stopped after its first step
        for name in frame_columns(f):
            f[name].resize(2, axis=0)
    (folder / "summary.csv").unlink()
    lines = []
    sweep.sweep(path, varies, folder, progress=lines.append)
    assert [line.split()[1] for line in lines] == ["kept", "resumed"]
    assert lines[0].startswith("[1/2]") and " ETA " in lines[0] and " ETA " not in lines[1]  # done / total, ETA
    assert (folder / "point000.h5").stat().st_mtime_ns == kept
    with h5py.File(folder / "point001.h5") as f:
        assert f["time"][:].tolist() == pytest.approx([0.0, 0.2, 0.4, 0.6])
    again = summary_rows(folder)
    assert [r["file"] for r in again] == [r["file"] for r in first]
    for a, b in zip(first, again):
        assert float(a["body0_dz_m"]) == pytest.approx(float(b["body0_dz_m"]), rel=1e-7)
    with pytest.raises(scene.SceneError, match="point000.h5 holds a run of a different scene"):
        sweep.sweep(path, ["flow.viscosity=3e-3,2e-3"], folder, progress=lambda line: None)
    lines.clear()
    sweep.sweep(path, ["flow.viscosity=3e-3,2e-3"], folder, progress=lines.append, overwrite=True)
    assert [line.split()[1] for line in lines] == ["ran", "ran"]


def test_a_point_failing_in_a_local_worker_is_named_and_the_pool_shut_down(tmp_path, capsys):
    path = write(tmp_path, BASE)
    varies = ["solver.tolerance=1e-8,1e-300"]  # valid, but GMRES cannot reach 1e-300
    with pytest.raises(sweep.SweepError, match=r"point001 \(solver.tolerance=1e-300\) failed: ConvergenceError"):
        sweep.sweep(path, varies, tmp_path / "bad", workers=2, progress=lambda line: None)
    assert multiprocessing.active_children() == []  # no worker left behind
    assert (tmp_path / "bad" / "point000.h5").exists() and not (tmp_path / "bad" / "summary.csv").exists()
    assert cli.main(["sweep", str(path), "--vary", varies[0], "--output-dir", str(tmp_path / "bad")]) == 1
    err = capsys.readouterr().err
    assert "warpbem sweep: point001 (solver.tolerance=1e-300) failed" in err and "Traceback" not in err


def test_a_run_missing_a_column_of_this_version_is_refused_by_name(tmp_path):
    """A file written by an older warpbem (here: a column removed) is not resumed half-way
    with a KeyError: the refusal names the column."""
    path = write(tmp_path, BASE)
    out = tmp_path / "old.h5"
    run.run(path, out, progress=lambda line: None)
    with h5py.File(out, "a") as f:
        del f["closest_gap"]
    with pytest.raises(run.RunFileError, match="no column 'closest_gap' that this version of warpbem writes"):
        run.run(None, out, resume=True, progress=lambda line: None)


def frames(path):
    """The frames complete in a run file that another process may be writing (0 until readable)."""
    with contextlib.suppress(OSError, KeyError):
        with h5py.File(path, "r", locking=False) as f:
            return complete_rows(f)
    return 0


def children(pid):
    """The processes whose parent is ``pid`` (Linux /proc)."""
    found = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(stat.parent.name))
    return found


def alive(pid):
    """Whether ``pid`` runs (a zombie, dead but not yet reaped, does not)."""
    with contextlib.suppress(OSError):
        return pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigterm_to_a_sweep_ends_its_workers_and_the_sweep_resumes(tmp_path):
    """Issue 26 item 6: SIGTERM to ``warpbem sweep`` (killing its process, as a batch system
    does) interrupts its worker processes, none is left running, the command exits 130, and the
    interrupted points' files resume. Before, the workers ran on after their sweep had died."""
    long_run = dict(BASE, physics={}, flow={"shear_rate": 10.0, "viscosity": 1e-3},
                    time={"end": 400.0, "dt_max": 0.2, "dt_min": 0.05, "contact_gap": 1e-6})
    path = write(tmp_path, long_run)
    folder = tmp_path / "sweep"
    command = [sys.executable, "-c", "import sys; from warpbem.app.cli import main; sys.exit(main(sys.argv[1:]))",
               "sweep", str(path), "--vary", "flow.viscosity=1e-3,2e-3", "--output-dir", str(folder),
               "--workers", "2"]
    sweeping = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    points = [folder / "point000.h5", folder / "point001.h5"]
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and not all(p.exists() and frames(p) >= 2 for p in points):
            time.sleep(0.5)
        workers = children(sweeping.pid)
        assert len(workers) >= 2, "the sweep's workers did not start"
        sweeping.send_signal(signal.SIGTERM)
        _, err = sweeping.communicate(timeout=120)
    finally:  # never leave this test's processes behind, whatever failed
        for pid in children(sweeping.pid):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        sweeping.kill()
    assert sweeping.returncode == 130 and "the same command resumes the sweep" in err, err
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and any(alive(pid) for pid in workers):
        time.sleep(0.2)
    assert not any(alive(pid) for pid in workers), "workers left running after their sweep ended"
    for point in points:  # each interrupted file resumes (here to a nearer end)
        with open_result(point) as f:
            last = float(f["time"][complete_rows(f) - 1])
        assert last < 400.0
        resumed = run.run(None, point, [f"time.end={last + 0.4}"], resume=True, progress=lambda line: None)
        assert resumed.time == pytest.approx(last + 0.4)


def frame_columns(f) -> list:
    """The frame columns of an open run file: its root datasets (the meshes are a group)."""
    return [name for name, value in f.items() if isinstance(value, h5py.Dataset)]
