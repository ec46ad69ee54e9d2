"""Stability map: where each method stops being accurate, or GMRES stalls, as two surfaces
close in. Sweeps the gap between a sphere and the wall, and between two spheres, from about
one element size down to 1e-3 radius, for several quadrature options and both precisions;
records the error against the exact series (Brenner 1961 and GCB 1967b for the wall, Stimson
& Jeffery 1926 for two spheres) and the GMRES iterations.

    python benchmarks/stability.py [--gaps 0.4 0.2 0.1 0.05 0.02 0.01 0.005]
"""

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from common import output, print_table, pyplot, write_csv
from warpbem.app.progress import Progress

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

OPTIONS = {
    "p=1 (seed scheme), no refinement": dict(density_order=1, contact_refinement=0.0),
    "p=1, contact refinement 3 (scaled)": dict(density_order=1),
    "default: p=2, contact refinement 1.1 (scaled)": dict(),
    "default, float32 (GMRES tol 1e-6)": dict(dtype="float32", tolerance=1e-6),
}
# smallest gap run per option: p = 1 refined to the rule needs 7200 elements at a gap of 0.01
# (a 3.7 GB matrix) and four times as many at 0.002
SMALLEST_GAP = {"p=1, contact refinement 3 (scaled)": 0.01}
# two spheres refine to half their gap (refinement.resolved_length): 7100 points at 0.02, and at
# 0.01 a matrix past half the 24 GB machine's memory
SMALLEST_PAIR_GAP = {"p=1, contact refinement 3 (scaled)": 0.05}  # p = 1: 3 times the elements
ELEMENT_SIZE = 2 * np.pi / 16  # edge of a k = 4 cube-sphere element, in radii


def solve(bodies, options, **flow):
    """One solve with the solver ``options`` (a dict of ``SolverOptions`` fields) and the flow and
    loads ``flow`` (keywords of ``solve_mobility``); (solution, False), or (None, True) if it stalls."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return wb.solve_mobility(bodies, viscosity=1.0, options=wb.SolverOptions(**options), **flow), False
    except wb.ConvergenceError:
        return None, True


def wall_errors(mesh, gap, options):
    h = 1.0 + gap
    free, stall_a = solve([wb.Body(mesh, position=(0, 0, h))], options, shear_rate=1.0)
    pushed, stall_b = solve([wb.Body(mesh, position=(0, 0, h), fixed=True, velocity=(0, 0, 1.0))], options)
    ref = series.free_sphere_in_shear(h)
    err_shear = np.nan if free is None else max(abs(free.velocity[0, 0] / h / ref["U_over_gdot_h"] - 1),
                                                  abs(free.angular_velocity[0, 1] / ref["Omega_over_gdot"] - 1))
    err_normal = np.nan if pushed is None else abs(pushed.force[0, 2] / (6 * np.pi * series.brenner_lambda(h)) - 1)
    its = max(s.iterations for s in (free, pushed) if s is not None) if (free or pushed) else np.nan
    n = len((free or pushed).solution_vector) // 3 if (free or pushed) else 0
    return dict(err_shear=err_shear, err_normal=err_normal, iterations=its, stalled=stall_a or stall_b, elements=n)


def pair_errors(mesh, gap, options):
    h = 1.0 + gap / 2
    bodies = [wb.Body(mesh, position=(0, 0, 0)), wb.Body(mesh, position=(2 * h, 0, 0))]
    sol, stalled = solve(bodies, options, wall=False, forces=[[6 * np.pi, 0, 0], [-6 * np.pi, 0, 0]])
    err = np.nan if sol is None else abs(1 / sol.velocity[0, 0] / series.approaching_spheres_lambda(h) - 1)
    return dict(err_pair=err, iterations_pair=np.nan if sol is None else sol.iterations, stalled_pair=stalled,
                elements_pair=0 if sol is None else len(sol.solution_vector) // 3)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gaps", type=float, nargs="+", default=[0.4, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005])
    args = parser.parse_args()
    mesh = wb.mesh.sphere(1.0, 4)
    rows = []
    cases = [(name, options, gap) for name, options in OPTIONS.items()
             for gap in args.gaps if gap >= SMALLEST_GAP.get(name, 0.0)]
    progress = Progress(len(cases))
    for name, options, gap in cases:
        row = dict(option=name, gap=gap, gap_over_element=gap / ELEMENT_SIZE)
        row.update(wall_errors(mesh, gap, options))
        if gap >= SMALLEST_PAIR_GAP.get(name, 0.02) or options.get("contact_refinement") == 0.0:
            row.update(pair_errors(mesh, gap, options))
        else:
            row.update(err_pair=np.nan, iterations_pair=np.nan, stalled_pair=False, elements_pair=0)
        rows.append(row)
        print_table([row]) if len(rows) == 1 else print(
            "  ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in row.values()), flush=True)
        progress.done(f"{name}, gap {gap:g}")
    print()
    print_table(rows)
    print(f"csv: {write_csv('stability.csv', rows)}")

    plt = pyplot()
    fig, axes = plt.subplots(2, 3, figsize=(16, 8), sharex=True)
    panels = [("err_normal", "sphere -> wall: Brenner force error"), ("err_shear", "sphere in shear near wall: max(U, Omega) error"),
              ("err_pair", "two approaching spheres: force error")]
    for col, (key, title) in enumerate(panels):
        its_key = "iterations_pair" if key == "err_pair" else "iterations"
        for (name, style) in zip(OPTIONS, ("o:", "s--", "D-", "x:")):
            sub = [r for r in rows if r["option"] == name]
            x = [r["gap_over_element"] for r in sub]
            axes[0, col].loglog(x, [r[key] for r in sub], style, label=name)
            axes[1, col].semilogx(x, [r[its_key] for r in sub], style, label=name)
        axes[0, col].axhline(0.01, color="0.5", ls=":", lw=1)
        axes[0, col].set_title(title, fontsize=10)
        axes[1, col].set_xlabel("gap / element size (k = 4: element edge 0.39 radius)")
    axes[0, 0].set_ylabel("relative error")
    axes[1, 0].set_ylabel("GMRES iterations (missing: stalled)")
    axes[0, 0].legend(fontsize=8)
    for ax in axes.ravel():
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(output("stability.png"), dpi=120)
    print(f"chart: {output('stability.png')}")


if __name__ == "__main__":
    main()
