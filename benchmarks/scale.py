"""Scale: N cells of 96 elements, time per operator product and per solve, and memory, for the
assembled (dense) operator, the direct matrix-free sum and the treecode, against a plain NumPy
product of the same operator and BLAS on the assembled matrix (the memory-bandwidth floor).
Everything is measured side by side in one run; ratios and growth exponents are what to read
(the machines are shared and noisy).

Cells: unit spheres on a square grid 3 radii apart, centres 1.5 radii above the wall, shear
flow; contact refinement off so each cell keeps its 96 elements; constant density (p = 1). The
Warp/NumPy ratio uses the operator without adaptive subdivision, which the NumPy baseline does
not have; every other column is the default (adaptive) operator. The treecode's error is that
of a product with a random density against the direct sum: all points up to --direct-max cells,
beyond that --sample random points (their rows of the direct sum assembled).

The treecode's one error parameter, its tolerance, is swept at --sweep-cells cells (error
against the direct sum, time, points per box); at every N the tolerances --tolerances are run.

    python benchmarks/scale.py [--counts 8 16 32 64 128 256 512 1024] [--device cpu]
                               [--tolerances 1e-4 1e-6] [--numpy-max 32] [--direct-max 128]
                               [--solve-max 32] [--treecode-solve-max 1024] [--dense-max-gb 3]
                               [--sweep-cells 64] [--sweep 1e-2 1e-3 1e-4 1e-5 1e-6 1e-7]
"""

import resource
import time
import warnings

import numpy as np

import numpy_baseline
from common import arguments, best_time, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem import Body, ContactResolutionWarning, MobilitySolver, mesh, runtime
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, QuadratureOptions, discrete_form
from warpbem.hydro.treecode import TreecodeOptions
from warpbem.kernels import integrals
from warpbem.hydro.options import SolverOptions


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


def direct_rows(operator, q: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Rows of the direct product (1/2 + D) q at the given collocation points: their rows of
    the matrix assembled (all elements) and applied, with their self blocks."""
    wp = runtime.init()
    geo = operator.geometry
    block = wp.empty((3 * len(points), 3 * geo.n_points), dtype=operator.kernels.green.dtype, device=operator.device)
    integrals.assemble_entries(operator.kernels, operator.device, operator.surface, points, np.arange(geo.n_elements),
                               block, compact=True)
    own = np.einsum("aij,aj->ai", operator.self_blocks().numpy()[points], q.reshape(-1, 3)[points]).ravel()
    return block.numpy() @ q + own


def growth(rows, key, smallest=64):
    """Exponent of a power law fitted to key(N) over N >= smallest (nan with fewer than 2)."""
    pts = [(r["cells"], r[key]) for r in rows if r["cells"] >= smallest and np.isfinite(r.get(key, np.nan))]
    if len(pts) < 2:
        return float("nan")
    n, t = np.log(np.array(pts)).T
    return float(np.polyfit(n, t, 1)[0])


def main():
    warnings.simplefilter("ignore", ContactResolutionWarning)  # refinement is off on purpose
    parser = arguments(__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[8, 16, 32, 64, 128, 256, 512, 1024])
    parser.add_argument("--tolerances", type=float, nargs="+", default=[1e-4, 1e-6], help="treecode tolerances")
    parser.add_argument("--sweep-cells", type=int, default=64, help="cells of the tolerance sweep")
    parser.add_argument("--sweep", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7])
    parser.add_argument("--numpy-max", type=int, default=32, help="largest N for the NumPy baseline")
    parser.add_argument("--direct-max", type=int, default=128, help="largest N for the direct matrix-free sum")
    parser.add_argument("--solve-max", type=int, default=32, help="largest N for dense and direct solves")
    parser.add_argument("--treecode-solve-max", type=int, default=1024, help="largest N for treecode solves")
    parser.add_argument("--dense-max-gb", type=float, default=3.0, help="largest assembled matrix")
    parser.add_argument("--sample", type=int, default=400, help="points of the sampled error beyond --direct-max")
    args = parser.parse_args()
    if args.quick:
        args.counts, args.tolerances, args.sweep = [8, 64], [1e-4], [1e-3, 1e-5]
    device = runtime.resolve_device(args.device)
    progress = Progress(len(args.sweep) + len(args.counts))  # the tolerance sweep, then each count
    sweep = tolerance_sweep(args, device, progress)
    rows = []
    for n in args.counts:
        bodies = cells(n)
        geometry = SurfaceGeometry.from_bodies(bodies, QuadratureOptions().order, 1.0, True)
        q = np.random.default_rng(n).standard_normal(3 * geometry.n_elements)
        matrix_gb = (3 * geometry.n_elements) ** 2 * 8 / 1e9
        row = dict(cells=n, elements=geometry.n_elements, matrix_GB=matrix_gb)
        reference = None
        if n <= args.direct_max:
            plain = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions(adaptive=False)), "matrix_free",
                                  device)
            plain.matvec(q)  # compile, self blocks
            row["warp_free_apply_s"], row["cores_free_apply"] = cores_busy(lambda: plain.matvec(q))
            adaptive = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions()), "matrix_free", device)
            reference = adaptive.matvec(q)
            row["direct_product_s"] = best_time(lambda: adaptive.matvec(q), 1)
            if n <= args.numpy_max:
                row["numpy_apply_s"] = best_time(lambda: numpy_baseline.apply(geometry, q, True), 1)
                row["numpy_over_warp"] = row["numpy_apply_s"] / row["warp_free_apply_s"]
                row["max_abs_diff"] = float(np.abs(numpy_baseline.apply(geometry, q, True) - plain.matvec(q)).max())
        if matrix_gb <= args.dense_max_gb:
            dense = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions()), "dense", device)
            row["assembly_s"], row["cores_assembly"] = cores_busy(dense.matrix)
            row["dense_product_s"] = best_time(lambda: dense.matvec(q), 3)  # BLAS A @ x: the floor
            if reference is not None:
                row["free_over_dense_apply"] = row["direct_product_s"] / row["dense_product_s"]
            del dense
        sample = None
        for tolerance in args.tolerances:
            label = f"{tolerance:.0e}"
            t = time.perf_counter()
            tree = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions()), "treecode", device,
                                 treecode=TreecodeOptions(tolerance=tolerance))
            tree.matvec(q)  # the first product assembles the stored near field
            row[f"tree{label}_setup_s"] = time.perf_counter() - t
            out = tree.matvec(q)
            row[f"tree{label}_product_s"] = best_time(lambda: tree.matvec(q), 2)
            row[f"tree{label}_GB"] = (tree.near_field_bytes * tree.near_field_stored
                                      + tree.far_field.memory_bytes) / 1e9
            if reference is not None:
                row[f"tree{label}_error"] = float(np.linalg.norm(out - reference) / np.linalg.norm(reference))
            else:
                if sample is None:
                    points = np.sort(np.random.default_rng(0).choice(geometry.n_points, args.sample, replace=False))
                    sample = (points, direct_rows(tree, q, points), (3 * points[:, None] + np.arange(3)).ravel())
                points, exact, dofs = sample
                row[f"tree{label}_error"] = float(np.linalg.norm(out[dofs] - exact) / np.linalg.norm(exact))
            row["levels"] = tree.far_field.tree.levels
            del tree
        solves = [("dense", n <= args.solve_max and matrix_gb <= args.dense_max_gb),
                  ("matrix_free", n <= args.solve_max), ("treecode", n <= args.treecode_solve_max)]
        for mode, wanted in solves:
            if wanted:
                solver = MobilitySolver(shear_rate=1.0, viscosity=1.0, device=device, options=SolverOptions(operator=mode, contact_refinement=0.0, density_order=1, treecode=TreecodeOptions()), keep_systems=False)  # its default tolerance
                t = time.perf_counter()
                sol = solver.solve(bodies)
                row[f"solve_{mode}_s"] = time.perf_counter() - t
                row[f"gmres_its_{mode}"] = sol.iterations
        row["max_rss_GB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
        rows.append(row)
        print({k: (float(f"{v:.4g}") if isinstance(v, float) else v) for k, v in row.items()}, flush=True)
        progress.done(f"{n} cells")

    keys = ["cells", "elements", "matrix_GB", "warp_free_apply_s", "direct_product_s", "numpy_apply_s",
            "numpy_over_warp", "max_abs_diff", "assembly_s", "dense_product_s", "free_over_dense_apply",
            "cores_free_apply", "cores_assembly"]
    for tolerance in args.tolerances:
        keys += [f"tree{tolerance:.0e}_{k}" for k in ("setup_s", "product_s", "error", "GB")]
    keys += ["levels"] + [k for mode in ("dense", "matrix_free", "treecode") for k in (f"solve_{mode}_s", f"gmres_its_{mode}")]
    keys += ["max_rss_GB"]
    table = [{k: r.get(k, float("nan")) for k in keys} for r in rows]
    print()
    print_table(table)
    print(f"csv: {write_csv('scale.csv', table)}")
    exponents = {"dense product (BLAS)": growth(rows, "dense_product_s", 8),
                 "direct matrix-free product": growth(rows, "direct_product_s", 8)}
    for tolerance in args.tolerances:
        exponents[f"treecode product, tolerance {tolerance:g}"] = growth(rows, f"tree{tolerance:.0e}_product_s")
        exponents[f"treecode memory, tolerance {tolerance:g}"] = growth(rows, f"tree{tolerance:.0e}_GB")
    exponents["treecode solve"] = growth(rows, "solve_treecode_s")
    for name, slope in exponents.items():
        print(f"{name} grows as N^{slope:.2f}" + (" (N >= 8)" if "dense" in name or "direct" in name else " (N >= 64)"))
    plt = pyplot()
    fig, (ax, ax_err, ax_sweep) = plt.subplots(1, 3, figsize=(17, 4.8))
    curves = [("direct_product_s", "direct matrix-free (Warp)", "direct matrix-free product"),
              ("warp_free_apply_s", "direct, plain Gauss (Warp)", None),
              ("numpy_apply_s", "direct, plain Gauss (NumPy)", None),
              ("dense_product_s", "BLAS A @ x, assembled", "dense product (BLAS)"),
              ("assembly_s", "Warp assembly (once)", None)]
    curves += [(f"tree{t:.0e}_product_s", f"treecode, tolerance {t:g}", f"treecode product, tolerance {t:g}")
               for t in args.tolerances]
    curves += [(f"tree{args.tolerances[-1]:.0e}_setup_s", f"treecode set-up, tolerance {args.tolerances[-1]:g} (once)",
                None)]
    for key, label, fitted in curves:
        pts = [(r["cells"], r[key]) for r in rows if key in r]
        if pts:
            suffix = f" ~N^{exponents[fitted]:.2f}" if fitted and np.isfinite(exponents[fitted]) else ""
            ax.loglog(*zip(*pts), "o-", label=label + suffix)
    ax.set_xlabel("cells N (96 elements each)")
    ax.set_ylabel("time per product [s]")
    ax.set_title(f"Operator product, {device}")
    for tolerance in args.tolerances:
        key = f"tree{tolerance:.0e}_error"
        pts = [(r["cells"], r[key]) for r in rows if key in r]
        line, = ax_err.loglog(*zip(*pts), "o-", label=f"tolerance {tolerance:g}")
        ax_err.axhline(tolerance, color=line.get_color(), ls=":")
    ax_err.set_xlabel("cells N")
    ax_err.set_ylabel("relative error of the product vs direct sum")
    ax_err.set_title("Treecode error (dotted: the tolerance asked for)")
    tol = [r["tolerance"] for r in sweep]
    ax_sweep.loglog(tol, [r["error"] for r in sweep], "o-", label="error")
    ax_sweep.loglog(tol, tol, "k:", label="error = tolerance")
    ax_sweep.set_xlabel("tolerance")
    ax_sweep.set_ylabel("relative error of the product")
    ax_sweep.invert_xaxis()
    twin = ax_sweep.twinx()
    twin.loglog(tol, [r["product_s"] for r in sweep], "s--", color="C3", label="time per product")
    twin.set_ylabel("time per product [s]", color="C3")
    ax_sweep.set_title(f"Treecode, {args.sweep_cells} cells: error and cost over the tolerance")
    print(f"chart: {save_chart(fig, output('scale.png'), (ax, ax_err, ax_sweep), legend_size=7)}")


def tolerance_sweep(args, device, progress) -> list:
    """Error against the direct sum, product and set-up time, points per box at the leaves and
    ranks, over the treecode's tolerance, at --sweep-cells cells; a line to ``progress`` (a
    Progress) per tolerance."""
    bodies = cells(args.sweep_cells)
    geometry = SurfaceGeometry.from_bodies(bodies, QuadratureOptions().order, 1.0, True)
    q = np.random.default_rng(1).standard_normal(3 * geometry.n_elements)
    exact = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions()), "matrix_free", device).matvec(q)
    rows = []
    for tolerance in args.sweep:
        t = time.perf_counter()
        tree = discrete_form(BoundaryOperator(geometry, True, QuadratureOptions()), "treecode", device,
                             treecode=TreecodeOptions(tolerance=tolerance))
        out = tree.matvec(q)
        far = tree.far_field
        rows.append(dict(tolerance=tolerance, error=float(np.linalg.norm(out - exact) / np.linalg.norm(exact)),
                         setup_s=time.perf_counter() - t, product_s=best_time(lambda: tree.matvec(q), 2),
                         leaf_points=str(far.points[-1]), largest_rank=max(max(r) for r in far.ranks.values()),
                         far_GB=far.memory_bytes / 1e9))
        progress.done(f"tolerance {tolerance:g} at {args.sweep_cells} cells")
    print_table(rows)
    print(f"csv: {write_csv('scale_tolerance.csv', rows)}")
    return rows


if __name__ == "__main__":
    main()
