"""Sweeps on a Dask cluster: the same point files and summary as a serial local sweep, and a
point that fails on a worker is named in the error."""

import csv
import json
from pathlib import Path

import dask
import h5py
import numpy as np
import pytest
from distributed import Client, LocalCluster

from warpbem.app import cli, sweep

from .test_scene import BASE, write

# point 0 takes three steps, point 1 one: rows must come in grid order whichever finishes first
VARIES = ["time.end=0.6,0.2"]


@pytest.fixture(scope="module")
def client():
    # spawned worker processes (distributed's default, pinned here against a site config that
    # sets fork): Warp's runtime is not safe to fork once initialised, as in sweep.py's pool
    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}), \
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as c:
        yield c


def scene_file(tmp_path):
    return write(tmp_path, json.loads(json.dumps(BASE)))


def rows(summary):
    return list(csv.DictReader(summary.open()))


def assert_same_sweep(a: Path, b: Path):
    """Two sweep folders hold the same summary rows (files named by their folder) and frames."""
    ra, rb = rows(a / "summary.csv"), rows(b / "summary.csv")
    assert [list(r) for r in ra] == [list(r) for r in rb] and len(ra) == 2
    for i, (x, y) in enumerate(zip(ra, rb)):
        assert Path(x.pop("file")) == a / f"point{i:03d}.h5" and Path(y.pop("file")) == b / f"point{i:03d}.h5"
        # same labels; numbers equal to round-off (a worker's BLAS may run on fewer threads,
        # which reorders the sums of the preconditioner's LU factorisation)
        assert {k: v for k, v in x.items() if not k.endswith("_m")} == {k: v for k, v in y.items() if not k.endswith("_m")}
        for k in x:
            if k.endswith("_m"):
                assert float(x[k]) == pytest.approx(float(y[k]), rel=1e-9, abs=1e-18)
        with h5py.File(a / f"point{i:03d}.h5") as f, h5py.File(b / f"point{i:03d}.h5") as g:
            assert f["time"].shape == g["time"].shape == (4 if i == 0 else 2,)
            for name in ("time", "position", "orientation", "velocity"):
                np.testing.assert_allclose(f[name][:], g[name][:], rtol=0, atol=1e-12)
            assert f.attrs["scene"] == g.attrs["scene"]
    assert [r["time.end"] for r in ra] == ["0.6", "0.2"]
    assert float(ra[0]["body0_dz_m"]) < float(ra[1]["body0_dz_m"]) < 0  # longer settling, larger drop


def test_cluster_sweep_matches_the_serial_one(tmp_path, client):
    path = scene_file(tmp_path)
    sweep.sweep(path, VARIES, tmp_path / "serial", progress=lambda line: None)
    lines = []
    summary = sweep.sweep(path, VARIES, tmp_path / "cluster", scheduler=client, progress=lines.append)
    assert summary == tmp_path / "cluster" / "summary.csv"
    assert_same_sweep(tmp_path / "serial", tmp_path / "cluster")
    # one progress line per point as it finishes, in whatever order the cluster finishes them
    # ("[k/2] ran FILE: ...")
    assert len(lines) == 2 and {line.split(": ")[0].split("] ran ")[1] for line in lines} == {
        str(tmp_path / "cluster" / f"point{i:03d}.h5") for i in range(2)}
    assert client.status == "running"  # a Client handed in is left open

    # the command line, given the scheduler's address, connects on its own and gives the same
    assert cli.main(["sweep", str(path), "--vary", VARIES[0], "--output-dir", str(tmp_path / "cli"),
                     "--scheduler", client.scheduler.address]) == 0
    assert_same_sweep(tmp_path / "serial", tmp_path / "cli")


def test_a_point_failing_on_a_worker_is_named(tmp_path, client, capsys):
    path = scene_file(tmp_path)
    # valid for the scene (checked before any work) but GMRES cannot reach it: fails on the worker
    varies = ["solver.tolerance=1e-8,1e-300"]
    with pytest.raises(sweep.SweepError, match=r"point001 \(solver.tolerance=1e-300\) failed on the cluster:"
                                               r" ConvergenceError: GMRES did not converge"):
        sweep.sweep(path, varies, tmp_path / "bad", scheduler=client, progress=lambda line: None)
    assert not (tmp_path / "bad" / "summary.csv").exists()
    assert cli.main(["sweep", str(path), "--vary", varies[0], "--output-dir", str(tmp_path / "bad"),
                     "--scheduler", client.scheduler.address]) == 1
    assert "warpbem sweep: point001 (solver.tolerance=1e-300) failed" in capsys.readouterr().err


def test_unreachable_scheduler_and_both_kinds_of_worker_are_refused(tmp_path):
    path = scene_file(tmp_path)
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}), \
            pytest.raises(sweep.SweepError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:1"):
        sweep.sweep(path, VARIES, tmp_path / "none", scheduler="tcp://127.0.0.1:1", progress=lambda line: None)
    with pytest.raises(ValueError, match="not both"):
        sweep.sweep(path, VARIES, tmp_path / "none", workers=2, scheduler="tcp://127.0.0.1:1")
