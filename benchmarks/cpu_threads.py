"""Row splitting across CPU threads: assembly and matrix-free apply with 1 thread vs all cores.

A Warp CPU launch runs on one core; warpbem launches row blocks from a thread pool. This prints
the times side by side, measured in the same run, and the speed-up ratio.

    python benchmarks/cpu_threads.py [--bodies 12] [--subdivisions 4] [--repeats 3]
"""

import argparse

import numpy as np

from common import best_time
from warpbem import Body, mesh, runtime
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import DoubleLayerOperator, QuadratureOptions


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=12)
    parser.add_argument("--subdivisions", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    sphere = mesh.sphere(1.0, args.subdivisions)
    bodies = [Body(sphere, position=(3.0 * i, 0.0, 1.5)) for i in range(args.bodies)]
    geometry = SurfaceGeometry.from_bodies(bodies, QuadratureOptions().order, 1.0, True)
    q = np.random.default_rng(0).standard_normal(3 * geometry.n_elements)
    all_cores = runtime.cpu_threads()
    rows = []
    for threads in (1, all_cores):
        runtime.cpu_threads = lambda n=threads: n  # noqa: E731  (benchmark-only override)

        def assemble():
            DoubleLayerOperator(geometry, True, QuadratureOptions(), mode="dense").assemble()

        op = DoubleLayerOperator(geometry, True, QuadratureOptions(), mode="matrix_free")
        op.matvec(q)  # compile and build the self blocks outside the timing
        rows.append((threads, best_time(assemble, args.repeats), best_time(lambda: op.matvec(q), args.repeats)))
    print(f"{args.bodies} bodies x {sphere.n_elements} elements = {geometry.n_elements} elements")
    print(f"{'threads':>8} {'assembly [s]':>13} {'matrix-free apply [s]':>22}")
    for threads, a, m in rows:
        print(f"{threads:8d} {a:13.3f} {m:22.3f}")
    print(f"speed-up with {all_cores} threads: assembly x{rows[0][1] / rows[1][1]:.2f},"
          f" matrix-free apply x{rows[0][2] / rows[1][2]:.2f}")


if __name__ == "__main__":
    main()
