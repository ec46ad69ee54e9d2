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

    python benchmarks/deformable_shear.py [--parts theory,interval] [--quick] [--device cuda:0]

Writes results/bench/deformable_theory.csv, deformable_interval.csv and the charts
deformable_theory.png and deformable_interval.png.
"""

import time
import warnings

import numpy as np

import warpbem as wb
from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.dynamics import Flow, Model, Simulator, StepPolicy
from warpbem.elastic.deformable import Deformation

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A, MU, SHEAR, NU = 5e-6, 1e-3, 100.0, 0.33


def roscoe(ca):
    """(D, tilt in rad) of the linear small-deformation steady state (module docstring)."""
    return 5 * ca / (2 * np.sqrt(4 + 9 * ca ** 2)), 0.5 * np.arctan(1.5 * ca)


def cell(k, modulus, dt, wall, device, *, height=0.0, **options):
    mesh = wb.mesh.sphere(A, k)
    flow = Flow(SHEAR, MU, wall)
    model = Model([mesh], [False], flow, policy=StepPolicy(dt, 1e-7, 1e-9), scheme="euler",
                  interactions=[Deformation([mesh], [True], [modulus], [NU], flow, **options)])
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
    rows = []
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
    runs = {}
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


def main():
    parser = arguments(__doc__)
    parser.add_argument("--parts", default="theory,interval")
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


if __name__ == "__main__":
    main()
