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
arrays up to --full-max without the split (every body in every solve), each array with and
then without it (near: the adherent cells in each solve, all of them without the split). --paths: the free cell's path (the flow is along x; the cell
starts mid-array and moves with it), one or more of
  between   (the default, the scene's own): 6 um high (1 um over the wall), midway between the
            two middle rows, 15 um from each row's centre line (lateral gap 5 um to the domes),
            starting midway between two columns;
  along     directly above a row of domes (the row at y = -15 um, the lower of the two middle
            rows), the cell's lowest point 1.5 um above the domes' top (the top taken from the
            dome's mesh: 8.75 um above the wall, so the centre is 15.25 um high), starting midway
            between two columns: it passes over the next dome's top with a 1.5 um gap;
  diagonal  the same array rotated by 45 degrees about its centre (positions and orientations of
            the domes; so seen along the flow, staggered rows 30/sqrt(2) = 21.2 um apart, domes
            42.4 um apart in a row, each row shifted by half of that), the cell 6 um high midway
            between the two diagonal rows through the centre (10.6 um from each: it passes a dome
            every 21.2 um, on alternating sides, at a closest gap of 0.69 um), starting midway
            between two of them. This is the path of a cell crossing the unrotated array along
            its diagonal, between two diagonal lines of domes.
Each path's table gives step_over_smallest: the step against the same path's and mode's smallest
array (the issue's check: 8 x 8 over 3 x 3 with the split <= 3), and amortised_s: (set-up + N
steps) / N with N = --amortise (the split's background solve is in its set-up, the first frame);
the cpu_ columns the same in process time (all the process's threads), which other work on a
shared machine moves less than the wall-clock time.
--tag names the CSV and chart (frozen_steps_TAG.csv / .png; without, frozen_steps.csv).

suspension: scenes/sedimenting_over_array.toml (64 free cells over 16 x 16 domes): the free
cells' velocities by the split at --suspension-cutoffs against the full solve (the treecode) at
the start (time: a solve after the free cells moved 0.1 um), then the scene's set-up, time per
step (k = --scene-steps) and memory.

    python benchmarks/frozen.py errors [--side 8] [--cutoffs ...] [--positions ...] [--replot]
    python benchmarks/frozen.py steps [--counts 3 8 32] [--steps 5] [--full] [--full-max 8]
                                      [--paths between along diagonal] [--amortise 100] [--tag NAME]
    python benchmarks/frozen.py suspension [--suspension-cutoffs 0 10e-6 40e-6] [--scene-steps 1]
"""

import csv
import json
import resource
import subprocess
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "array_crossing.toml"
SUSPENSION = "sedimenting_over_array.toml"
PITCH = 30e-6


def row_offset(n: int) -> float:
    """y of the first row, so that y = 0 lies between the two middle rows (glance 15 um)."""
    return -0.5 * PITCH - PITCH * ((n - 1) // 2)


def crossing_overrides(n: int, x: float | None = None, y: float = 0.0, z: float = 6e-6) -> list:
    out = [f"arrays.0.count=[{n},{n}]", f"arrays.0.origin=[0,{row_offset(n)!r},4.5e-6]"]
    if x is not None:
        out.append(f"bodies.0.position=[{x!r},{y!r},{z!r}]")
    return out


PATHS = ("between", "along", "diagonal")
ALONG_GAP = 1.5e-6  # m: the free cell's lowest point above the domes' top on the path "along"
DIAGONAL_DEG = 45.0  # the array's rotation for the path "diagonal"


def mesh_heights():
    """(the domes' top above the wall, the free cell's radius), m, from the scene's meshes."""
    from warpbem.app import scene as scenes

    loaded = scenes.load(SCENE, crossing_overrides(1))
    free, dome = loaded.bodies[0], loaded.bodies[1]
    top = dome.position[2] + float(np.asarray(dome.mesh.nodes)[:, 2].max())
    return top, float(np.linalg.norm(np.asarray(free.mesh.nodes), axis=1).max())


def path_case(path: str, n: int) -> tuple[list, dict | None]:
    """The scene overrides and the layout (``step_case``) of the free cell's ``path`` over an
    n x n array (module docstring, steps)."""
    x_mid = PITCH * ((n - 1) // 2) + 0.5 * PITCH  # midway between two columns
    if path == "between":
        return crossing_overrides(n, x_mid), None
    if path == "along":
        top, radius = mesh_heights()
        return crossing_overrides(n, x_mid, row_offset(n) + PITCH * ((n - 1) // 2), top + ALONG_GAP + radius), None
    if path == "diagonal":
        centre = np.array([0.5 * (n - 1) * PITCH, row_offset(n) + 0.5 * (n - 1) * PITCH])
        half = 0.5 * PITCH / np.sqrt(2.0)  # half the distance between diagonal rows (10.6 um)
        x, y = centre + [-half, half]
        # the scene loads (its placement checked) with the cell at its own start before the array
        return crossing_overrides(n), dict(rotate_deg=DIAGONAL_DEG, about=centre.tolist(), free=[x, y, 6e-6])
    raise ValueError(f"unknown path {path!r}: one of {PATHS}")


def rotated_array(loaded, degrees: float, about, free=None):
    """The scene with its fixed bodies turned by ``degrees`` about the vertical through ``about``
    (x, y; m): positions and orientations; the free cell (body 0) moved to ``free`` (m) if given."""
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    turn = np.array([np.cos(a / 2), 0.0, 0.0, np.sin(a / 2)])

    def product(p, q):  # quaternions [w, x, y, z]
        w1, v1, w2, v2 = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])
        return (w1 * w2 - v1 @ v2, *(w1 * v2 + w2 * v1 + np.cross(v1, v2)))

    bodies = []
    for b in loaded.bodies:
        if b.fixed:
            dx, dy = b.position[0] - about[0], b.position[1] - about[1]
            b = replace(b, position=(about[0] + c * dx - s * dy, about[1] + s * dx + c * dy, b.position[2]),
                        orientation=tuple(float(v) for v in product(turn, b.orientation)))
        elif free is not None and not bodies:
            b = replace(b, position=tuple(float(v) for v in free))
        bodies.append(b)
    return replace(loaded, bodies=tuple(bodies))


def errors(args):
    import warpbem as wb
    from warpbem.app import scene as scenes
    from warpbem.dynamics.model import build_solver
    from warpbem.hydro.frozen import FrozenArraySolver

    loaded = scenes.load(SCENE, crossing_overrides(args.side))
    model = loaded.model
    options = model.solver
    flow = model.flow
    gravity = model.bound("gravity")
    fixed_bodies = loaded.initial_bodies()[1:]
    free_mesh = loaded.bodies[0].mesh
    weight = np.zeros((len(fixed_bodies) + 1, 3))
    weight[0] = gravity.force[0]
    full = build_solver(without_split(options), flow, args.device)
    split = FrozenArraySolver(build_solver(without_split(options), flow, args.device), cutoff=0.0)
    rows, raw, progress = [], [], Progress(len(args.positions))
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
        progress.done(f"x = {x * 1e6:.0f} um: full solve {full_time:.2f} s, U = {exact.velocity[0] * 1e6} um/s")
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
    plot_errors(rows, args.side, len(args.positions))


def plot_errors(rows, side, n_positions):
    """Left: the largest error over the positions against the cut-off (a cut-off past the array,
    every cell near, drawn as a line); right: error against the time per solve."""
    from warpbem.hydro.frozen import DEFAULT_CUTOFF

    default_um = DEFAULT_CUTOFF * 1e6
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    finite = [r for r in rows if r["cutoff_um"] < 1e5]
    every = [r for r in rows if r["cutoff_um"] >= 1e5]
    cut = [r["cutoff_um"] for r in finite]
    left.semilogy(cut, [r["velocity_error_max"] for r in finite], "o-", label="velocity U")
    left.semilogy(cut, [r["angular_error_max"] for r in finite], "s--", label="angular velocity")
    for r in every:
        left.axhline(r["velocity_error_max"], color="C2", lw=0.8, label="every cell near (GMRES tolerance)")
    left.axhline(1e-3, color="k", lw=0.8, ls=":", label="1e-3")
    left.axvline(default_um, color="C3", lw=0.8, ls="--", label=f"default {default_um:g} um")
    left.set_xlabel("cut-off between bounding spheres [um]")
    left.set_ylabel(f"largest relative error over {n_positions} positions")
    left.set_title(f"near-far split against the full solve, {side} x {side} domes")
    right.loglog([r["split_s_median"] for r in rows], [r["velocity_error_max"] for r in rows], "o-",
                 label="split (cut-off in um)")
    for r in rows:
        label = "all" if r["cutoff_um"] >= 1e5 else f"{r['cutoff_um']:.0f}"
        right.annotate(label, (r["split_s_median"], r["velocity_error_max"]), fontsize=7, xytext=(3, 3),
                       textcoords="offset points")
    right.axvline(rows[0]["full_s_median"], color="C3", label="full solve (kept blocks)")
    right.set_xlabel("time per solve [s] (median over positions)")
    right.set_ylabel("largest relative error of U")
    right.set_title("accuracy against cost")
    print(save_chart(fig, output(f"frozen_errors_{side}x{side}.png"), (left, right), legend_size=8))


def rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def without_split(options):
    """The scene's solver options without the split (the full solve, and the split's inner)."""
    return replace(options, near_far_split="off")


def step_case(scene: str, overrides: list, steps: int, split: bool, device: str, layout: dict | None = None) -> dict:
    """One run in this process: set-up (the first frame), time per step as (T(2k) - T(k)) / k,
    peak memory. layout: {"rotate_deg": a, "about": [x, y]} turns the fixed bodies (``rotated_array``)."""
    from warpbem.app import scene as scenes
    from warpbem.dynamics import Simulator
    from warpbem.surfaces.placement import check_placement

    loaded = scenes.load(ROOT / "scenes" / scene, overrides)
    if layout:
        loaded = rotated_array(loaded, layout["rotate_deg"], layout["about"], layout.get("free"))
        check_placement(loaded.initial_bodies(), loaded.model.flow.wall)
    model = loaded.model
    # the split forced on or off: the scene's "auto" would decide by the array's size
    model = replace(model, solver=replace(model.solver, near_far_split="on") if split else without_split(model.solver))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0, c0 = time.perf_counter(), time.process_time()
        sim = Simulator(model, device)
        state = loaded.initial_state()
        sim.frame(state)
        setup, cpu_setup = time.perf_counter() - t0, time.process_time() - c0
        marks, cpu = [], []
        for k in range(2 * steps):
            state, frame = sim.step(state)
            marks.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
    per_step = (marks[2 * steps - 1] - marks[steps - 1]) / steps
    cpu_step = (cpu[2 * steps - 1] - cpu[steps - 1]) / steps
    end = state.positions[0]
    return dict(bodies=model.n_bodies, domes=int(model.fixed_mask.sum()),
                travel_um=float(np.linalg.norm(end - loaded.bodies[0].position)) * 1e6,
                elements=int(sum(len(m.elements) for m in model.meshes)), split=split, setup_s=setup,
                step_s=per_step, cpu_setup_s=cpu_setup, cpu_step_s=cpu_step, first_steps_s=marks[steps - 1] - setup,
                near=int(len(sim.mobility.near_bodies)) if split else int(model.fixed_mask.sum()), operator=sim.mobility.operator_description,
                peak_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6)


def run_case(scene: str, overrides: list, steps: int, split: bool, device: str, layout: dict | None = None) -> dict:
    """``step_case`` in a process of its own (its own peak memory)."""
    command = [sys.executable, __file__, "case", scene, json.dumps(overrides), str(steps),
               "split" if split else "full", "--device", device, "--layout", json.dumps(layout)]
    done = subprocess.run(command, capture_output=True, text=True, cwd=Path(__file__).parent)
    if done.returncode:
        print(done.stderr[-3000:], file=sys.stderr)
        raise SystemExit(f"{scene} {overrides} failed")
    return json.loads(done.stdout.strip().splitlines()[-1])


STEP_FORMATS = {"setup_s": "{:.1f}", "step_s": "{:.3f}", "first_steps_s": "{:.2f}", "peak_gb": "{:.2f}",
                "step_over_smallest": "{:.2f}", "amortised_s": "{:.3f}", "travel_um": "{:.1f}",
                "cpu_setup_s": "{:.1f}", "cpu_step_s": "{:.3f}", "cpu_over_smallest": "{:.2f}",
                "cpu_amortised_s": "{:.3f}"}


def steps(args):
    """Each path's arrays, each with the split and then (--full) without, side by side."""
    # each array with the split and then without, side by side (the shared machine's load drifts)
    cases = [(path, n, split) for path in args.paths for n in args.counts for split in (True, False)
             if split or (args.full and n <= args.full_max)]
    rows, progress = [], Progress(len(cases))
    for path, n, split in cases:
        overrides, layout = path_case(path, n)
        row = run_case(SCENE.name, overrides, args.steps, split, args.device, layout)
        rows.append(dict(path=path, array=f"{n}x{n}", **row))
        print_table(rows[-1:], STEP_FORMATS)
        progress.done(f"{path}, {n} x {n}, {'split' if split else 'full'}")
    for r in rows:
        same = [q for q in rows if q["path"] == r["path"] and q["split"] == r["split"]]
        smallest = min(same, key=lambda q: q["domes"])
        r["step_over_smallest"] = r["step_s"] / smallest["step_s"]
        r["amortised_s"] = (r["setup_s"] + args.amortise * r["step_s"]) / args.amortise
        if "cpu_step_s" in r:  # process time (all threads): less moved by other work on a shared machine
            r["cpu_over_smallest"] = r["cpu_step_s"] / smallest["cpu_step_s"]
            r["cpu_amortised_s"] = (r["cpu_setup_s"] + args.amortise * r["cpu_step_s"]) / args.amortise
    print()
    print_table(rows, STEP_FORMATS)
    name = f"frozen_steps_{args.tag}" if args.tag else "frozen_steps"
    print(write_csv(f"{name}.csv", rows))
    plot_steps(rows, name, args.amortise)


def plot_steps(rows, name, amortise):
    """Per path (colour), split (solid) and not (dashed): the time per step, the step against
    the smallest array's, and (set-up + N steps) / N against the number of domes."""
    from warpbem.hydro.frozen import DEFAULT_CUTOFF

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    paths = list(dict.fromkeys(r["path"] for r in rows))
    for c, path in enumerate(paths):
        for split in (True, False):
            at = sorted((r for r in rows if r["path"] == path and r["split"] == split), key=lambda r: r["domes"])
            if not at:
                continue
            style = dict(color=f"C{c}", ls="-" if split else "--", marker="o" if split else "s",
                         label=f"{path}, {'split ' + format(DEFAULT_CUTOFF * 1e6, 'g') + ' um' if split else 'no split'}")
            domes = [r["domes"] for r in at]
            for ax, key in zip(axes, ("step_s", "step_over_smallest", "amortised_s")):
                ax.plot(domes, [r[key] for r in at], **style)
    ticks = sorted({r["domes"] for r in rows})
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xticks(ticks, [str(t) for t in ticks])
        ax.minorticks_off()
        ax.set_xlabel("adherent domes (n x n, 30 um pitch)")
    axes[0].set_yscale("log")
    axes[0].set_ylabel("time per step [s]")
    axes[0].set_title("step cost, free cell crossing the array")
    axes[1].axhline(3.0, color="k", lw=0.8, ls=":", label="3 (issue 23)")
    axes[1].set_ylabel("step / the smallest array's step")
    axes[1].set_title("against the smallest array, same path and mode")
    axes[2].set_yscale("log")
    axes[2].set_ylabel(f"(set-up + {amortise} steps) / {amortise} [s]")
    axes[2].set_title(f"set-up amortised over {amortise} steps")
    print(save_chart(fig, output(f"{name}.png"), axes, legend_size=7))


def suspension(args):
    """The 64 free cells over 16 x 16 domes: each free cell's velocity by the split at each of
    --suspension-cutoffs against the full solve (treecode) at the start; then the scene's time
    per step, set-up and memory with its own cut-off."""
    import warpbem as wb
    from warpbem.app import scene as scenes
    from warpbem.dynamics.model import build_solver
    from warpbem.hydro.frozen import FrozenArraySolver

    loaded = scenes.load(ROOT / "scenes" / SUSPENSION)
    model, bodies = loaded.model, loaded.initial_bodies()
    weight = model.bound("gravity").force
    free = ~model.fixed_mask
    # the full solve, each cut-off, then the scene's steps
    rows, progress = [], Progress(1 + len(args.suspension_cutoffs) + (args.scene_steps > 0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        full = build_solver(without_split(model.solver), model.flow, args.device)
        t = time.perf_counter()
        exact = full.solve(bodies, forces=weight)
        rows.append(dict(solve="full", cutoff_um=float("nan"), near=int(model.fixed_mask.sum()),
                         time_s=time.perf_counter() - t, iterations=exact.iterations, operator=exact.operator_mode,
                         velocity_error_max=0.0, angular_error_max=0.0))
        print_table(rows[-1:])
        progress.done("full solve")
        del full
        for cutoff in args.suspension_cutoffs:
            split = FrozenArraySolver(build_solver(without_split(model.solver), model.flow, args.device), cutoff)
            t = time.perf_counter()
            split.solve(bodies, forces=weight)  # the background set up, and the first solve
            first = time.perf_counter() - t
            # a solve as in a step: the free cells moved on (0.1 um), the near system rebuilt
            moved = [b if b.fixed else wb.Body(b.mesh, position=b.position + [1e-7, 0.0, 0.0]) for b in bodies]
            t = time.perf_counter()
            iterations = split.solve(moved, forces=weight).iterations
            elapsed = time.perf_counter() - t
            sol = split.solve(bodies, forces=weight)
            rows.append(dict(solve=f"split (set-up + first {first:.0f} s)", cutoff_um=cutoff * 1e6,
                             near=len(split.near_bodies), time_s=elapsed, iterations=iterations,
                             operator=sol.operator_mode,
                             velocity_error_max=max(rel(sol.velocity[i], exact.velocity[i]) for i in np.flatnonzero(free)),
                             angular_error_max=max(rel(sol.angular_velocity[i], exact.angular_velocity[i])
                                                   for i in np.flatnonzero(free))))
            print_table(rows[-1:])
            progress.done(f"split, cut-off {cutoff * 1e6:g} um")
    print()
    print_table(rows, {"velocity_error_max": "{:.2e}", "angular_error_max": "{:.2e}", "time_s": "{:.1f}"})
    write_csv("frozen_suspension.csv", rows)
    if not args.scene_steps:
        return
    run = run_case(SUSPENSION, [], args.scene_steps, True, args.device)
    progress.done(f"the scene's {args.scene_steps} steps")
    print_table([run], STEP_FORMATS)
    write_csv("frozen_suspension_steps.csv", [run])


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "case":  # a child process of ``run_case``
        scene, overrides, k, mode = sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
        device = sys.argv[sys.argv.index("--device") + 1] if "--device" in sys.argv else "cpu"
        layout = json.loads(sys.argv[sys.argv.index("--layout") + 1]) if "--layout" in sys.argv else None
        print(json.dumps(step_case(scene, overrides, k, mode == "split", device, layout)))
        return
    parser = arguments(__doc__)
    parser.add_argument("what", choices=["errors", "steps", "suspension"])
    parser.add_argument("--side", type=int, default=8)
    parser.add_argument("--cutoffs", type=float, nargs="+",
                        default=[0.0, 5e-6, 10e-6, 15e-6, 20e-6, 30e-6, 40e-6, 60e-6, 90e-6, 150e-6, 1.0])
    parser.add_argument("--positions", type=float, nargs="+",
                        default=[-20e-6, 0.0, 15e-6, 45e-6, 90e-6, 105e-6, 150e-6, 210e-6, 240e-6])
    parser.add_argument("--counts", type=int, nargs="+", default=[3, 8, 32])
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--full", action="store_true", help="also without the split, up to --full-max")
    parser.add_argument("--full-max", type=int, default=8)
    parser.add_argument("--paths", nargs="+", choices=PATHS, default=["between"],
                        help="steps: the free cell's paths (module docstring)")
    parser.add_argument("--amortise", type=int, default=100, help="steps: N of (set-up + N steps) / N")
    parser.add_argument("--tag", default="", help="steps: the CSV and chart frozen_steps_TAG")
    parser.add_argument("--scene-steps", type=int, default=1, help="suspension: k of the scene's steps (0: none)")
    parser.add_argument("--suspension-cutoffs", type=float, nargs="+", default=[0.0, 10e-6, 40e-6])
    parser.add_argument("--replot", action="store_true", help="errors: chart the last run's CSV again")
    args = parser.parse_args()
    if args.what == "errors" and args.replot:
        with output(f"frozen_errors_{args.side}x{args.side}_summary.csv").open() as f:
            rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
        plot_errors(rows, args.side, len(args.positions))
    else:
        {"errors": errors, "steps": steps, "suspension": suspension}[args.what](args)


if __name__ == "__main__":
    main()
