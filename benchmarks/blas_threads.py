"""BLAS threads beside Warp's CPU thread pool: the spread of repeated timings with OpenBLAS free
to use every core (its threads spin after each call, beside the pool's) and with the package's
policy (kernels/launch.py: one BLAS thread once Warp's pool has run, every core only for
factorizations of ``launch.BLAS_ALL_CORES_ROWS`` rows or more). Issue 26 item 7: timings swung
2x within an hour on the 2-core CPU, partly from the spinning threads.

Workloads, each timed ``--repeats`` times with the two settings interleaved (side by side in one
run, so that the machine's other load falls on both):
- a 400 x 400 matrix product, then the matrix-free apply of six spheres (k = 3) above the wall,
  the pattern of a GMRES step beside NumPy work;
- a mobility solve of four 5 um spheres 0.5-2 um above the wall (k = 4), built from scratch;
- the same with one sphere at k = 6 (1 536 elements), whose block factor takes every core.

    python benchmarks/blas_threads.py [--repeats 20]
"""

import argparse
import time

import numpy as np
from threadpoolctl import ThreadpoolController

import warpbem as wb
from common import print_table, pyplot, save_chart, write_csv, output
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, QuadratureOptions, discrete_form
from warpbem.app.progress import Progress
from warpbem.kernels import launch


def product_then_apply():
    sphere = wb.mesh.sphere(1.0, 3)
    geometry = SurfaceGeometry.from_bodies([wb.Body(sphere, position=(3.0 * i, 0.0, 1.5)) for i in range(6)],
                                           QuadratureOptions().order, 1.0, True)
    op = discrete_form(BoundaryOperator(geometry, True), "matrix_free")
    q = np.random.default_rng(0).standard_normal(3 * geometry.n_elements)
    a = np.random.default_rng(1).standard_normal((400, 400))

    def run():
        a @ a
        op.matvec(q)
    return run


def mobility(subdivisions, heights):
    sphere = wb.mesh.sphere(5e-6, subdivisions)

    def run():
        bodies = [wb.Body(sphere, position=(12e-6 * i, 0.0, 5e-6 + h)) for i, h in enumerate(heights)]
        wb.solve_mobility(bodies, shear_rate=100.0, viscosity=1.2e-3)
    return run


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    workloads = {"product + matrix-free apply": product_then_apply(),
                 "mobility, 4 spheres k = 4": mobility(4, [0.5e-6, 1e-6, 1.5e-6, 2e-6]),
                 "mobility, 1 sphere k = 6": mobility(6, [1e-6])}
    controller = ThreadpoolController()
    settings = {"BLAS on every core": lambda: controller.limit(limits=launch.cpu_threads(), user_api="blas"),
                "warpbem's policy": lambda: controller.limit(limits=1, user_api="blas")}
    for run in workloads.values():
        run()  # compile the kernels and start the thread pool (which limits BLAS) outside the timings
    times = {(w, s): [] for w in workloads for s in settings}
    progress = Progress(args.repeats * len(workloads))
    for repeat in range(args.repeats):
        for name, run in workloads.items():
            for setting, limit in settings.items():
                with limit():
                    t = time.perf_counter()
                    run()
                    times[name, setting].append(time.perf_counter() - t)
            progress.done(name)
    rows = []
    for (name, setting), t in times.items():
        t = np.array(t)
        p10, median, p90 = np.percentile(t, [10, 50, 90])
        rows.append({"workload": name, "blas": setting, "median_ms": 1e3 * median, "p10_ms": 1e3 * p10,
                     "p90_ms": 1e3 * p90, "min_ms": 1e3 * t.min(), "max_ms": 1e3 * t.max(),
                     "p90_over_p10": p90 / p10, "max_over_min": t.max() / t.min()})
    print_table(rows, {k: "{:.1f}" if k.endswith("_ms") else "{:.2f}"
                       for k in rows[0] if k not in ("workload", "blas")})
    print(f"table: {write_csv('blas_threads.csv', rows)}")
    plt = pyplot()
    fig, axes = plt.subplots(1, len(workloads), figsize=(4 * len(workloads), 3.6))
    for ax, name in zip(axes, workloads):
        ax.boxplot([1e3 * np.array(times[name, s]) for s in settings], whis=(0, 100))
        ax.set_xticks(range(1, len(settings) + 1), list(settings), fontsize=8)
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("time per run [ms]")
    print(f"chart: {save_chart(fig, output('blas_threads.png'), axes)}")


if __name__ == "__main__":
    main()
