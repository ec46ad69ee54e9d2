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
"""

from __future__ import annotations

import csv
import itertools
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import h5py
import numpy as np

from . import run as runner
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


def _run_point(args):
    scene_path, output, labels, overrides, device = args
    runner.run(scene_path, output, overrides, device, progress=lambda line: None, overwrite=True)
    with h5py.File(output, "r") as f:
        start, end = f["position"][0], f["position"][-1]
        names = json.loads(f.attrs["body_names"])
        closest = float(np.min(f["closest_gap"][:]))
    return {"file": str(output), **labels, "closest_gap_m": closest,
            **{f"{n}_dz_m": float(end[i, 2] - start[i, 2]) for i, n in enumerate(names)},
            **{f"{n}_dx_m": float(end[i, 0] - start[i, 0]) for i, n in enumerate(names)}}


def _line(done, total, row) -> str:
    return f"[{done}/{total}] {row['file']}: " + ", ".join(
        f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in row.items() if k != "file")


def _on_cluster(jobs, scheduler, progress) -> list[dict]:
    """The points' rows in grid order, run as tasks on a Dask cluster; a progress line as each
    finishes. ``scheduler``: an address, or a ``distributed.Client`` (left open)."""
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
        for done, future in enumerate(as_completed(futures), 1):
            i = futures[future]
            try:
                row = future.result()
            except Exception as err:
                raise SweepError(f"point{i:03d} ({', '.join(jobs[i][3])}) failed on the cluster:"
                                 f" {type(err).__name__}: {err}") from err
            rows[i] = {**row, "file": str(jobs[i][1])}  # the file named as a local sweep names it
            progress(_line(done, len(jobs), rows[i]))
    finally:
        client.cancel(list(futures))  # nothing left running on the cluster after an error or interrupt
        if own:
            client.close()
    return rows


def sweep(scene_path, varies, output_dir, device="cpu", workers=1, progress=print, scheduler=None) -> Path:
    """Run every point of the grid; returns the summary CSV. ``workers`` local processes, or with
    ``scheduler`` (a Dask scheduler address or ``distributed.Client``) the cluster's workers."""
    if scheduler is not None and workers > 1:
        raise ValueError("give workers (local processes) or scheduler (a Dask cluster), not both")
    points = grid(varies, load(scene_path).sweep)
    if not points or not points[0][1]:
        raise SceneError("nothing to sweep: give --vary KEY=V1,V2 or add [sweep.AXIS] cases to the scene")
    for _, overrides in points:  # validate every point before any work
        load(scene_path, overrides)
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    jobs = [(scene_path, output_dir / f"point{i:03d}.h5", labels, overrides, device)
            for i, (labels, overrides) in enumerate(points)]
    if scheduler is not None:
        rows = _on_cluster(jobs, scheduler, progress)
    else:
        rows = []
        if workers <= 1:
            results = map(_run_point, jobs)
        else:
            # fresh interpreters (spawn): Warp's runtime is not safe to fork once initialised
            pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
            results = pool.map(_run_point, jobs)
        for i, row in enumerate(results):
            rows.append(row)
            progress(_line(i + 1, len(jobs), row))
        if workers > 1:
            pool.shutdown()
    summary = output_dir / "summary.csv"
    with summary.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return summary
