"""Frozen adherent arrays (warpbem/hydro/frozen.py): the near-far split's error against the full
solve over the cut-off, and the cost of a step against the array's size.

errors: a free cell (radius 5 um, k = 4, 6 um high, 1.05 g/cc) at --positions along its path
between the two middle rows of an --side x --side array of domes (30 um pitch; the scene
scenes/array_crossing.toml), its velocity and angular velocity by the split at each --cutoffs
against the full solve (every body in one system, kept blocks of the domes), both with the
scene's solver settings. Table and chart: the largest relative error over the positions, the
adherent cells solved with the free cell, the time per solve.

steps: the crossing scene over --counts arrays (n x n domes), in a process of its own each (its
peak memory): set-up (the first frame: the background solve), and the time per step measured as
(T(2k steps) - T(k steps)) / k with k = --steps, the cell starting mid-array between two columns
(the same neighbourhood from 8 x 8 on; the 3 x 3 array's is its edge). --full also runs the
arrays up to --full-max without the split (every body in every solve).

    python benchmarks/frozen.py errors [--side 8] [--cutoffs ...] [--positions ...]
    python benchmarks/frozen.py steps [--counts 3 8 32] [--steps 5] [--full] [--full-max 8]
"""

import json
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from common import arguments, output, print_table, pyplot, save_chart, write_csv

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "array_crossing.toml"
PITCH = 30e-6


def row_offset(n: int) -> float:
    """y of the first row, so that y = 0 lies between the two middle rows (glance 15 um)."""
    return -0.5 * PITCH - PITCH * ((n - 1) // 2)


def crossing_overrides(n: int, x: float | None = None, cutoff: float | None = None) -> list:
    out = [f"arrays.0.count=[{n},{n}]", f"arrays.0.origin=[0,{row_offset(n)!r},4.5e-6]"]
    if x is not None:
        out.append(f"bodies.0.position=[{x!r},0.0,6e-6]")
    if cutoff is not None:
        out.append(f"solver.near_far_cutoff={cutoff!r}")
    return out


def errors(args):
    import warpbem as wb
    from warpbem.app import scene as scenes
    from warpbem.hydro.frozen import FrozenArraySolver

    loaded = scenes.load(SCENE, crossing_overrides(args.side))
    model = loaded.model
    options = model.solver
    flow = model.flow
    gravity = model.interaction("gravity")
    fixed_bodies = loaded.initial_bodies()[1:]
    free_mesh = loaded.bodies[0].mesh
    weight = np.zeros((len(fixed_bodies) + 1, 3))
    weight[0] = gravity.force[0]
    full = SolverOptionsWithout(options).build(flow, args.device)
    split = FrozenArraySolver(SolverOptionsWithout(options).build(flow, args.device), cutoff=0.0)
    rows, raw = [], []
    for x in args.positions:
        bodies = [wb.Body(free_mesh, position=(x, 0.0, 6e-6))] + fixed_bodies
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wb.ContactResolutionWarning)
            t = time.perf_counter()
            exact = full.solve(bodies, forces=weight)
            full_time = time.perf_counter() - t
            for cutoff in args.cutoffs:
                split.cutoff = cutoff
                t = time.perf_counter()
                sol = split.solve(bodies, forces=weight)
                elapsed = time.perf_counter() - t
                raw.append(dict(x_um=x * 1e6, cutoff_um=cutoff * 1e6, near=len(split.near_bodies),
                                velocity_error=rel(sol.velocity[0], exact.velocity[0]),
                                angular_error=rel(sol.angular_velocity[0], exact.angular_velocity[0]),
                                split_s=elapsed, full_s=full_time))
        print(f"x = {x * 1e6:.0f} um: full solve {full_time:.2f} s, U = {exact.velocity[0] * 1e6} um/s", flush=True)
    for cutoff in args.cutoffs:
        at = [r for r in raw if r["cutoff_um"] == cutoff * 1e6]
        rows.append(dict(cutoff_um=cutoff * 1e6, near_mean=np.mean([r["near"] for r in at]),
                         velocity_error_max=max(r["velocity_error"] for r in at),
                         angular_error_max=max(r["angular_error"] for r in at),
                         split_s_median=float(np.median([r["split_s"] for r in at])),
                         full_s_median=float(np.median([r["full_s"] for r in at]))))
    print_table(rows, {"cutoff_um": "{:.0f}", "near_mean": "{:.1f}", "velocity_error_max": "{:.2e}",
                       "angular_error_max": "{:.2e}", "split_s_median": "{:.3f}", "full_s_median": "{:.2f}"})
    write_csv(f"frozen_errors_{args.side}x{args.side}.csv", raw)
    write_csv(f"frozen_errors_{args.side}x{args.side}_summary.csv", rows)
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    cut = [r["cutoff_um"] for r in rows]
    floor = 1e-9  # the split's own error with every cell near is GMRES's; chart it at a floor
    left.semilogy(cut, [max(r["velocity_error_max"], floor) for r in rows], "o-", label="velocity U")
    left.semilogy(cut, [max(r["angular_error_max"], floor) for r in rows], "s--", label="angular velocity")
    left.axhline(1e-3, color="k", lw=0.8, ls=":", label="1e-3 (the default's bound)")
    left.set_xlabel("cut-off between bounding spheres [um]")
    left.set_ylabel(f"largest relative error over {len(args.positions)} positions")
    left.set_title(f"near-far split against the full solve, {args.side} x {args.side} domes")
    right.loglog([r["split_s_median"] for r in rows], [max(r["velocity_error_max"], floor) for r in rows], "o-",
                 label="split (cut-offs)")
    for r in rows:
        right.annotate(f"{r['cutoff_um']:.0f}", (r["split_s_median"], max(r["velocity_error_max"], floor)),
                       fontsize=7, xytext=(3, 3), textcoords="offset points")
    right.axvline(rows[0]["full_s_median"], color="C3", label="full solve (kept blocks)")
    right.set_xlabel("time per solve [s] (median over positions)")
    right.set_ylabel("largest relative error of U")
    right.set_title("accuracy against cost")
    print(save_chart(fig, output(f"frozen_errors_{args.side}x{args.side}.png"), (left, right), legend_size=8))


def rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def SolverOptionsWithout(options):
    """The scene's solver options without the split (the full solve, and the split's inner)."""
    from dataclasses import replace

    return replace(options, near_far_cutoff=None)


def step_case(n: int, steps: int, split: bool, device: str) -> dict:
    """One crossing case in this process: set-up, time per step, peak memory."""
    from warpbem.app import scene as scenes
    from warpbem.dynamics import Simulator

    x = PITCH * ((n - 1) // 2) + 0.5 * PITCH
    overrides = crossing_overrides(n, x)
    loaded = scenes.load(SCENE, overrides)
    model = loaded.model
    if not split:
        from dataclasses import replace

        model = replace(model, solver=SolverOptionsWithout(model.solver))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        sim = Simulator(model, device)
        state = loaded.initial_state()
        sim.frame(state)
        setup = time.perf_counter() - t0
        marks = []
        for k in range(2 * steps):
            state, frame = sim.step(state)
            marks.append(time.perf_counter() - t0)
    per_step = (marks[2 * steps - 1] - marks[steps - 1]) / steps
    return dict(array=f"{n}x{n}", domes=n * n, elements=96 * (n * n + 1), split=split, setup_s=setup,
                step_s=per_step, first_steps_s=marks[steps - 1] - setup, near=int(len(getattr(sim.solver, "near_bodies", []))),
                operator=sim.solver.operator, peak_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
                x_um=float(state.positions[0, 0] * 1e6))


def steps(args):
    rows = []
    cases = [(n, True) for n in args.counts] + [(n, False) for n in args.counts if args.full and n <= args.full_max]
    for n, split in cases:
        command = [sys.executable, __file__, "case", str(n), str(args.steps), "split" if split else "full",
                   "--device", args.device]
        done = subprocess.run(command, capture_output=True, text=True, cwd=Path(__file__).parent)
        if done.returncode:
            print(done.stderr[-3000:], file=sys.stderr)
            raise SystemExit(f"case {n} x {n} failed")
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print_table(rows[-1:], {"setup_s": "{:.1f}", "step_s": "{:.3f}", "first_steps_s": "{:.2f}",
                                "peak_gb": "{:.2f}", "x_um": "{:.1f}"})
    smallest = next(r for r in rows if r["split"] and r["domes"] == min(args.counts) ** 2)
    for r in rows:
        r["step_over_smallest"] = r["step_s"] / smallest["step_s"]
    print()
    print_table(rows, {"setup_s": "{:.1f}", "step_s": "{:.3f}", "first_steps_s": "{:.2f}", "peak_gb": "{:.2f}",
                       "x_um": "{:.1f}", "step_over_smallest": "{:.2f}"})
    write_csv("frozen_steps.csv", rows)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "case":  # a child process of ``steps``
        n, k, mode = int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
        device = sys.argv[sys.argv.index("--device") + 1] if "--device" in sys.argv else "cpu"
        print(json.dumps(step_case(n, k, mode == "split", device)))
        return
    parser = arguments(__doc__)
    parser.add_argument("what", choices=["errors", "steps"])
    parser.add_argument("--side", type=int, default=8)
    parser.add_argument("--cutoffs", type=float, nargs="+",
                        default=[0.0, 5e-6, 10e-6, 15e-6, 20e-6, 30e-6, 40e-6, 60e-6, 90e-6, 150e-6, 1.0])
    parser.add_argument("--positions", type=float, nargs="+",
                        default=[-20e-6, 0.0, 15e-6, 45e-6, 90e-6, 105e-6, 150e-6, 210e-6, 240e-6])
    parser.add_argument("--counts", type=int, nargs="+", default=[3, 8, 32])
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--full", action="store_true", help="also without the split, up to --full-max")
    parser.add_argument("--full-max", type=int, default=8)
    args = parser.parse_args()
    errors(args) if args.what == "errors" else steps(args)


if __name__ == "__main__":
    main()
