"""Adhesion cost and accuracy (issue 9 items 1, 4, 10), on the machine it runs on, side by side:

1. bond kernels: bonds per second of the loads (geometry + per-cell sums, eq. 4.3-4.4) and of
   the kinetics (rupture, formation, insertion) for 1e3 - 1e5 bonds over many cells, beside
   the time of one mobility solve of a k = 4 cell near the wall;
2. mobility reuse: one cell captured from the free stream (thesis figs. 4.9-4.11 setup: a = 5
   um, sigma = 0.5 dyn/cm, G = 4 kPa, 100 1/s), solved at every state (the reference) and
   from snapshots on lattices of 0.5 - 20 nm, same seed and steps: the error of the distance
   rolled before arrest, of the velocity history and of the bond count, against the speed-up;
   and (2b) the change of two cells' grand mobility when one moves along the flow by 12.5 -
   200 nm, the error of a lateral lattice of twice that; (2c) the error of the several-body
   snapshots' height lattice, with and without each cell's self part moved to its own height;
3. the step: kinetics_fraction (k dt per step) from 0.4 to 0.025, 8 seeds each: mean distance
   to arrest and bonds at the end, against the cost;
4. wall time per simulated second of one rolling cell (k = 4, the scene defaults) and of four
   cells rolling side by side with full hydrodynamic interaction; (4b, part "scene") of a scene
   file, e.g. --scene scenes/rolling_cells.toml --simulated 0.02.

    python benchmarks/adhesion.py [--quick] [--device cuda:0]

Writes results/bench/adhesion_*.csv and adhesion.png.
"""

import csv
import time
import warnings

import numpy as np

import warpbem as wb
from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.dynamics.model import Flow, Model, SolverOptions, StepPolicy, build_solver
from warpbem.dynamics.simulator import Simulator
from warpbem.forces.adhesion import Adhesion
from warpbem.forces.bond_model import BondOptions
from warpbem.forces.external import STANDARD_GRAVITY, Gravity
from warpbem.forces.repulsion import Repulsion
from warpbem.surfaces.body import Body
from warpbem.surfaces.gaps import Contacts, GapFinder

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A = 5e-6
REST = A + 236e-9  # m: centre height where gravity and eq. 3.1 balance
TABLE_4_1 = dict(receptor_density=20e12, spring_constant=5e-4, equilibrium_length=30e-9, off_rate=2.4,
                 reactive_compliance=0.39e-10, on_rate=365.0)


def kernel_throughput(device, sizes):
    """Bonds per second of the bond loads and of one kinetics pass, and one solve's time."""
    mesh = wb.mesh.sphere(A, 2)
    rows, progress = [], Progress(len(sizes))
    for cells, cap in sizes:
        meshes = [mesh] * cells
        positions = np.array([[30e-6 * (i % 32), 30e-6 * (i // 32), REST] for i in range(cells)])
        bonds = Adhesion(BondOptions(**TABLE_4_1, max_bonds=cap))
        adh = bonds.bound(Model(meshes, [False] * cells, interactions=[bonds]), device)
        bodies = [Body(mesh, position=p) for p in positions]
        contacts = Contacts(bodies, [mesh.size()] * cells, True, GapFinder(device))
        part = adh.initial_state(bodies)
        rng = np.random.default_rng(0)
        for c in range(cells):  # a full table: receptors of the cell, anchors 10-50 nm below their tips
            start, end = adh.receptor_start[c], adh.receptor_start[c + 1]
            picked = rng.choice(np.arange(start, end), size=cap, replace=False)
            part["receptor"][c * cap:(c + 1) * cap] = picked
            tips = positions[c] + adh.tips[picked]
            part["anchor"][c * cap:(c + 1) * cap] = tips - [0, 0, 30e-9] - rng.uniform(0, 20e-9, (cap, 1)) * [0, 0, 1]
        frame = adh._frame(bodies, contacts, part)
        table = adh._table(part)

        def loads():
            vector, moment = adh.geometry(table, frame)
            adh.reduce(table[0], moment, adh.tip_forces(vector.numpy()))

        def kinetics():
            adh.advance_state(part, bodies, bodies, contacts, 1e-4, 1e-4)

        for fn in (loads, kinetics):
            fn()  # warm-up (compilation)
        t_loads = min(_timed(loads) for _ in range(3))
        t_kin = min(_timed(kinetics) for _ in range(3))
        n = cells * cap
        rows.append(dict(cells=cells, bonds=n, receptors=len(adh.tips), loads_s=t_loads, loads_bonds_per_s=n / t_loads,
                         kinetics_s=t_kin, kinetics_receptors_per_s=len(adh.tips) / t_kin))
        progress.done(f"bond kernels: {cells} cells, {n} bonds")
    solver = build_solver(SolverOptions(), Flow(100.0, 1e-3), device)
    solver.keep_systems = False  # from scratch: no kept blocks, no warm start
    mesh4 = wb.mesh.sphere(A, 4)
    solver.solve([Body(mesh4, position=(0, 0, REST))])
    t_solve = min(_timed(lambda: solver.solve([Body(mesh4, position=(0, 0, REST))])) for _ in range(3))
    for r in rows:
        r["loads_per_solve"] = r["loads_s"] / t_solve
    return rows, t_solve


def _timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def rolling_model(k=3, reuse=2e-9, fraction=0.1, seed=1, dt_max=1e-4, cells=1, spacing=15e-6):
    mesh = wb.mesh.sphere(A, k)
    n = cells
    gravity = Gravity([1050.0] * n, 1000.0, STANDARD_GRAVITY)
    bonds = Adhesion(BondOptions(**TABLE_4_1, seed=seed, max_bonds=200, kinetics_fraction=fraction), shear_modulus=[4e3] * n)
    model = Model([mesh] * n, [False] * n, Flow(100.0, 1e-3), interactions=[gravity, Repulsion(), bonds],
                  solver=SolverOptions(reuse_tolerance=reuse), policy=StepPolicy(dt_max, 1e-7, 1e-9), scheme="euler")
    positions = [[0.0, spacing * (i - (n - 1) / 2), REST] for i in range(n)]
    return model, model.initial_state(positions)


def roll(model, state, end, device):
    sim = Simulator(model, device)
    t0 = time.perf_counter()
    times, u, bonds = [state.time], [sim.frame(state).velocity[:, 0]], [0]
    while state.time < end:
        state, frame = sim.step(state, end)
        times.append(state.time)
        u.append(frame.velocity[:, 0])
        bonds.append(int(frame.parts["bond"]["count"].sum()))  # over all cells
    return dict(wall=time.perf_counter() - t0, steps=state.steps, snapshots=sim.hydro.snapshots_solved,
                x=state.positions[:, 0], t=np.array(times), u=np.array(u), bonds=np.array(bonds))


def reuse_chart(device, tolerances, end):
    runs, progress = {}, Progress(1 + len(tolerances))
    for d in [0.0] + tolerances:
        runs[d] = roll(*rolling_model(reuse=d), end, device)
        progress.done(f"reuse {d * 1e9:g} nm: {runs[d]['wall']:.1f} s")
    ref = runs[0.0]
    rows = []
    for d, r in runs.items():
        rows.append(dict(reuse_nm=d * 1e9, wall_s=r["wall"], speedup=ref["wall"] / r["wall"],
                         snapshots=r["snapshots"], steps=r["steps"], rolled_um=r["x"][0] * 1e6,
                         rolled_error=abs(r["x"][0] - ref["x"][0]) / ref["x"][0],
                         velocity_rms_error=np.sqrt(np.mean((r["u"][:, 0] - ref["u"][:, 0]) ** 2)) / ref["u"][0, 0],
                         bonds_end=int(r["bonds"][-1]), bonds_error=int(r["bonds"][-1] - ref["bonds"][-1])))
    return rows


def lateral_error(device, spacing, shifts):
    """Relative change of two rolling cells' grand mobility (and flow motion) when one moves
    along the flow by each shift: the error of a lateral snapshot lattice of twice that."""
    mesh = wb.mesh.sphere(A, 3)
    model = Model([mesh, mesh], [False, False], Flow(100.0, 1e-3), solver=SolverOptions())
    from warpbem.dynamics.hydrodynamics import HydrodynamicSolves

    hydro = HydrodynamicSolves(model, build_solver(model.solver, model.flow, device))

    def mobility(shift):
        bodies = [Body(mesh, position=(0.0, 0.0, REST)), Body(mesh, position=(spacing + shift, 0.0, REST))]
        flow = hydro.mobility.solve(bodies)
        grand = hydro._grand_mobility(bodies).quadratic()
        return grand, np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])

    grand0, flow0 = mobility(0.0)
    rows, progress = [], Progress(len(shifts))
    for shift in shifts:
        grand, flow = mobility(shift)
        rows.append(dict(spacing_um=spacing * 1e6, shift_nm=shift * 1e9,
                         grand_mobility_change=np.abs(grand - grand0).max() / np.abs(grand0).max(),
                         flow_motion_change=np.abs(flow - flow0).max() / np.abs(flow0).max()))
        progress.done(f"lateral shift {shift * 1e9:g} nm")
    return rows


def interaction_error(device, spacing, lattices, fine=0.5e-9):
    """Error of the several-body snapshots on a height lattice D (hydrodynamics.py): two cells
    ``spacing`` apart along the flow at the rest height, at heights 0.4 D above and below the
    lattice point (on the fine lattice, so only the interaction lattice errs), from the split
    snapshot (interaction at the lattice point, each cell's self part at its own height) and
    from the interaction snapshot alone, against the exact solve there."""
    mesh = wb.mesh.sphere(A, 3)
    from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion

    def motion(flow, grand):
        return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])

    def change(a, b):  # of the grand mobility and of the motion in the flow
        return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]

    rows, progress = [], Progress(2 * len(lattices))
    for lattice in lattices:
        model = Model([mesh, mesh], [False, False], Flow(100.0, 1e-3),
                      solver=SolverOptions(reuse_tolerance=fine, reuse_lateral=spacing / 8, reuse_interaction=lattice))
        hydro = HydrodynamicSolves(model, build_solver(model.solver, model.flow, device))
        base = np.round(REST / lattice) * lattice
        for name, offsets in (("opposite", (0.4, -0.4)), ("same", (0.4, 0.4))):
            bodies = [Body(mesh, position=(0.0, 0.0, base + offsets[0] * lattice)),
                      Body(mesh, position=(spacing, 0.0, base + offsets[1] * lattice))]
            exact = motion(Motion.of(hydro.mobility.solve(bodies)),
                           hydro._grand_mobility(bodies))
            split = motion(*hydro._snapshot(bodies))
            coarse = motion(*hydro._kept(*hydro._snapped(bodies, lattice), lambda b: None))
            (grand_split, flow_split), (grand_coarse, flow_coarse) = change(split, exact), change(coarse, exact)
            rows.append(dict(lattice_nm=lattice * 1e9, heights=name, grand_split=grand_split,
                             grand_interaction_only=grand_coarse, flow_split=flow_split,
                             flow_interaction_only=flow_coarse))
            progress.done(f"height lattice {lattice * 1e9:g} nm, heights {name}")
    return rows


def step_chart(device, fractions, seeds, end):
    rows, progress = [], Progress(len(fractions) * seeds)
    for f in fractions:
        runs = []
        for s in range(seeds):
            runs.append(roll(*rolling_model(fraction=f, seed=s, dt_max=1.0), end, device))
            progress.done(f"kinetics fraction {f:g}, seed {s}: {runs[-1]['wall']:.1f} s")
        rolled = np.array([r["x"][0] for r in runs]) * 1e6
        bonds = np.array([r["bonds"][-1] for r in runs])
        rows.append(dict(kinetics_fraction=f, dt_s=np.mean([np.diff(r["t"]).mean() for r in runs]),
                         wall_s=np.mean([r["wall"] for r in runs]),
                         rolled_um=rolled.mean(), rolled_se=rolled.std(ddof=1) / np.sqrt(seeds),
                         bonds_end=bonds.mean(), bonds_se=bonds.std(ddof=1) / np.sqrt(seeds)))
    ref = rows[-1]
    for r in rows:
        r["speedup"] = ref["wall_s"] / r["wall_s"]
        r["rolled_error"] = abs(r["rolled_um"] - ref["rolled_um"]) / ref["rolled_um"]
    return rows


def speed(device, end, cells):
    rows, progress = [], Progress(len(cells))
    for n in cells:
        model, state = rolling_model(k=4, reuse=2e-9, fraction=0.1, dt_max=1.0, cells=n)
        r = roll(model, state, end, device)
        rows.append(dict(cells=n, simulated_s=end, wall_s=r["wall"], wall_per_simulated_s=r["wall"] / end,
                         steps=r["steps"], snapshots=r["snapshots"], mean_velocity_um_s=r["x"].mean() / end * 1e6,
                         bonds_end=int(r["bonds"][-1])))
        progress.done(f"{n} cells: {r['wall']:.1f} s")
    return rows


def scene_speed(device, path, end):
    """Wall time per simulated second of a scene file (its model and start, to ``end`` s)."""
    from warpbem.app import scene

    s = scene.load(path, [f"time.end={end}"])
    r = roll(s.model, s.initial_state(), end, device)
    return [dict(scene=str(path), cells=s.model.n_bodies, simulated_s=end, wall_s=r["wall"],
                 wall_per_simulated_s=r["wall"] / end, steps=r["steps"], snapshots=r["snapshots"],
                 mean_velocity_um_s=(r["x"] - s.initial_state().positions[:, 0]).mean() / end * 1e6,
                 bonds_end=int(r["bonds"][-1]))]


def chart(reuse_rows, step_rows, path):
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.5))
    for r in reuse_rows[1:]:
        a.loglog(r["speedup"], max(r["rolled_error"], 1e-6), "o", color="C0")
        a.annotate(f"{r['reuse_nm']:g} nm", (r["speedup"], max(r["rolled_error"], 1e-6)), fontsize=8)
        a.loglog(r["speedup"], max(r["velocity_rms_error"], 1e-6), "s", color="C1")
    a.plot([], [], "o", color="C0", label="distance rolled before arrest")
    a.plot([], [], "s", color="C1", label="velocity history (RMS / free-stream velocity)")
    a.set(xlabel="speed-up over solving every state", ylabel="relative error (same seed, same steps)",
          title="mobility snapshots: lattice spacing")
    a.legend(fontsize=8)
    # the cost of a run is its number of steps (wall times on a shared machine are too noisy)
    x = [r["dt_s"] / step_rows[-1]["dt_s"] for r in step_rows]
    b.semilogx(x, [r["rolled_um"] for r in step_rows], "o-")
    b.errorbar(x, [r["rolled_um"] for r in step_rows], yerr=[2 * r["rolled_se"] for r in step_rows], fmt="none")
    for r, xi in zip(step_rows, x):
        b.annotate(f"k dt = {r['kinetics_fraction']:g}", (xi, r["rolled_um"]), fontsize=8)
    b.set(xlabel="fewer steps than with k dt = %g" % step_rows[-1]["kinetics_fraction"],
          ylabel="distance rolled before arrest [um] (mean, 2 SE)", title="step: kinetics fraction")
    return save_chart(fig, path, (a, b))


def interaction_chart(rows, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for heights, marker in (("opposite", "o"), ("same", "s")):
        sel = [r for r in rows if r["heights"] == heights]
        x = [r["lattice_nm"] for r in sel]
        for key, colour, label in (("grand_split", "C0", "grand mobility, split"),
                                   ("grand_interaction_only", "C1", "grand mobility, interaction snapshot only"),
                                   ("flow_split", "C2", "motion in the flow, split"),
                                   ("flow_interaction_only", "C3", "motion in the flow, interaction snapshot only")):
            ax.loglog(x, [r[key] for r in sel], marker + "-", color=colour, label=f"{label} ({heights})", alpha=0.8)
    ax.set(xlabel="height lattice of the several-body snapshots, reuse_interaction [nm]",
           ylabel="largest change / largest entry, at 0.4 lattice off",
           title="two cells 12 um apart rolling in line: snapshot error")
    return save_chart(fig, path, (ax,), legend_size=6)


def main():
    parser = arguments(__doc__)
    parser.add_argument("--parts", default="kernels,reuse,interaction,step,speed",
                        help="comma-separated parts to run: kernels, reuse (with the lateral lattice), interaction, step,"
                             " speed, scene")
    parser.add_argument("--replot", action="store_true", help="only redraw the chart from the CSV tables")
    parser.add_argument("--cells", default="1,4", help="cell counts of the speed part (default 1,4)")
    parser.add_argument("--simulated", type=float, default=1.0, help="simulated seconds of the speed part")
    parser.add_argument("--scene", help="with the part 'scene': a scene file to time (e.g. scenes/rolling_cells.toml)")
    args = parser.parse_args()
    if args.replot:
        tables = [[{k: float(v) for k, v in row.items()} for row in csv.DictReader(output(name).open())]
                  for name in ("adhesion_reuse.csv", "adhesion_step.csv")]
        print("chart:", chart(*tables, output("adhesion.png")))
        if output("adhesion_interaction.csv").exists():
            rows = [{k: (v if k == "heights" else float(v)) for k, v in row.items()}
                    for row in csv.DictReader(output("adhesion_interaction.csv").open())]
            print("chart:", interaction_chart(rows, output("adhesion_interaction.png")))
        return
    parts = set(args.parts.split(","))
    q = args.quick
    sizes = [(10, 100), (100, 100)] if q else [(10, 100), (100, 100), (1000, 100)]
    if "kernels" in parts:
        rows, t_solve = kernel_throughput(args.device, sizes)
        print(f"\n1. bond kernels on {args.device} (one solve of a k = 4 cell near the wall: {t_solve:.3f} s)")
        print_table(rows)
        write_csv("adhesion_kernels.csv", rows)
    if "reuse" in parts:
        print("\n2. mobility reuse (one cell captured from the free stream, k = 3)")
        reuse_rows = reuse_chart(args.device, [2e-9, 10e-9] if q else [0.5e-9, 1e-9, 2e-9, 5e-9, 10e-9, 20e-9],
                                 0.005 if q else 0.02)
        print_table(reuse_rows)
        write_csv("adhesion_reuse.csv", reuse_rows)
        print("\n2b. lateral lattice: two cells 12 um apart, one moved along the flow")
        lateral_rows = lateral_error(args.device, 12e-6, [25e-9, 50e-9, 100e-9] if q else [12.5e-9, 25e-9, 50e-9,
                                                                                           100e-9, 200e-9])
        print_table(lateral_rows)
        write_csv("adhesion_lateral.csv", lateral_rows)
    if "interaction" in parts:
        print("\n2c. height lattice of the several-body snapshots: two cells 12 um apart along the flow")
        interaction_rows = interaction_error(args.device, 12e-6, [10e-9, 40e-9] if q else [5e-9, 10e-9, 20e-9,
                                                                                        40e-9, 80e-9])
        print_table(interaction_rows)
        write_csv("adhesion_interaction.csv", interaction_rows)
        print("chart:", interaction_chart(interaction_rows, output("adhesion_interaction.png")))
    if "step" in parts:
        print("\n3. step (kinetics fraction; reuse 2 nm)")
        step_rows = step_chart(args.device, [0.4, 0.1, 0.025] if q else [0.4, 0.2, 0.1, 0.05, 0.025], 2 if q else 8,
                               0.005 if q else 0.03)
        print_table(step_rows)
        write_csv("adhesion_step.csv", step_rows)
    if "speed" in parts:
        print("\n4. wall time per simulated second (k = 4, defaults)")
        speed_rows = speed(args.device, 0.02 if q else args.simulated,
                           [1] if q else [int(c) for c in args.cells.split(",")])
        print_table(speed_rows)
        write_csv("adhesion_speed.csv", speed_rows)
    if "scene" in parts:
        print(f"\n4b. wall time per simulated second of {args.scene}")
        scene_rows = scene_speed(args.device, args.scene, args.simulated)
        print_table(scene_rows)
        write_csv("adhesion_scene_speed.csv", scene_rows)
    if {"reuse", "step"} <= parts:
        print("chart:", chart(reuse_rows, step_rows, output("adhesion.png")))


if __name__ == "__main__":
    main()
