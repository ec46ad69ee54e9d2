"""Deformable cells in shear (issue 10 items 4 and 9): the model against theory, and the cost of
solving its elastic target less often.

1. theory: a free deformable sphere (a = 5 um) in unbounded shear, gdot = 100 1/s, mu = 1 mPa
   s, at Ca = mu gdot / G from 0.01 to 0.2, stepped to its steady shape (10 relaxation times,
   at least 2 ms). Its Taylor deformation D and the tilt of its long axis from 45 degrees
   against the small-deformation theory of an elastic sphere in shear (Roscoe 1967, linear in
   the strain; derived in warpbem/elastic/deformable.py): D = 5 Ca / (2 sqrt(4 + 9 Ca^2)), tilt
   = (1/2) atan(3 Ca / 2); for the relaxing model at k = 4 and 8 and two steps (its first-order
   lag in dt extrapolated away), and for the quasi-static model (no tilt at any Ca).
2. interval: the thesis's stiffest tank-treading cell (G = 23 Pa, Vi = 0.0043, fig. 2.10 c-d)
   7.75 um above the wall, 100 steps of 0.1 ms, its elastic target (the traction and elastic
   solves) updated every m = 1, 2, 4, 8, 16 steps: the error of the node displacements and of
   the path against m = 1, and the speed-up, side by side in one run.
3. speed (item 11): wall time per step of one deformable cell (k = 4 and 8: 96 and 384
   elements; eta = 1 Pa, 7.75 um above the wall, steps of 0.1 ms) against the same cell rigid,
   side by side in one run (rigid and deformable steps interleaved, after two warm-up steps),
   with the deformable step's share spent in the traction and the elastic solves.
4. limits (item 10): where the scheme fails, a k = 4 cell in unbounded shear: the viscous
   number Ca = 0.2, 0.5, 1 (steps of 0.1 ms for 10 tau; the steady D against Roscoe's, the
   largest max |u| / a, what the solver said) and the step at Ca = 0.1 (dt = 0.1 to 10 ms: the
   errors of D and of the tilt from 45 degrees, the turn per step).

    python benchmarks/deformable_shear.py [--parts theory,interval,speed,limits] [--quick] [--device cuda:0]

Writes results/bench/deformable_theory.csv, deformable_interval.csv, deformable_speed.csv,
deformable_limits.csv and the charts deformable_theory.png, deformable_interval.png and
deformable_speed.png.
"""

import time
import warnings

import numpy as np

import warpbem as wb
from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.dynamics import Flow, Model, Simulator, StepPolicy
from warpbem.elastic import deformable, interior
from warpbem.elastic.deformable import Deformation, DeformationOptions

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A, MU, SHEAR, NU = 5e-6, 1e-3, 100.0, 0.33


def roscoe(ca):
    """(D, tilt in rad) of the linear small-deformation steady state (module docstring)."""
    return 5 * ca / (2 * np.sqrt(4 + 9 * ca ** 2)), 0.5 * np.arctan(1.5 * ca)


def cell(k, modulus, dt, wall, device, *, height=0.0, rigid=False, **options):
    mesh = wb.mesh.sphere(A, k)
    flow = Flow(SHEAR, MU, wall)
    shape = [] if rigid else [Deformation([True], [modulus], [NU], DeformationOptions(**options))]
    model = Model([mesh], [False], flow, policy=StepPolicy(dt, 1e-7, 1e-9), scheme="euler", interactions=shape)
    return Simulator(model, device), model.initial_state([[0.0, 0.0, height]])


def steady_shape(k, ca, dt, relaxation, device):
    """D and tilt (rad) at the end of the run, the time per step (s)."""
    sim, state = cell(k, MU * SHEAR / ca, dt, False, device, relaxation=relaxation)
    tau = 1.5 * ca / SHEAR
    steps = int(round(max(10 * tau, 2e-3) / dt)) if relaxation else 3
    start = time.perf_counter()
    for _ in range(steps):
        state, frame = sim.step(state)
    return (frame.derived["taylor_deformation"][0], np.pi / 4 - frame.derived["inclination_angle"][0],
            (time.perf_counter() - start) / steps)


def theory_rows(ks, cas, dts, device):
    rows, progress = [], Progress(len(cas))
    for ca in cas:
        d_exact, tilt_exact = roscoe(ca)
        row = dict(Ca=ca, D_theory=d_exact, tilt_theory_deg=np.degrees(tilt_exact))
        (_, q1, _), (d_qs, q2, _) = (steady_shape(ks[0], ca, dt, False, device) for dt in dts)
        row.update(quasi_static_D=d_qs / d_exact - 1, quasi_static_tilt_deg=np.degrees(2 * q2 - q1))
        for k in ks:
            (d1, t1, s1), (d2, t2, s2) = (steady_shape(k, ca, dt, True, device) for dt in dts)
            tilt = 2 * t2 - t1  # first order in dt (the target's lag): Richardson to dt -> 0
            row.update({f"k{k}_D": d2 / d_exact - 1, f"k{k}_tilt_deg": np.degrees(tilt),
                        f"k{k}_tilt": tilt / tilt_exact - 1, f"k{k}_tilt_dt{dts[-1]:g}": t2 / tilt_exact - 1,
                        f"k{k}_s_per_step": 0.5 * (s1 + s2)})
        rows.append(row)
        print_table([row])
        progress.done(f"Ca = {ca:g}")
    return rows


def theory_chart(rows, ks, path):
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    ca = np.array([r["Ca"] for r in rows])
    fine = np.linspace(0, ca.max() * 1.05, 100)
    d, tilt = roscoe(fine)
    left.plot(fine, d, "k-", label="Roscoe (linear): 5 Ca / (2 sqrt(4 + 9 Ca^2))")
    left.plot(fine, 1.25 * fine, "k:", label="5 Ca / 4")
    right.plot(fine, np.degrees(tilt), "k-", label="Roscoe (linear): atan(3 Ca / 2) / 2")
    for k, marker in zip(ks, "os"):
        left.plot(ca, [roscoe(c)[0] * (1 + r[f"k{k}_D"]) for c, r in zip(ca, rows)], marker, mfc="none",
                  label=f"relaxing model, k = {k}")
        right.plot(ca, [r[f"k{k}_tilt_deg"] for r in rows], marker, mfc="none", label=f"relaxing model, k = {k}")
    left.plot(ca, [roscoe(c)[0] * (1 + r["quasi_static_D"]) for c, r in zip(ca, rows)], "x",
              label="quasi-static model")
    right.plot(ca, [r["quasi_static_tilt_deg"] for r in rows], "x", label="quasi-static model")
    left.set(xlabel="Ca = mu gdot / G", ylabel="Taylor deformation D", title="elastic sphere in shear: D")
    right.set(xlabel="Ca = mu gdot / G", ylabel="45 deg - inclination [deg]", title="tilt of the long axis")
    return save_chart(fig, path, (left, right), legend_size=7)


def interval_rows(intervals, k, steps, device):
    runs, progress = {}, Progress(len(intervals))
    for m in intervals:
        sim, state = cell(k, 23.0, 1e-4, True, device, height=7.75e-6, update_interval=m)
        sim.step(state)  # warm-up: kernels and the cell's elastic operators
        shapes, paths = [], []
        start = time.perf_counter()
        for _ in range(steps):
            state, frame = sim.step(state)
            shapes.append(state.parts["deformation"]["node_displacement"][0].copy())
            paths.append(state.positions[0].copy())
        runs[m] = (time.perf_counter() - start, np.array(shapes), np.array(paths))
        progress.done(f"update interval {m}")
    base_time, base_shape, base_path = runs[intervals[0]]
    scale = np.abs(base_shape).max()
    travel = np.abs(base_path[-1] - base_path[0]).max()
    return [dict(update_interval=m, s_per_step=t / steps, speed_up=base_time / t,
                 shape_error=np.abs(shape - base_shape).max() / scale,
                 path_error=np.abs(path - base_path).max() / travel)
            for m, (t, shape, path) in runs.items()]


def interval_chart(rows, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    speed = [r["speed_up"] for r in rows]
    ax.loglog(speed, [max(r["shape_error"], 1e-12) for r in rows], "o-", label="node displacements")
    ax.loglog(speed, [max(r["path_error"], 1e-12) for r in rows], "s-", label="path (of its travel)")
    for r in rows:
        ax.annotate(f"m={r['update_interval']}", (r["speed_up"], max(r["shape_error"], 1e-12)), fontsize=7)
    ax.set(xlabel="speed-up against solving every step", ylabel="largest error against m = 1",
           title="G = 23 Pa cell at the wall: target solved every m steps")
    return save_chart(fig, path, (ax,), legend_size=8)


class Stopwatch:
    """Wraps a function of a module so that the seconds spent in it add up in ``seconds``."""

    def __init__(self, module, name):
        self.module, self.name, self.inner, self.seconds = module, name, getattr(module, name), 0.0

        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return self.inner(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - start

        setattr(module, name, timed)


def speed_rows(ks, steps, device):
    traction = Stopwatch(deformable, "solve_traction")
    elastic = Stopwatch(interior.InteriorElasticity, "solve")
    rows, progress = [], Progress(len(ks))
    for k in ks:
        runs = {kind: cell(k, 1.0, 1e-4, True, device, height=7.75e-6, rigid=kind == "rigid")
                for kind in ("rigid", "deformable")}
        for sim, state in runs.values():
            for _ in range(2):  # warm-up: kernels, the cell's elastic operators
                state, _ = sim.step(state)
        states = {kind: state for kind, (sim, state) in runs.items()}
        seconds = dict.fromkeys(runs, 0.0)
        traction.seconds = elastic.seconds = 0.0
        for _ in range(steps):
            for kind, (sim, _) in runs.items():
                start = time.perf_counter()
                states[kind], _ = sim.step(states[kind])
                seconds[kind] += time.perf_counter() - start
        rows.append(dict(k=k, elements=6 * k * k, rigid_s_per_step=seconds["rigid"] / steps,
                         deformable_s_per_step=seconds["deformable"] / steps,
                         ratio=seconds["deformable"] / seconds["rigid"],
                         traction_share=traction.seconds / seconds["deformable"],
                         elastic_share=elastic.seconds / seconds["deformable"]))
        print_table(rows[-1:])
        progress.done(f"k = {k}")
    return rows


def speed_chart(rows, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    labels = [f"k = {r['k']} ({r['elements']} el.)" for r in rows]
    x = np.arange(len(rows))
    rigid = np.array([r["rigid_s_per_step"] for r in rows])
    total = np.array([r["deformable_s_per_step"] for r in rows])
    traction = total * [r["traction_share"] for r in rows]
    elastic = total * [r["elastic_share"] for r in rows]
    ax.bar(x - 0.2, rigid, 0.4, label="rigid cell")
    ax.bar(x + 0.2, total - traction - elastic, 0.4, label="deformable: mobility and the rest")
    ax.bar(x + 0.2, traction, 0.4, bottom=total - traction - elastic, label="deformable: traction solve")
    ax.bar(x + 0.2, elastic, 0.4, bottom=total - elastic, label="deformable: elastic solve")
    ax.set_xticks(x, labels)
    ax.set(ylabel="wall time per step [s]", title="one cell 7.75 um above the wall, 2-core CPU")
    return save_chart(fig, path, (ax,), legend_size=8)


def limit_row(ca, dt, device):
    """One run of a k = 4 cell in shear to 10 tau (at least 2 ms, 10 steps): its last D and
    tilt against Roscoe's, the largest max |u| / a, and the solver's warnings or its stop."""
    sim, state = cell(4, MU * SHEAR / ca, dt, False, device)
    steps = max(int(round(max(15 * ca / SHEAR, 2e-3) / dt)), 10)
    d_exact, tilt_exact = roscoe(ca)
    amplitude, outcome, frame = 0.0, "ran", None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", wb.DeformationWarning)
        try:
            for _ in range(steps):
                state, frame = sim.step(state)
                amplitude = max(amplitude, np.abs(state.parts["deformation"]["node_displacement"][0]).max() / A)
        except wb.DeformationError as err:
            outcome = f"stopped at t = {state.time * 1e3:.1f} ms: {str(err).split(':')[1].strip()}"
    said = sorted({str(w.message).split(":")[1].split(",")[0].strip() for w in caught
                   if issubclass(w.category, wb.DeformationWarning)})
    d, tilt = (np.nan, np.nan) if frame is None else (frame.derived["taylor_deformation"][0],
                                                      np.pi / 4 - frame.derived["inclination_angle"][0])
    return dict(Ca=ca, dt_ms=dt * 1e3, turn_per_step=SHEAR / 2 * dt, D=d, D_error=d / d_exact - 1,
                tilt_deg=np.degrees(tilt), tilt_error=tilt / tilt_exact - 1, max_u_over_a=amplitude,
                outcome=outcome if not said else f"{outcome}; warned: {'; '.join(said)}")


def main():
    parser = arguments(__doc__)
    parser.add_argument("--parts", default="theory,interval,speed,limits")
    args = parser.parse_args()
    parts = args.parts.split(",")
    if "theory" in parts:
        ks, cas = ([4], [0.02, 0.1]) if args.quick else ([4, 8], [0.01, 0.02, 0.05, 0.1, 0.2])
        print("1. elastic sphere in unbounded shear against Roscoe's linear theory (errors relative)")
        rows = theory_rows(ks, cas, (1e-4, 5e-5), args.device)
        print_table(rows)
        write_csv("deformable_theory.csv", rows)
        print("chart:", theory_chart(rows, ks, output("deformable_theory.png")))
    if "interval" in parts:
        print("\n2. the elastic target solved every m steps (G = 23 Pa, 7.75 um above the wall)")
        rows = interval_rows([1, 2, 4] if args.quick else [1, 2, 4, 8, 16], 4, 20 if args.quick else 100,
                             args.device)
        print_table(rows)
        write_csv("deformable_interval.csv", rows)
        print("chart:", interval_chart(rows, output("deformable_interval.png")))
    if "speed" in parts:
        print("\n3. wall time per step: one deformable cell against the same cell rigid")
        rows = speed_rows([4] if args.quick else [4, 8], 3 if args.quick else 10, args.device)
        print_table(rows)
        write_csv("deformable_speed.csv", rows)
        print("chart:", speed_chart(rows, output("deformable_speed.png")))
    if "limits" in parts:
        print("\n4. where the scheme fails: the viscous number and the step (k = 4, unbounded shear)")
        cases = [(0.2, 1e-4), (1.0, 1e-4)] if args.quick else [(0.2, 1e-4), (0.5, 1e-4), (1.0, 1e-4), (0.1, 1e-4),
                                                              (0.1, 1e-3), (0.1, 3e-3), (0.1, 1e-2)]
        rows, progress = [], Progress(len(cases))
        for ca, dt in cases:
            rows.append(limit_row(ca, dt, args.device))
            print_table(rows[-1:])
            progress.done(f"Ca = {ca:g}, dt = {dt * 1e3:g} ms")
        print_table(rows)
        write_csv("deformable_limits.csv", rows)


if __name__ == "__main__":
    main()
