"""Scale: N cells of 96 elements, time per operator apply and per solve, assembled vs
matrix-free, against a plain NumPy apply of the same operator and BLAS on the assembled matrix
(the memory-bandwidth floor). Everything is measured side by side in one run; ratios are what
to read (the machines are shared and noisy).

Cells: unit spheres on a square grid 3 radii apart, centres 1.5 radii above the wall, shear
flow; contact refinement off so each cell keeps its 96 elements. The Warp/NumPy ratio uses
the operator without adaptive subdivision, which the NumPy baseline does not have; the
default (adaptive) Warp operator is timed too.

    python benchmarks/scale.py [--counts 1 2 8 32 128] [--device cpu] [--numpy-max 32]
                               [--solve-max 32] [--dense-max-gb 4]
"""

import argparse
import resource
import time
import warnings

import numpy as np

import numpy_baseline
from common import best_time, output, print_table, pyplot, write_csv
from warpbem import Body, ContactResolutionWarning, MobilitySolver, mesh, runtime
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import DoubleLayerOperator, QuadratureOptions


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def cores_busy(fn):
    """Wall time of fn and the mean number of cores it kept busy (CPU time / wall time)."""
    c, t = cpu_seconds(), time.perf_counter()
    fn()
    wall = time.perf_counter() - t
    return wall, (cpu_seconds() - c) / wall


def cells(n):
    side = int(np.ceil(np.sqrt(n)))
    sphere = mesh.sphere(1.0, 4)
    return [Body(sphere, position=(3.0 * (i % side), 3.0 * (i // side), 1.5)) for i in range(n)]


def main():
    warnings.simplefilter("ignore", ContactResolutionWarning)  # refinement is off on purpose
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 2, 8, 32, 128])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--numpy-max", type=int, default=32, help="largest N for the NumPy baseline")
    parser.add_argument("--solve-max", type=int, default=32, help="largest N for full solves")
    parser.add_argument("--dense-max-gb", type=float, default=4.0, help="largest assembled matrix")
    args = parser.parse_args()
    device = runtime.resolve_device(args.device)
    rows = []
    for n in args.counts:
        bodies = cells(n)
        geometry = SurfaceGeometry.from_bodies(bodies, QuadratureOptions().order, 1.0, True)
        q = np.random.default_rng(n).standard_normal(3 * geometry.n_elements)
        matrix_gb = (3 * geometry.n_elements) ** 2 * 8 / 1e9
        row = dict(cells=n, elements=geometry.n_elements, matrix_GB=matrix_gb)
        plain = DoubleLayerOperator(geometry, True, QuadratureOptions(adaptive=False), device=device,
                                    mode="matrix_free")
        plain.matvec(q)  # compile, self blocks
        row["warp_free_apply_s"], row["cores_free_apply"] = cores_busy(lambda: plain.matvec(q))
        adaptive = DoubleLayerOperator(geometry, True, QuadratureOptions(), device=device, mode="matrix_free")
        adaptive.matvec(q)
        row["warp_free_adaptive_apply_s"] = best_time(lambda: adaptive.matvec(q), 1)
        if n <= args.numpy_max:
            row["numpy_apply_s"] = best_time(lambda: numpy_baseline.apply(geometry, q, True), 1)
            row["numpy_over_warp"] = row["numpy_apply_s"] / row["warp_free_apply_s"]
            row["max_abs_diff"] = float(np.abs(numpy_baseline.apply(geometry, q, True) - plain.matvec(q)).max())
        if matrix_gb <= args.dense_max_gb:
            dense = DoubleLayerOperator(geometry, True, QuadratureOptions(), device=device, mode="dense")
            row["assembly_s"], row["cores_assembly"] = cores_busy(dense.assemble)
            row["dense_apply_s"] = best_time(lambda: dense.matvec(q), 3)  # BLAS A @ x: the floor
            row["free_over_dense_apply"] = row["warp_free_adaptive_apply_s"] / row["dense_apply_s"]
        if n <= args.solve_max:
            for mode in ("dense", "matrix_free"):
                if mode == "dense" and matrix_gb > args.dense_max_gb:
                    continue
                solver = MobilitySolver(shear_rate=1.0, viscosity=1.0, device=device, operator=mode,
                                        contact_refinement=0.0, reuse=False, density_order=1)  # as the operators above
                t = time.perf_counter()
                sol = solver.solve(bodies)
                row[f"solve_{mode}_s"] = time.perf_counter() - t
                row["gmres_iterations"] = sol.iterations
        rows.append(row)
        print({k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items()}, flush=True)

    keys = ["cells", "elements", "matrix_GB", "warp_free_apply_s", "warp_free_adaptive_apply_s", "numpy_apply_s",
            "numpy_over_warp", "max_abs_diff", "assembly_s", "dense_apply_s", "free_over_dense_apply",
            "cores_free_apply", "cores_assembly", "solve_dense_s", "solve_matrix_free_s", "gmres_iterations"]
    table = [{k: r.get(k, float("nan")) for k in keys} for r in rows]
    print()
    print_table(table)
    print(f"csv: {write_csv('scale.csv', table)}")
    n = np.array([r["cells"] for r in rows], dtype=float)
    t_free = np.array([r["warp_free_adaptive_apply_s"] for r in rows])
    big = n >= 8
    if big.sum() >= 2:
        slope = np.polyfit(np.log(n[big]), np.log(t_free[big]), 1)[0]
        print(f"matrix-free apply time grows as N^{slope:.2f} (N >= 8)")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for key, label in (("warp_free_adaptive_apply_s", "Warp matrix-free (adaptive)"),
                       ("warp_free_apply_s", "Warp matrix-free (plain Gauss)"),
                       ("numpy_apply_s", "NumPy matrix-free (plain Gauss)"),
                       ("dense_apply_s", "BLAS A @ x on the assembled matrix"),
                       ("assembly_s", "Warp assembly (once)")):
        pts = [(r["cells"], r[key]) for r in rows if key in r]
        if pts:
            ax.loglog(*zip(*pts), "o-", label=label)
    ref = t_free[-1] * (n / n[-1]) ** 2
    ax.loglog(n, ref, "k:", label="~ N^2")
    ax.set_xlabel("cells N (96 elements each)")
    ax.set_ylabel("time [s]")
    ax.set_title(f"Operator apply and assembly, {device}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(output("scale.png"), dpi=120)
    print(f"chart: {output('scale.png')}")


if __name__ == "__main__":
    main()
