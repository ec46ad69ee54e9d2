"""Accuracy against cost: relative error of the solver against the exact sphere-wall solutions
versus wall time per solve, over mesh size k (6 k^2 elements), Gauss order (1-6 points per
direction), adaptive near-singular subdivision on/off and contact refinement off/on.

Cases: free sphere in wall-bounded shear at h/a = 1.5 and 1.1 (error = the larger of the
errors of U and Omega; GCB 1967b) and a sphere held fixed at h/a = 1.1 (the larger of the
errors of f* and t*). Marks the seed's configuration (k = 4, 3x3 Gauss, nothing else) and the
project default (k = 4 as in the seed, 2x2 Gauss, adaptive, contact refinement 3).

    python benchmarks/pareto.py [--ks 2 4 8 12 16] [--orders 1 2 3 4 5 6] [--replot]
"""

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

import warpbem as wb
from common import output, print_table, pyplot, write_csv

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

CASES = {
    "free sphere, h/a = 1.5": (1.5, False),
    "free sphere, h/a = 1.1": (1.1, False),
    "held sphere, h/a = 1.1": (1.1, True),
}
SEED = dict(k=4, order=3, adaptive=False, refinement=0.0)
DEFAULT = dict(k=4, order=2, adaptive=True, refinement=3.0)


def error_and_time(mesh, h, fixed, order, adaptive, refinement):
    body = wb.Body(mesh, position=(0, 0, h), fixed=fixed)
    t = time.perf_counter()
    sol = wb.solve_mobility([body], shear_rate=1.0, viscosity=1.0, quadrature_order=order,
                            adaptive_quadrature=adaptive, contact_refinement=refinement)
    elapsed = time.perf_counter() - t
    if fixed:
        ref = series.fixed_sphere_in_shear(h)
        errors = (-sol.force[0, 0] / (6 * np.pi * h * ref["f_star"]) - 1,
                  -sol.torque[0, 1] / (4 * np.pi * ref["t_star"]) - 1)
    else:
        ref = series.free_sphere_in_shear(h)
        errors = (sol.velocity[0, 0] / h / ref["U_over_gdot_h"] - 1,
                  sol.angular_velocity[0, 1] / ref["Omega_over_gdot"] - 1)
    return max(abs(e) for e in errors), elapsed, len(sol.solution_vector) // 3, sol.iterations


def pareto_front(points):
    """Indices of the points no other point beats in both time and error."""
    order = np.argsort([p[0] for p in points])
    front, best = [], np.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ks", type=int, nargs="+", default=[2, 4, 8, 12, 16])
    parser.add_argument("--orders", type=int, nargs="+", default=[1, 2, 3, 4, 5, 6])
    parser.add_argument("--replot", action="store_true", help="redraw the chart from the last CSV")
    args = parser.parse_args()
    if args.replot:
        plot(read_csv(), args.ks, args.orders)
        return
    for order in args.orders:  # compile every kernel variant outside the timings
        error_and_time(wb.mesh.sphere(1.0, 2), 1.5, True, order, True, 0.0)
    rows = []
    for k in args.ks:
        mesh = wb.mesh.sphere(1.0, k)
        for order in args.orders:
            for adaptive in (False, True):
                for refinement in (0.0, 3.0):
                    for case, (h, fixed) in CASES.items():
                        err, t, n, its = error_and_time(mesh, h, fixed, order, adaptive, refinement)
                        rows.append(dict(case=case, k=k, order=order, adaptive=adaptive, refinement=refinement,
                                         elements=n, error=err, time_s=t, iterations=its))
            print(f"k = {k}, order {order}: done", flush=True)
    print_table(rows)
    print(f"csv: {write_csv('pareto.csv', rows)}")
    plot(rows, args.ks, args.orders)


def read_csv():
    with output("pareto.csv").open() as f:
        rows = list(csv.DictReader(f))
    types = dict(k=int, order=int, adaptive=lambda v: v == "True", refinement=float, elements=int,
                 error=float, time_s=float, iterations=int)
    return [{key: types.get(key, str)(value) for key, value in r.items()} for r in rows]


def plot(rows, ks, orders):
    plt = pyplot()
    fig, axes = plt.subplots(1, len(CASES), figsize=(6 * len(CASES), 5), sharey=True)
    colours = dict(zip(ks, plt.cm.viridis(np.linspace(0, 0.9, len(ks)))))
    markers = dict(zip(orders, "o^sDvP*"))
    for ax, case in zip(axes, CASES):
        sub = [r for r in rows if r["case"] == case]
        for r in sub:
            ax.loglog(r["time_s"], r["error"], markers[r["order"]], ms=6,
                      mfc=colours[r["k"]] if r["adaptive"] else "none", mec=colours[r["k"]],
                      alpha=1.0 if r["refinement"] else 0.45)
        front = pareto_front([(r["time_s"], r["error"]) for r in sub])
        ax.loglog([sub[i]["time_s"] for i in front], [sub[i]["error"] for i in front], "k-", lw=1, label="Pareto front")
        for mark, config, style in (("seed", SEED, "rx"), ("default", DEFAULT, "r+")):
            r = next(r for r in sub if all(r[key] == v for key, v in config.items()))
            ax.loglog(r["time_s"], r["error"], style, ms=16, mew=2, label=f"{mark} ({r['error']:.1e})")
        ax.set_title(case)
        ax.set_xlabel("wall time per solve [s] (2-core CPU)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_ylabel("relative error vs exact series")
    handles = [plt.Line2D([], [], ls="", marker="o", color=c, label=f"k = {k}") for k, c in colours.items()]
    handles += [plt.Line2D([], [], ls="", marker=m, color="0.3", label=f"order {o}") for o, m in markers.items()]
    handles += [plt.Line2D([], [], ls="", marker="o", mfc="none", mec="0.3", label="hollow: no adaptive"),
                plt.Line2D([], [], ls="", marker="o", color="0.3", alpha=0.45, label="faint: no contact refinement")]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(output("pareto.png"), dpi=120)
    print(f"chart: {output('pareto.png')}")


if __name__ == "__main__":
    main()
