"""A small parameter sweep on a Dask cluster: a dense cell (1050 kg/m^3) settling towards the wall
in two fluids, 1000 and 1025 kg/m^3, then the sweep's summary read back, printed and charted.

    python examples/sweep_on_dask.py [--scheduler tcp://HOST:8786] [--output-dir results/sweep_on_dask]

Without ``--scheduler`` a local Dask cluster is started (two worker processes); with it the
points run on that cluster, whose workers must see this repository and the output folder at the
same paths. The sweep is ``warpbem.app.sweep.sweep``, the function behind

    warpbem sweep scenes/reference_free_cell.toml --vary physics.fluid_density=1000,1025 \\
        --vary height=7.5 --vary flow.shear_rate=0 --output-dir results/sweep_on_dask \\
        --scheduler tcp://HOST:8786

on ``scenes/reference_free_cell.toml`` (a lone 5 um cell in plasma, 1.2 mPa s) started 7.5 um
above the wall, here in still fluid (shear rate 0). It writes one run file per point and
``summary.csv`` (one row per point: its labels and the cell's displacement, ``free_dz_m``, in m);
run again into the same folder it resumes (finished points are kept). This script adds the mean
settling velocity W = -dz / t_end (m/s) and ``settling.png``.

What to expect: Stokes flow is linear in the loads, so the cell sinks under its weight less its
buoyancy, F = (4/3) pi a^3 (rho_cell - rho_fluid) g, at W = F / (6 pi mu a lambda(h/a)), lambda
Brenner's (1961) wall correction of Stokes drag (3.205 at h/a = 1.5, so W = 0.708 um/s for the
1000 kg/m^3 fluid, g = 9.80665 m/s^2). While the descent is small against the gap (lambda hardly
changes) the two velocities stand as the buoyancies, 50 : 25 = 2. In the scene's 100 1/s shear
the same holds for the exact sphere (the shear moves it along the wall only: Goldman, Cox &
Brenner 1967b), but the rotating cube-sphere mesh drifts up and down by 1e-4 - 3e-4 of its speed
along the wall (0.03 - 0.2 um/s), a tenth of the lighter cell's settling: hence still fluid.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import dask
from distributed import Client, LocalCluster

from warpbem.app.sweep import sweep

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "reference_free_cell.toml"
CELL_DENSITY = 1050.0               # kg/m^3, the scene's
FLUID_DENSITIES = (1000.0, 1025.0)  # kg/m^3


def run_sweep(output_dir, scheduler=None, end=0.1, subdivisions=4, workers=2, processes=True) -> Path:
    """Run the two fluids to ``end`` (s) with a cell of ``subdivisions`` (k: 6 k^2 elements) on the
    Dask cluster at ``scheduler`` (an address or a ``distributed.Client``), or on a local one of
    ``workers`` workers (``processes=False``: threads of this process); returns summary.csv."""
    varies = [f"physics.fluid_density={','.join(repr(rho) for rho in FLUID_DENSITIES)}", "height=7.5",
              "flow.shear_rate=0.0", f"time.end={end!r}", f"bodies.0.mesh.subdivisions={subdivisions}"]
    if scheduler is not None:
        return sweep(SCENE, varies, output_dir, scheduler=scheduler)
    # spawned worker processes: Warp's runtime is not safe to fork once initialised (as in
    # warpbem/app/sweep.py's local pool), whatever a site's Dask configuration says
    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}), \
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                         dashboard_address=None) as cluster, Client(cluster) as client:
        return sweep(SCENE, varies, output_dir, scheduler=client)


def settling(summary) -> list[dict]:
    """The summary's rows with the buoyant density difference (kg/m^3) and the mean settling
    velocity W = -dz / t_end (m/s) added."""
    rows = list(csv.DictReader(Path(summary).open()))
    for row in rows:
        row["density_difference"] = CELL_DENSITY - float(row["physics.fluid_density"])
        row["settling_velocity"] = -float(row["free_dz_m"]) / float(row["time.end"])
    return rows


def chart(rows, path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    drho = [r["density_difference"] for r in rows]
    w = [r["settling_velocity"] * 1e6 for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(drho, w, "o", ms=8, label="sweep points")
    # linear Stokes flow: W proportional to the buoyant weight, through the origin and the heavier point
    heavy = max(range(len(rows)), key=lambda i: drho[i])
    ax.plot([0, max(drho)], [0, w[heavy]], "k--", lw=1, label="W proportional to rho_cell - rho_fluid")
    ax.set(xlabel="rho_cell - rho_fluid [kg/m^3]", ylabel="mean settling velocity W [um/s]", xlim=(0, None),
           ylim=(0, None), title="a 5 um cell settling 7.5 um above the wall")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def main(output_dir="results/sweep_on_dask", scheduler=None, end=0.1, subdivisions=4, workers=2,
         processes=True) -> list[dict]:
    summary = run_sweep(output_dir, scheduler, end, subdivisions, workers, processes)
    rows = settling(summary)
    print(" rho_fluid [kg/m^3] | rho_cell - rho_fluid | dz [nm] | W [um/s]")
    for r in rows:
        print(f"{float(r['physics.fluid_density']):18.0f} | {r['density_difference']:20.0f} |"
              f" {float(r['free_dz_m']) * 1e9:7.2f} | {r['settling_velocity'] * 1e6:.4f}")
    (a, b) = rows
    print(f"W ratio {a['settling_velocity'] / b['settling_velocity']:.5f}, buoyancy ratio"
          f" {a['density_difference'] / b['density_difference']:.5f}  summary: {summary}"
          f"  chart: {chart(rows, Path(output_dir) / 'settling.png')}")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scheduler", help="a Dask scheduler's address; default: a local cluster")
    parser.add_argument("--output-dir", default="results/sweep_on_dask")
    parser.add_argument("--end", type=float, default=0.1, help="simulated time, s")
    args = parser.parse_args()
    main(args.output_dir, args.scheduler, args.end)
