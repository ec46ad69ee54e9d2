"""warpbem and the rigid-multiblob peer (RigidMultiblobsWall) measured side by side, in one run
(issue 27, item 3).

The peer is GPL: it is never imported here nor copied into this repository. It runs from its own
checkout, named by the environment variable ``WARPBEM_PEER`` (a clone of
stochasticHydroTools/RigidMultiblobsWall), in its own Python, ``WARPBEM_PEER_PYTHON`` (default:
``$WARPBEM_PEER/../venv/bin/python``; it needs numpy, scipy, numba), through
``peer_worker.py``, which calls the peer's functions and answers over a pipe. Without the
checkout the script says so and exits 0 (with ``--require-peer``: exit 2).

One timing protocol for both codes, interleaved case by case: per setting, one warm-up, then
the MEDIAN of 3 solves, each building its bodies from scratch (warpbem: the mesh, the bodies and
the solve; the peer: reading its blob model, the body, the blob mobility and the solve). Both on
the machine's threads (warpbem's pool; the peer's BLAS, ``OPENBLAS_NUM_THREADS`` = cores).

Cases (radius a = 1, viscosity 1, wall z = 0; exact values: the series of
``tests/verification/sphere_wall_series.py``): a free sphere in the shear u = (gdot z, 0, 0) at
h/a = 1.5 and 1.1 (U/(gdot h) and Omega/gdot), the parallel translational drag F^t* at h/a = 1.5
(translating, not rotating) and Brenner's normal drag lambda at h/a = 1.1. Error: |code/exact - 1|.

Prints issue 27's table: per time budget per solve (0.01 ... 3 s) and quantity, ratio = the
peer's best error within the budget / warpbem's best error within it (> 1: warpbem more
accurate; "peer only": no warpbem setting is that fast), and charts both codes' fronts (error
against time per solve, one panel per quantity).

    WARPBEM_PEER=/work/peer/RigidMultiblobsWall ../.venv/bin/python peer_side_by_side.py
        [--accuracies 3e-2 ... 3e-5] [--blobs 12 42 162 642 2562] [--replot]
        [--sweep [--ks 2 3 4 5 6 8] [--orders 1 2]]

The warpbem settings timed: the accuracy target at each of ``--accuracies`` (``warpbem_settings``),
or with ``--sweep`` the settings pareto.py sweeps.
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import warpbem as wb
from common import output, print_table, pyplot, write_csv

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

BUDGETS = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0)  # s per solve
# (case, h/a): the solves; each free solve gives two quantities
CASES = (("free", 1.5), ("free", 1.1), ("parallel", 1.5), ("normal", 1.1))
QUANTITIES = ("U 1.5", "Omega 1.5", "U 1.1", "Omega 1.1", "F^t* 1.5", "lambda 1.1")
BLOBS = (12, 42, 162, 642, 2562)
REPEATS = 3


@dataclass
class Setting:
    """One warpbem setting to time: the sphere mesh level and ``SolverOptions`` fields."""
    label: str
    k: int
    options: dict = field(default_factory=dict)


ACCURACIES = (3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5)


def warpbem_settings(accuracies=ACCURACIES) -> list[Setting]:
    """The warpbem settings this benchmark times, for every case: the accuracy target
    (``SolverOptions.accuracy``) at each of ``accuracies``, given the k = 4 library sphere (which
    the target rebuilds at the k it chooses, inside the timed solve)."""
    return [Setting(f"accuracy {a:g}", 4, dict(accuracy=a)) for a in accuracies]


def swept_settings(ks=(2, 3, 4, 5, 6, 8), orders=(1, 2)) -> list[Setting]:
    """``--sweep``: the settings ``pareto.py`` sweeps (mesh level k, density order p, contact
    refinement off / the default ratio), for comparison with the target's choices."""
    return [Setting(f"k={k}, p={p}" + ("" if refined else ", no refinement"), k,
                    dict(density_order=p, contact_refinement=None if refined else 0.0))
            for k in ks for p in orders for refined in (False, True)]


# ------------------------------------------------------------------------------------ warpbem
def warpbem_solve(case: str, h: float, setting: Setting):
    """One solve from scratch: mesh, body, solve."""
    mesh = wb.mesh.sphere(1.0, setting.k)
    options = wb.SolverOptions(**setting.options)
    if case == "free":
        return wb.solve_mobility([wb.Body(mesh, position=(0, 0, h))], shear_rate=1.0, viscosity=1.0, options=options)
    velocity = (1.0, 0, 0) if case == "parallel" else (0, 0, 1.0)
    return wb.solve_mobility([wb.Body(mesh, position=(0, 0, h), fixed=True, velocity=velocity)], viscosity=1.0,
                             options=options)


def warpbem_values(case: str, sol) -> dict:
    """Raw results in the units of the peer worker's answer."""
    if case == "free":
        return dict(U=float(sol.velocity[0, 0]), Omega=float(sol.angular_velocity[0, 1]))
    return dict(F=float(sol.force[0, 0 if case == "parallel" else 2]))


def warpbem_timed(case: str, h: float, setting: Setting) -> dict:
    warpbem_solve(case, h, setting)  # warm-up
    times = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        sol = warpbem_solve(case, h, setting)
        times.append(time.perf_counter() - t)
    return dict(warpbem_values(case, sol), times=times, unknowns=len(sol.solution_vector))


# --------------------------------------------------------------------------------------- peer
def peer_paths() -> tuple[Path, Path] | None:
    """(checkout, its Python), or None (with the reason printed) when the peer is not set up."""
    checkout = os.environ.get("WARPBEM_PEER")
    if not checkout:
        print("peer skipped: set WARPBEM_PEER to a checkout of stochasticHydroTools/RigidMultiblobsWall "
              "(and WARPBEM_PEER_PYTHON to a Python with numpy, scipy, numba; default $WARPBEM_PEER/../venv)")
        return None
    checkout = Path(checkout).expanduser().resolve()
    python = Path(os.environ.get("WARPBEM_PEER_PYTHON", checkout.parent / "venv" / "bin" / "python"))
    if not (checkout / "mobility" / "mobility.py").is_file():
        print(f"peer skipped: WARPBEM_PEER={checkout} is not a RigidMultiblobsWall checkout (no mobility/mobility.py)")
        return None
    if not python.is_file():
        print(f"peer skipped: no Python at {python} (set WARPBEM_PEER_PYTHON)")
        return None
    return checkout, python


class Peer:
    """The peer worker, a subprocess in the peer's Python: one JSON request, one JSON answer."""

    def __init__(self, checkout: Path, python: Path):
        threads = str(os.cpu_count() or 1)
        env = dict(os.environ, OPENBLAS_NUM_THREADS=threads, OMP_NUM_THREADS=threads, MKL_NUM_THREADS=threads,
                   NUMBA_NUM_THREADS=threads, PYTHONWARNINGS="ignore")
        self.process = subprocess.Popen([str(python), str(Path(__file__).with_name("peer_worker.py")), str(checkout)],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)

    def timed(self, case: str, h: float, blobs: int) -> dict:
        self.process.stdin.write(json.dumps(dict(case=case, h=h, blobs=blobs, repeats=REPEATS)) + "\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            raise SystemExit(f"the peer worker stopped (exit {self.process.wait()}); see its error above")
        return json.loads(line)

    def close(self):
        self.process.stdin.close()
        self.process.wait(timeout=30)


# ---------------------------------------------------------------------------------- the table
def errors(case: str, h: float, values: dict) -> dict:
    """|code/exact - 1| of each quantity of a case."""
    if case == "free":
        ref = series.free_sphere_in_shear(h)
        return {f"U {h}": abs(values["U"] / h / ref["U_over_gdot_h"] - 1),
                f"Omega {h}": abs(values["Omega"] / ref["Omega_over_gdot"] - 1)}
    if case == "parallel":
        return {f"F^t* {h}": abs(values["F"] / (6 * np.pi * series.parallel_resistance(h)["Ft"]) - 1)}
    return {f"lambda {h}": abs(values["F"] / (6 * np.pi * series.brenner_lambda(h)) - 1)}


def rows_of(code: str, config: str, case: str, h: float, result: dict) -> list[dict]:
    t = statistics.median(result["times"])
    times = " ".join(f"{x:.4g}" for x in result["times"])
    return [dict(code=code, config=config, quantity=q, error=e, time_s=t, times=times)
            for q, e in errors(case, h, result).items()]


def best_within(rows, code, quantity, budget):
    inside = [r for r in rows if r["code"] == code and r["quantity"] == quantity and r["time_s"] <= budget]
    return min(inside, key=lambda r: r["error"]) if inside else None


def ratio_table(rows) -> list[dict]:
    """Issue 27's table: per budget and quantity, the peer's best error / warpbem's best error."""
    table = []
    for budget in BUDGETS:
        row = {"budget per solve": f"{budget:g} s"}
        for q in QUANTITIES:
            ours, peer = best_within(rows, "warpbem", q, budget), best_within(rows, "RMW", q, budget)
            if peer is None:
                row[q] = "warpbem only" if ours else "-"
            elif ours is None:
                row[q] = "peer only"
            else:
                row[q] = f"{peer['error'] / ours['error']:.2g}" if ours["error"] > 0 else "inf"
        table.append(row)
    return table


def detail_table(rows) -> list[dict]:
    """Who gives each ratio: the best setting of each code within each budget."""
    table = []
    for q in QUANTITIES:
        for budget in BUDGETS:
            ours, peer = best_within(rows, "warpbem", q, budget), best_within(rows, "RMW", q, budget)
            table.append(dict(quantity=q, budget_s=budget,
                              warpbem=f"{ours['error']:.1e} ({ours['config']}, {ours['time_s']:.3g} s)"
                              if ours else "-",
                              RMW=f"{peer['error']:.1e} ({peer['config']}, {peer['time_s']:.3g} s)" if peer else "-"))
    return table


def pareto_front(points):
    front, best = [], np.inf
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def plot(rows) -> Path:
    plt = pyplot()
    fig, axes = plt.subplots(2, 3, figsize=(15, 9), sharex=True)
    families = (("warpbem", "s", "C1", "warpbem (settings of warpbem_settings)"),
                ("RMW", "^", "k", "RigidMultiblobsWall (12 ... 2562 blobs)"))
    for ax, q in zip(axes.T.ravel(), QUANTITIES):
        for code, marker, colour, label in families:
            points = [(r["time_s"], max(r["error"], 1e-12)) for r in rows if r["quantity"] == q and r["code"] == code]
            if not points:
                continue
            ax.loglog(*zip(*points), marker, color=colour, ms=4, mfc="none", alpha=0.5)
            ax.loglog(*zip(*pareto_front(points)), "-" + marker, color=colour, ms=5, label=label + ": best per time")
        for budget in BUDGETS:
            ax.axvline(budget, color="0.85", lw=0.8, zorder=0)
        ax.set_title(q.replace(" ", ", h/a = "))
        ax.grid(alpha=0.3, which="both")
    for ax in axes[1]:
        ax.set_xlabel("wall time per solve [s] (median of 3 after a warm-up, from scratch)")
    for ax in axes[:, 0]:
        ax.set_ylabel("|code / exact - 1|")
    axes[0, 0].legend(fontsize=8, loc="lower left")
    fig.suptitle("warpbem and the rigid-multiblob peer measured side by side (one run, one protocol)")
    fig.tight_layout()
    path = output("peer_side_by_side.png")
    fig.savefig(path, dpi=120)
    return path


def read_csv() -> list[dict]:
    with output("peer_side_by_side.csv").open() as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["error"], r["time_s"] = float(r["error"]), float(r["time_s"])
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--accuracies", type=float, nargs="+", default=list(ACCURACIES))
    parser.add_argument("--sweep", action="store_true", help="time the swept settings (--ks, --orders) instead")
    parser.add_argument("--ks", type=int, nargs="+", default=[2, 3, 4, 5, 6, 8])
    parser.add_argument("--orders", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--blobs", type=int, nargs="+", default=list(BLOBS))
    parser.add_argument("--replot", action="store_true", help="table and chart from the last CSV")
    parser.add_argument("--require-peer", action="store_true", help="exit 2 (not 0) when the peer is not set up")
    args = parser.parse_args()
    if args.replot:
        rows = read_csv()
    else:
        paths = peer_paths()
        if paths is None:
            sys.exit(2 if args.require_peer else 0)
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)  # near contact on purpose
        warnings.simplefilter("ignore", wb.AccuracyWarning)  # the tightest targets out of reach at h/a 1.1
        peer = Peer(*paths)
        settings = swept_settings(args.ks, args.orders) if args.sweep else warpbem_settings(args.accuracies)
        rows = []
        try:
            for case, h in CASES:  # interleaved: both codes on one case, then the next
                for blobs in args.blobs:
                    result = peer.timed(case, h, blobs)
                    rows += rows_of("RMW", f"{blobs} blobs", case, h, result)
                    print(f"RMW {case} h/a {h}, {blobs} blobs: {statistics.median(result['times']):.3g} s, "
                          + ", ".join(f"{r['quantity']} {r['error']:.2e}" for r in rows[-2:] if r["code"] == "RMW"
                                      and r["config"] == f"{blobs} blobs"), flush=True)
                for setting in settings:
                    result = warpbem_timed(case, h, setting)
                    new = rows_of("warpbem", setting.label, case, h, result)
                    rows += new
                    print(f"warpbem {case} h/a {h}, {setting.label} ({result['unknowns']} unknowns): "
                          f"{new[0]['time_s']:.3g} s, " + ", ".join(f"{r['quantity']} {r['error']:.2e}" for r in new),
                          flush=True)
        finally:
            peer.close()
        print(f"csv: {write_csv('peer_side_by_side.csv', rows)}")
    print("\nBest error of each code within each budget:")
    print_table(detail_table(rows))
    print("\nRatio = peer error / warpbem error, best of each within the budget per solve "
          "(> 1: warpbem more accurate):")
    print_table(ratio_table(rows))
    print(f"chart: {plot(rows)}")


if __name__ == "__main__":
    main()
