"""Shared helpers of the benchmark scripts: output folder, CSV tables, charts, timing."""

import argparse
import atexit
import csv
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "results" / "bench"

# Benchmarks time the solves: each run starts from an empty snapshot store of its own (removed at
# exit), not from the snapshots earlier runs kept (dynamics/snapshot_store.py), unless
# WARPBEM_SNAPSHOT_STORE names one
if "WARPBEM_SNAPSHOT_STORE" not in os.environ:
    os.environ["WARPBEM_SNAPSHOT_STORE"] = tempfile.mkdtemp(prefix="warpbem-benchmark-snapshots-")
    atexit.register(shutil.rmtree, os.environ["WARPBEM_SNAPSHOT_STORE"], ignore_errors=True)


def arguments(doc: str) -> argparse.ArgumentParser:
    """The parser every sized benchmark starts from: its docstring as help, ``--quick`` (smaller
    sizes and shorter runs) and ``--device`` (cpu, cuda:0, ...)."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="smaller sizes and shorter runs")
    parser.add_argument("--device", default="cpu")
    return parser


def output(name: str) -> Path:
    OUT.mkdir(parents=True, exist_ok=True)
    return OUT / name


def write_csv(name: str, rows: list[dict]) -> Path:
    path = output(name)
    fields = list(dict.fromkeys(k for row in rows for k in row))  # rows may hold different columns
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, restval="")
        writer.writeheader()
        writer.writerows(rows)
    return path


def print_table(rows: list[dict], formats: dict | None = None) -> None:
    formats = formats or {}
    keys = list(rows[0])
    cells = [[formats.get(k, "{}").format(r[k]) if not isinstance(r[k], float) or k in formats
              else f"{r[k]:.4g}" for k in keys] for r in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) for i, k in enumerate(keys)]
    print("  ".join(k.rjust(w) for k, w in zip(keys, widths)))
    for c in cells:
        print("  ".join(v.rjust(w) for v, w in zip(c, widths)), flush=True)


def best_time(fn, repeats: int = 3) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_chart(fig, path: Path, axes=(), legend_size: float | None = None) -> Path:
    """Grid the ``axes`` (and give each a legend of ``legend_size`` points, if set), lay the
    figure out and write it to ``path`` (120 dpi)."""
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        if legend_size is not None:
            ax.legend(fontsize=legend_size)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path
