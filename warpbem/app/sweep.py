"""``warpbem sweep``: run a scene over a grid of parameter values, one HDF5 file per point and a
summary table (CSV), in local worker processes or on a Dask distributed cluster.

    warpbem sweep SCENE --vary flow.shear_rate=80,100,120 --vary bodies.0.position=[0,2e-6,8e-6],[0,5e-6,8e-6]
                  --output-dir results/sweep [--workers 2 | --scheduler tcp://HOST:8786]
    warpbem sweep scenes/fig5_04_05_shapes.toml --vary glance=2,3.5 --vary shape=sphere,box ...

``--vary KEY=V1,V2`` sets a scene key to each value (TOML: numbers, booleans, [arrays]; commas
inside brackets do not split values). ``--vary AXIS=L1,L2`` picks cases of a named axis of the
scene's [sweep.AXIS] tables (each case a list of key=value overrides); without any --vary the
grid of all the scene's axes runs.

``--scheduler ADDRESS`` (or a ``distributed.Client`` given to ``sweep``) runs the points as
tasks of a Dask cluster (the ``dask`` extra) instead: the workers must see the scene, its mesh
files and the output folder at the same paths (a shared file system). The files and the summary
are the same as a local sweep's; the progress lines come as points finish.

Sweeps resume by default: run again into the same folder, a point whose file holds its run to
the end is kept, one that stopped early is resumed from its last complete frame, and a missing
or unreadable one is run; the summary is written from all. A point file holding a different
scene (the scene or the grid changed) stops the sweep before any work, naming it;
``overwrite=True`` (``--overwrite``) runs every point afresh. When a point fails, the sweep
stops with an error naming the point; local workers finish the point they are on (kept for the
next resume) and start no other.
"""

from __future__ import annotations

import contextlib
import csv
import ctypes
import itertools
import json
import multiprocessing
import os
import signal
import sys
import threading
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from ..dynamics.frame import frame_columns
from . import run as runner
from .io import RunFileError, complete_rows, open_result
from .progress import Progress
from .scene import SceneError, load


class SweepError(RuntimeError):
    """A sweep point failed on a cluster worker, or the cluster could not be reached."""


def split_values(text: str) -> list[str]:
    """'1,2,[3,4]' -> ['1', '2', '[3,4]']: split on commas outside brackets."""
    parts, depth, current = [], 0, ""
    for ch in text:
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    parts.append(current)
    if depth != 0 or any(not p.strip() for p in parts):
        raise SceneError(f"--vary: cannot split {text!r} into values")
    return [p.strip() for p in parts]


def grid(varies, scene_axes=None) -> list[tuple[dict, list[str]]]:
    """Every combination of the --vary options: (labels {name: value}, key=value overrides)."""
    scene_axes = scene_axes or {}
    if not varies:
        varies = [f"{axis}={','.join(cases)}" for axis, cases in scene_axes.items()]
    axes = []
    for item in varies:
        if "=" not in item:
            raise SceneError(f"--vary {item!r}: expected KEY=V1,V2,...")
        key, values = item.split("=", 1)
        if key in scene_axes:
            cases = scene_axes[key]
            for v in split_values(values):
                if v not in cases:
                    raise SceneError(f"--vary {key}: no case {v!r}; the scene has {', '.join(cases)}")
            axes.append([({key: v}, cases[v]) for v in split_values(values)])
        else:
            axes.append([({key: v}, [f"{key}={v}"]) for v in split_values(values)])
    return [({k: v for labels, _ in point for k, v in labels.items()}, [o for _, o in point for o in o])
            for point in itertools.product(*axes)]


def point_status(output: Path, scene) -> str:
    """"complete", "partial" (resume it) or "missing" (run it: no file, or not a readable run);
    SceneError if the file holds another scene."""
    try:
        f = open_result(output, needs=("scene", "time"))
    except RunFileError:
        return "missing"
    with f:
        if f.attrs["scene"] != json.dumps(scene.raw, sort_keys=True):
            raise SceneError(f"{output} holds a run of a different scene than this point's (the scene or the"
                             " grid changed): use another --output-dir, or --overwrite to run every point afresh")
        rows = complete_rows(f, frame_columns(scene.model))
        if rows == 0:
            return "missing"
        return "complete" if f["time"][rows - 1] >= scene.end else "partial"


def _run_point(args):
    """Run (or resume, or keep) one point; returns (summary row, what was done)."""
    scene_path, output, labels, overrides, device, overwrite = args
    status = "missing" if overwrite else point_status(Path(output), load(scene_path, overrides))
    if status == "partial":
        runner.run(None, output, (), device, resume=True, progress=lambda line: None)
    elif status == "missing":
        runner.run(scene_path, output, overrides, device, progress=lambda line: None, overwrite=True)
    with open_result(output) as f:
        rows = complete_rows(f)
        start, end = f["position"][0], f["position"][rows - 1]
        names = json.loads(f.attrs["body_names"])
        closest = float(np.min(f["closest_gap"][:rows]))
    row = {"file": str(output), **labels, "closest_gap_m": closest,
           **{f"{n}_dz_m": float(end[i, 2] - start[i, 2]) for i, n in enumerate(names)},
           **{f"{n}_dx_m": float(end[i, 0] - start[i, 0]) for i, n in enumerate(names)}}
    return row, {"complete": "kept", "partial": "resumed", "missing": "ran"}[status]


def _run_point_in_worker(args):
    """``_run_point`` in a worker process, which ends when interrupted: the pool's worker loop
    would otherwise report the interruption and take the next point."""
    try:
        return _run_point(args)
    except KeyboardInterrupt:
        os._exit(130)  # the run file is closed by then (its with-block has exited)


def _failed(i, job, err) -> SweepError:
    return SweepError(f"point{i:03d} ({', '.join(job[3])}) failed: {type(err).__name__}: {err}")


def _line(row, what) -> str:
    """What a point's progress line says after its count: what was done, the point's file and labels."""
    return f"{what} {row['file']}: " + ", ".join(
        f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in row.items() if k != "file")


def _on_cluster(jobs, scheduler, counter) -> list[dict]:
    """The points' rows in grid order, run as tasks on a Dask cluster; a progress line (through
    ``counter``, a Progress) as each finishes. ``scheduler``: an address, or a ``distributed.Client``
    (left open)."""
    try:
        from distributed import Client, as_completed
    except ImportError as err:
        raise SweepError("a Dask scheduler needs the dask extra: pip install 'warpbem[dask]'") from err
    own = not isinstance(scheduler, Client)
    try:
        client = Client(scheduler) if own else scheduler
    except OSError as err:  # timeouts included
        raise SweepError(f"cannot reach the Dask scheduler at {scheduler}: {err}") from err
    rows, futures = [None] * len(jobs), {}
    try:
        for i, (scene_path, output, *rest) in enumerate(jobs):
            # absolute paths: a worker's working directory need not be ours. pure=False: a point
            # writes a file, so two equal jobs must both run rather than share one result
            job = (Path(scene_path).resolve(), Path(output).resolve(), *rest)
            futures[client.submit(_run_point, job, pure=False)] = i
        for future in as_completed(futures):
            i = futures[future]
            try:
                row, what = future.result()
            except Exception as err:
                raise SweepError(f"point{i:03d} ({', '.join(jobs[i][3])}) failed on the cluster:"
                                 f" {type(err).__name__}: {err}") from err
            rows[i] = {**row, "file": str(jobs[i][1])}  # the file named as a local sweep names it
            counter.done(_line(rows[i], what))
    finally:
        client.cancel(list(futures))  # nothing left running on the cluster after an error or interrupt
        if own:
            client.close()
    return rows


def sweep(scene_path, varies, output_dir, device="cpu", workers=1, progress=print, scheduler=None,
          overwrite=False) -> Path:
    """Run every point of the grid (resuming a sweep already in ``output_dir``, see the module
    docstring); returns the summary CSV. ``workers`` local processes, or with ``scheduler`` (a
    Dask scheduler address or ``distributed.Client``) the cluster's workers."""
    if scheduler is not None and workers > 1:
        raise ValueError("give workers (local processes) or scheduler (a Dask cluster), not both")
    points = grid(varies, load(scene_path).sweep)
    if not points or not points[0][1]:
        raise SceneError("nothing to sweep: give --vary KEY=V1,V2 or add [sweep.AXIS] cases to the scene")
    output_dir = Path(output_dir)
    jobs = [(scene_path, output_dir / f"point{i:03d}.h5", labels, overrides, device, overwrite)
            for i, (labels, overrides) in enumerate(points)]
    for job in jobs:  # validate every point, and what its file holds, before any work
        scene = load(scene_path, job[3])
        if not overwrite:
            point_status(job[1], scene)
    output_dir.mkdir(parents=True, exist_ok=True)
    counter = Progress(len(jobs), progress)
    if scheduler is not None:
        rows = _on_cluster(jobs, scheduler, counter)
    elif workers <= 1:
        rows = []
        for i, job in enumerate(jobs):
            try:
                row, what = _run_point(job)
            except Exception as err:
                raise _failed(i, job, err) from err
            rows.append(row)
            counter.done(_line(row, what))
    else:
        rows = _in_processes(jobs, workers, counter)
    summary = output_dir / "summary.csv"
    with summary.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return summary


# seconds an interrupted worker has to close its run file before it is terminated
WORKER_GRACE = 10.0
PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _worker_init():
    """A worker is interrupted (SIGINT, as by Ctrl-C) when its sweep process dies, however it
    dies (Linux's parent-death signal): a killed sweep leaves no worker running on its own."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGINT))


@contextlib.contextmanager
def _terminate_as_interrupt():
    """SIGTERM to the sweep raises KeyboardInterrupt, so that its workers are stopped as on
    Ctrl-C (signals can be set from the main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _stop_workers(pool):
    """Interrupt the pool's workers (SIGINT: a run closes its HDF5 file, whose complete frames a
    later sweep resumes from) and terminate those still alive after WORKER_GRACE seconds."""
    # ProcessPoolExecutor lists its processes nowhere public
    processes = [p for p in dict(getattr(pool, "_processes", None) or {}).values() if p.is_alive()]
    for p in processes:
        with contextlib.suppress(ProcessLookupError):
            os.kill(p.pid, signal.SIGINT)
    for p in processes:
        p.join(WORKER_GRACE)
        if p.is_alive():
            p.terminate()
            p.join()


def _in_processes(jobs, workers, counter) -> list[dict]:
    """The points' rows in grid order from local worker processes (fresh interpreters, spawn:
    Warp's runtime is not safe to fork once initialised). On a failure the pending points are
    cancelled and the pool shut down once the running ones finish (their files are complete).
    On Ctrl-C or SIGTERM the workers are interrupted too, and the same command resumes."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_worker_init)
    with _terminate_as_interrupt():
        try:
            futures = [pool.submit(_run_point_in_worker, job) for job in jobs]
            rows = []
            for i, future in enumerate(futures):
                try:
                    row, what = future.result()
                except Exception as err:
                    raise _failed(i, jobs[i], err) from err
                rows.append(row)
                counter.done(_line(row, what))
            return rows
        except KeyboardInterrupt:
            _stop_workers(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
