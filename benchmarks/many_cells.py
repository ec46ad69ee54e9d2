"""Many adhesive cells (issue 25), on the machine it runs on, side by side:

1. accuracy: the grand mobility and the motion in the flow of n rigid 5 um cells at the rolling
   height (heights spread by +-20 nm) from the pairs (``[solver] grand_mobility = "pairs"``,
   dynamics/pairwise.py) against the whole system's solve, in the norm of
   ``benchmarks/adhesion.py`` part 2c (largest change over largest entry): the pairs at the
   cells' own positions ("pairwise": the approximation alone) and on the default lattices
   ("pairs, lattices"), and the cells alone (no coupling, for scale); cells in a line along the
   flow and in square patches;
2. cost per step: n cells rolling on stiff bonds (the state diagram's rolling point) for a
   short run from the same start, pairs against the whole system's snapshots, wall time and
   snapshots solved; the fitted exponent of the cost per step over n.

    python benchmarks/many_cells.py [--parts accuracy cost] [--quick]

Writes results/bench/many_cells_*.csv and many_cells.png.
"""

import time
import warnings

import numpy as np

import warpbem as wb
from common import arguments, print_table, write_csv
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.surfaces.body import Body

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A = 5e-6
REST = A + 236e-9  # m: centre height where gravity and eq. 3.1 balance (benchmarks/adhesion.py)
EXACT = dict(reuse_tolerance=1e-12, reuse_interaction=1e-12, pair_lateral=1e-12)  # lattices below round-off


def arrangement(kind, n, spacing, seed=1):
    """(n, 3) centres: ``line`` along the flow or a square ``patch`` (rows along the flow),
    heights REST +- 20 nm (seeded)."""
    rng = np.random.default_rng(seed)
    if kind == "line":
        lateral = [(spacing * i, 0.0) for i in range(n)]
    else:
        side = int(round(np.sqrt(n)))
        lateral = [(spacing * (i % side), spacing * (i // side)) for i in range(n)]
    return np.array([(x, y, REST + rng.uniform(-20e-9, 20e-9)) for x, y in lateral])


def motion(flow, grand):
    """(grand mobility Q, the flow's velocity and angular velocity times A) of a snapshot."""
    return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])


def change(a, b):
    return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]


def solves(mesh, n, device, **solver):
    model = Model([mesh] * n, [False] * n, Flow(100.0, 1e-3), solver=SolverOptions(**solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, device))


def accuracy(device, cases, k):
    mesh = wb.mesh.sphere(A, k)
    rows = []
    for kind, n, spacing in cases:
        bodies = [Body(mesh, position=p) for p in arrangement(kind, n, spacing)]
        hydro = solves(mesh, n, device)
        t = time.perf_counter()
        exact = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
        t_system = time.perf_counter() - t
        row = dict(arrangement=kind, cells=n, spacing_um=spacing * 1e6, k=k, system_s=t_system)
        for name, options in (("pairwise", dict(EXACT, grand_mobility="pairs")),
                              ("pairs_lattices", dict(reuse_tolerance=2e-9, grand_mobility="pairs"))):
            pairs = solves(mesh, n, device, **options)
            t = time.perf_counter()
            grand, flow = change(motion(*pairs._snapshot(bodies)), exact)
            row.update({f"{name}_grand": grand, f"{name}_flow": flow, f"{name}_s": time.perf_counter() - t,
                        f"{name}_snapshots": pairs.snapshots_solved})
        alone = solves(mesh, n, device, **EXACT, grand_mobility="pairs", pair_cutoff=0.0)
        row["alone_grand"], row["alone_flow"] = change(motion(*alone._snapshot(bodies)), exact)
        rows.append(row)
        print_table([row])
    return rows


def main():
    parser = arguments(__doc__)
    parser.add_argument("--parts", nargs="+", default=["accuracy"], choices=["accuracy", "cost"])
    parser.add_argument("--k", type=int, default=2, help="sphere mesh subdivisions")
    args = parser.parse_args()
    if "accuracy" in args.parts:
        cases = ([("line", 3, 25e-6)] if args.quick else
                 [("line", 3, 12e-6), ("line", 3, 25e-6), ("patch", 4, 25e-6), ("patch", 9, 25e-6)])
        rows = accuracy(args.device, cases, args.k)
        print(f"wrote {write_csv('many_cells_accuracy.csv', rows)}")


if __name__ == "__main__":
    main()
