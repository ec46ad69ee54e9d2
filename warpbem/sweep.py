"""``warpbem sweep``: run a scene over a grid of parameter values, one HDF5 file per point and a
summary table (CSV), in local worker processes.

    warpbem sweep SCENE --vary flow.shear_rate=80,100,120 --vary bodies.0.position=[0,2e-6,8e-6],[0,5e-6,8e-6]
                  --output-dir results/sweep [--workers 2]

Values are TOML (numbers, booleans, [arrays]); commas inside brackets do not split values.
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


def grid(varies) -> list[list[str]]:
    """Every combination of the --vary KEY=V1,V2 options, as lists of key=value overrides."""
    axes = []
    for item in varies:
        if "=" not in item:
            raise SceneError(f"--vary {item!r}: expected KEY=V1,V2,...")
        key, values = item.split("=", 1)
        axes.append([f"{key}={v}" for v in split_values(values)])
    return [list(point) for point in itertools.product(*axes)]


def _run_point(args):
    scene_path, output, overrides, device = args
    runner.run(scene_path, output, overrides, device, progress=lambda line: None)
    with h5py.File(output, "r") as f:
        start, end = f["position"][0], f["position"][-1]
        names = json.loads(f.attrs["body_names"])
    return {"file": str(output), **{o.split("=", 1)[0]: o.split("=", 1)[1] for o in overrides},
            **{f"{n}_dz_m": float(end[i, 2] - start[i, 2]) for i, n in enumerate(names)},
            **{f"{n}_dx_m": float(end[i, 0] - start[i, 0]) for i, n in enumerate(names)}}


def sweep(scene_path, varies, output_dir, device="cpu", workers=1, progress=print) -> Path:
    points = grid(varies)
    for overrides in points:  # validate every point before any work
        load(scene_path, overrides)
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    jobs = [(scene_path, output_dir / f"point{i:03d}.h5", overrides, device) for i, overrides in enumerate(points)]
    rows = []
    if workers <= 1:
        results = map(_run_point, jobs)
    else:
        # fresh interpreters (spawn): Warp's runtime is not safe to fork once initialised
        pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
        results = pool.map(_run_point, jobs)
    for i, row in enumerate(results):
        rows.append(row)
        progress(f"[{i + 1}/{len(jobs)}] {row['file']}: " + ", ".join(
            f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in row.items() if k != "file"))
    if workers > 1:
        pool.shutdown()
    summary = output_dir / "summary.csv"
    with summary.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return summary
