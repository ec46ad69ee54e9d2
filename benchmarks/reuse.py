"""Model no more than a scene needs: one free cell among N fixed adherent cells.

Repeated solves while the free cell moves a little each time (as in time stepping): with
reuse, the blocks, completion columns and preconditioner factors of the fixed cells are kept and
GMRES starts from the previous solution; without, everything is rebuilt. A third column keeps
the blocks but runs plain GMRES (no block-Jacobi preconditioner). Times side by side in one run.
Cells: 5 um spheres (96 elements), adherent centres 5.25 um above the wall on a square grid
15 um apart, free cell 7.75 um high moving 0.1 um per solve; contact refinement off so that
every N has the same elements per cell.

    python benchmarks/reuse.py [--counts 1 4 16 64] [--solves 4] [--device cpu]
"""

import argparse
import gc
import time
import warnings

import numpy as np

import warpbem as wb
from common import pyplot, print_table, write_csv, output
from warpbem.app.progress import Progress


def scene(n_fixed, mesh, x_free):
    side = int(np.ceil(np.sqrt(n_fixed)))
    fixed = [wb.Body(mesh, position=(15e-6 * (i % side), 15e-6 * (i // side), 5.25e-6), fixed=True)
             for i in range(n_fixed)]
    return fixed + [wb.Body(mesh, position=(x_free, -12e-6, 7.75e-6))]


def run(n_fixed, reuse, solves, mesh, device="cpu", precondition=True):
    # the constant density of the time-stepping scenes, whose repeated solves this measures
    solver = wb.MobilitySolver(shear_rate=100.0, viscosity=1.2e-3, options=wb.SolverOptions(contact_refinement=0.0, precondition=precondition, density_order=1), keep_systems=reuse,
                               device=device)
    times, iterations = [], []
    for step in range(solves):
        bodies = scene(n_fixed, mesh, -20e-6 + 0.1e-6 * step)
        t = time.perf_counter()
        sol = solver.solve(bodies)
        times.append(time.perf_counter() - t)
        iterations.append(sol.iterations)
    mode = sol.operator_mode
    del solver, sol
    gc.collect()  # free this solver's matrix before the next: "auto" picks dense only if it fits
    # the first solve builds everything in both cases; the repeated ones are what reuse changes
    return float(np.mean(times[1:])), float(np.mean(iterations[1:])), times[0], mode


def main():
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)  # refinement is off on purpose
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 4, 16, 64])
    parser.add_argument("--solves", type=int, default=4)
    parser.add_argument("--device", default="cpu")
    args = parser.parse_args()
    mesh = wb.mesh.sphere(5e-6, 4)
    run(1, True, 2, mesh)  # compile kernels outside the timings
    rows, progress = [], Progress(len(args.counts))
    for n in args.counts:
        plain = run(n, False, args.solves, mesh, args.device)
        kept = run(n, True, args.solves, mesh, args.device)
        unpreconditioned = run(n, True, args.solves, mesh, args.device, precondition=False)
        rows.append(dict(fixed_cells=n, elements=96 * (n + 1), mode=kept[3],
                         first_solve_s=kept[2], rebuild_s=plain[0], reuse_s=kept[0],
                         speedup=plain[0] / kept[0], iterations_rebuild=plain[1], iterations_reuse=kept[1],
                         reuse_plain_gmres_s=unpreconditioned[0], iterations_plain_gmres=unpreconditioned[1],
                         mode_plain_gmres=unpreconditioned[3]))
        print_table(rows[-1:] if len(rows) > 1 else rows)
        progress.done(f"{n} fixed cells")
    print()
    print_table(rows)
    print(f"csv: {write_csv('reuse.csv', rows)}")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    n = [r["fixed_cells"] for r in rows]
    ax.loglog(n, [r["rebuild_s"] for r in rows], "o-", label="rebuild every solve")
    ax.loglog(n, [r["reuse_s"] for r in rows], "s-", label="keep fixed-cell blocks + warm start")
    ax.set_xlabel("fixed adherent cells N (plus one free cell)")
    ax.set_ylabel("time per repeated solve [s]")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    ax.set_title("Reuse of unchanged operator blocks (2-core CPU)")
    fig.tight_layout()
    fig.savefig(output("reuse.png"), dpi=120)
    print(f"chart: {output('reuse.png')}")


if __name__ == "__main__":
    main()
