"""Row splitting across CPU threads: assembly and matrix-free apply with 1 thread, with all
cores and one row block per thread (the split before issue 8), and with all cores and
``launch.CHUNKS_PER_THREAD`` blocks per thread taken as threads come free (the split now).

A Warp CPU launch runs on one core; warpbem launches row blocks from a thread pool. Two cases:
twelve spheres far apart (rows of equal cost), one sphere 0.05 radius above the wall with the
default contact refinement, and that sphere among the twelve (its refined rows, which need the
adaptive quadrature, come first, so one block per thread leaves one thread most of the work). Times are
measured side by side in one run.

    python benchmarks/cpu_threads.py [--subdivisions 4] [--repeats 3]
"""

import argparse

import numpy as np

from common import best_time, print_table, write_csv
from warpbem import Body, mesh
from warpbem.app.progress import Progress
from warpbem.kernels import launch
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, QuadratureOptions, discrete_form


def cases(subdivisions):
    sphere = mesh.sphere(1.0, subdivisions)
    spread = [Body(sphere, position=(3.0 * i, 0.0, 1.5)) for i in range(12)]
    near = [Body(sphere, position=(0.0, 0.0, 1.05))]
    order = QuadratureOptions().order
    return {"12 spheres, h/a = 1.5": SurfaceGeometry.from_bodies(spread, order, 1.0, True),
            "1 sphere, h/a = 1.05, refined": SurfaceGeometry.from_bodies(near, order, 1.0, True, 3.0),
            "the same + 12 spheres at h/a = 1.5": SurfaceGeometry.from_bodies(
                near + [Body(sphere, position=(3.0 * (i + 1), 0.0, 1.5)) for i in range(12)], order, 1.0, True, 3.0)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subdivisions", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    all_cores, chunks = launch.cpu_threads(), launch.CHUNKS_PER_THREAD
    splits = {"1 thread": (1, 1), f"{all_cores} threads, 1 block each": (all_cores, 1),
              f"{all_cores} threads, {chunks} blocks each": (all_cores, chunks)}
    rows, geometries = [], cases(args.subdivisions)
    progress = Progress(len(geometries) * len(splits))
    for case, geometry in geometries.items():
        q = np.random.default_rng(0).standard_normal(3 * geometry.n_elements)
        times = {}
        for split, (threads, per_thread) in splits.items():
            launch.cpu_threads = lambda n=threads: n  # noqa: E731  (benchmark-only override)
            launch.CHUNKS_PER_THREAD = per_thread

            def assemble():
                discrete_form(BoundaryOperator(geometry, True), "dense").matrix()

            def self_blocks():  # the matrix-free set-up: row sums over each element's own body
                discrete_form(BoundaryOperator(geometry, True), "matrix_free").self_blocks()

            op = discrete_form(BoundaryOperator(geometry, True), "matrix_free")
            op.matvec(q)  # compile and build the self blocks outside the timing
            times[split] = (best_time(assemble, args.repeats), best_time(self_blocks, args.repeats),
                            best_time(lambda: op.matvec(q), args.repeats))
            progress.done(f"{case}, {split}")
        one = times["1 thread"]
        for split, (a, b, m) in times.items():
            rows.append({"case": case, "elements": geometry.n_elements, "split": split, "assembly_s": a,
                         "self_blocks_s": b, "apply_s": m, "assembly_x": one[0] / a, "self_blocks_x": one[1] / b,
                         "apply_x": one[2] / m})
    print_table(rows, {k: "{:.3f}" if k.endswith("_s") else "{:.2f}" for k in rows[0] if k[-2:] in ("_s", "_x")})
    print(f"table: {write_csv('cpu_threads.csv', rows)}")


if __name__ == "__main__":
    main()
