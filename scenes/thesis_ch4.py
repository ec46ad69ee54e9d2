"""Adhesion results (thesis ch. 4, and ch. 5 with bonds) from the runs of the adhesive scene
files, for scenes/README.md:

    warpbem sweep scenes/fig4_04_06_stiff_bonds.toml --output-dir results/fig4_04_06_stiff_bonds
    warpbem sweep scenes/fig4_09_11_soft_bonds.toml --output-dir results/fig4_09_11_soft_bonds
    warpbem sweep scenes/fig4_12_14_bond_cap.toml --output-dir results/fig4_12_14_bond_cap
    warpbem sweep scenes/fig4_07_11_compliant_rolling.toml --output-dir results/compliant_rolling
    warpbem run scenes/rolling_cells.toml --output results/rolling_cells.h5
    warpbem sweep scenes/state_diagram.toml --vary adhesion.off_rate=1.0 \
        --vary adhesion.reactive_compliance=0.6e-10 --vary adhesion.seed=1,2,3,4,5 \
        --output-dir results/rolling_alone
    warpbem run scenes/free_meets_rolling.toml --output results/free_meets_rolling.h5
    warpbem sweep scenes/recruitment_capture.toml --output-dir results/recruitment_capture
    warpbem sweep scenes/collision_binding.toml --output-dir results/collision_binding
    python scenes/thesis_ch4.py

Table 1 (results/thesis_ch4.csv), solitary rolling, figs. 4.4-4.14. The thesis ran 2000
(figs. 4.4-4.6) and 10000 steps (figs. 4.12-4.14) of 1e-8 - 1e-6 s, so it reports at most 2 and
10 ms of rolling; each run here gives the velocity at those times, when the cell came to rest
(velocity below 1 % of the free one), the distance it rolled, its bonds at the end, and its
Hertz contact area (mean over the run and at the end); for deformable cells (the
compliant_rolling runs) also the largest node displacement of the run. The chart
docs/figures/compliant_rolling.png sets the deformable cells' velocities beside the
rigid-with-Hertz cells' of the same parameters.

Table 3 (results/rolling_cells.csv), several rolling cells against the lone one: each cell's
velocity before any bond (its hydrodynamic velocity, where the neighbours act first) and its mean
velocity from release over the trio's run (60 ms), beside the same figures of the lone cell of
the same parameters (the state diagram's k_r0 = 1 /s, r0 = 0.6 A point, seeds 1-5).

Table 2 (results/adhesion_summary.csv), several rolling cells, a free cell meeting a rolling
one, recruitment by capture, binding to an adherent cell: each adhesive free cell's state by the rule of
``warpbem/app/adhesion_states.py``, its mean velocity over the last half of the run (a line
fitted to x(t)) and over the whole run, the time of its first bond and its velocity from then
on (a capture late in a run leaves the last half mostly free), its velocity in the first frame (before any bond: the
hydrodynamic velocity, where neighbours show first), its bonds, and how close its microvillus tips came to the wall (closest
surface gap less the 175 nm tips).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path


import numpy as np

from warpbem.app.adhesion_states import classify
from warpbem.app.io import open_result

ROOT = Path(__file__).resolve().parent.parent
ROUGHNESS = 175e-9
ROLLING = ["fig4_04_06_stiff_bonds", "fig4_09_11_soft_bonds", "compliant_rolling", "compliant_tether",
           "fig4_12_14_bond_cap"]


def rolling(path: Path, label: str) -> list[dict]:
    """Table 1 row of a solitary rolling run."""
    with open_result(path) as f:
        t, u = f["time"][:], f["velocity"][:, 0, 0]
        x = f["position"][:, 0, 0]
        bonds, area = f["bond_count"][:, 0], f["contact_area"][:, 0]
        shaped = "deformation_node_displacement" in f
        displacement = np.abs(f["deformation_node_displacement"][:]).max() if shaped else float("nan")
    rest = np.flatnonzero(u < 0.01 * u[0])
    return [dict(run=label, free_um_s=u[0] * 1e6, **{f"u_{ms}ms_um_s": np.interp(ms * 1e-3, t, u) * 1e6 if ms * 1e-3 <= t[-1] * (1 + 1e-9)
                                                   else float("nan") for ms in (1, 2, 5, 7, 10)},
                 u_end_um_s=u[-1] * 1e6, rest_ms=t[rest[0]] * 1e3 if len(rest) else float("nan"),
                 rolled_um=(x[-1] - x[0]) * 1e6, bonds_end=int(bonds[-1]), bonds_max=int(bonds.max()),
                 area_mean_um2=np.mean(area) * 1e12, area_end_um2=area[-1] * 1e12, t_end_ms=t[-1] * 1e3,
                 largest_displacement_nm=displacement * 1e9)]


def save_chart(plt, fig, ax, path: Path, legend_size: float) -> Path:
    """Grid and legend on ``ax``, the figure laid out, written to ``path`` (120 dpi) and closed."""
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# (deformable runs, their rigid-with-Hertz counterparts point by point, what they are)
COMPLIANT = [("compliant_rolling", "fig4_09_11_soft_bonds", "soft bonds (0.5 dyn/cm), figs. 4.7-4.11"),
             ("compliant_tether", "fig4_04_06_stiff_bonds", "stiff bonds (100 dyn/cm), figs. 4.3-4.6")]


def compliant_rolling_chart(path: Path) -> Path | None:
    """U(t) of the deformable cells (results/compliant_rolling, results/compliant_tether)
    beside the rigid-with-Hertz cells of the same parameters (results/fig4_09_11_soft_bonds,
    results/fig4_04_06_stiff_bonds), point by point, one panel per bond stiffness."""
    from warpbem.app.plotting import _pyplot

    panels = [(title, [(ROOT / "results" / rigid / p.name, p) for p in sorted((ROOT / "results" / shaped).glob("point*.h5"))])
              for shaped, rigid, title in COMPLIANT]
    panels = [(title, pairs) for title, pairs in panels if pairs]
    if not panels:
        return None
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(6.5 * len(panels), 4.5), squeeze=False)
    for ax, (title, pairs) in zip(axes[0], panels):
        for rigid, shaped in pairs:
            with open_result(shaped) as f:
                scene = json.loads(f.attrs["scene"])
                t, u = f["time"][:], f["velocity"][:, 0, 0]
            body = scene["bodies"][0]
            label = f"a = {body['mesh']['radius'] * 1e6:g} um, G = {body['shear_modulus'] / 1e3:g} kPa"
            line, = ax.plot(t * 1e3, u * 1e6, lw=2, label=f"{label}: deformable")
            if rigid.exists():
                end = t[-1]
                with open_result(rigid) as f:
                    t, u = f["time"][:], f["velocity"][:, 0, 0]
                keep = t <= end * 1.05  # over the deformable run's time
                ax.plot(t[keep] * 1e3, u[keep] * 1e6, "--", color=line.get_color(), lw=1,
                        label=f"{label}: rigid, Hertz patch")
        ax.set(xlabel="time [ms]", ylabel="rolling velocity U [um/s]", title=title)
        if ax is not axes[0][-1]:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    fig.suptitle("deformable cells against rigid ones with a Hertz patch", fontsize=10)
    return save_chart(plt, fig, axes[0][-1], path, legend_size=7)


def tethered_profile_chart(path: Path) -> Path | None:
    """Thesis fig. 4.3: the profile in the plane of shear (y = 0) of the deformable tethered
    cells at the end of their runs (results/compliant_tether), their lowest region, against the
    undeformed sphere and the Hertz surface of the same normal bond force (the flattening the
    rigid-with-Hertz model puts below its elements)."""
    from warpbem.app.plotting import _pyplot
    from warpbem.app.scene import parse
    from warpbem.forces import hertz
    from warpbem.surfaces.body import rotation_matrix

    runs = sorted((ROOT / "results" / "compliant_tether").glob("point*.h5"))
    if not runs:
        return None
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for run in runs:
        with open_result(run) as f:
            scene = json.loads(f.attrs["scene"])
            position, orientation = f["position"][-1, 0], f["orientation"][-1, 0]
            u = f["deformation_node_displacement"][-1, 0]
            force, t_end = float(f["contact_force"][-1, 0]), float(f["time"][-1])
        body = scene["bodies"][0]
        mesh = parse(scene, ROOT / "scenes").model.meshes[0]
        radius, modulus, nu = body["mesh"]["radius"], body["shear_modulus"], body["poisson_ratio"]
        section = np.abs(mesh.nodes[:, 1]) < 1e-6 * radius  # the rolling turns about y: the plane stays
        rotation = rotation_matrix(orientation)
        rigid = mesh.nodes[section] @ rotation.T + position
        shaped = (mesh.nodes[section] + u[:len(mesh.nodes)][section]) @ rotation.T + position
        low = rigid[:, 2] < position[2] - 0.8 * radius
        order = np.argsort(rigid[low, 0] - position[0])
        label = f"G = {modulus / 1e3:g} kPa, {force * 1e9:.2g} nN at {t_end * 1e3:g} ms"
        line, = ax.plot((shaped[low, 0][order] - position[0]) * 1e6, shaped[low, 2][order] * 1e9, "o-", ms=3, lw=1.5,
                        label=f"{label}: deformable mesh (y = 0 nodes)")
        rho, bottom = np.linspace(-2.5e-6, 2.5e-6, 401), position[2] - radius
        patch = hertz.contact_radius(force, radius, hertz.compliance(modulus, nu))
        # as the rigid-with-Hertz model places it (kernels/bonds.py): the flat on the plane of the
        # closest point, the rest brought down by up to the approach delta = a_s^2 / R
        ax.plot(rho * 1e6, (bottom + hertz.surface_height(rho, patch, radius)) * 1e9, "--", color=line.get_color(),
                lw=1, label=f"{label}: Hertz surface, a_s = {patch * 1e6:.2g} um (eq. 4.9)")
    ax.plot(rho * 1e6, (bottom + rho**2 / (2 * radius)) * 1e9, ":", color="0.4", lw=1, label="undeformed sphere (last run)")
    ax.set(xlabel="x - X [um] (flow direction)", ylabel="height above the wall [nm]", ylim=(0, 1000),
           title="fig. 4.3: the tethered compliant cell's contact (stiff bonds)")
    return save_chart(plt, fig, ax, path, legend_size=7)


def cells(path: Path, label: str) -> list[dict]:
    """Table 2 rows: one per adhesive free cell of a run."""
    rows = []
    with open_result(path) as f:
        names = json.loads(f.attrs["body_names"])
        scene = json.loads(f.attrs["scene"])
        t, x, z = f["time"][:], f["position"][:, :, 0], f["position"][:, :, 2]
        u, bonds = f["velocity"][:, :, 0], f["bond_count"][:]
    for i, name in enumerate(names):
        body = scene["bodies"][i]
        if body.get("fixed", False):
            continue
        state, ratio = classify(t, x[:, i], bonds[:, i], u[0, i])
        half = t >= 0.5 * t[-1]
        lowest_tip = (z[:, i] - body["mesh"]["radius"]).min() - ROUGHNESS
        bound = np.flatnonzero(bonds[:, i] > 0)
        since = slice(bound[0], None) if len(bound) else slice(0, 0)
        since_bond = (np.polyfit(t[since], x[since, i], 1)[0] * 1e6 if len(t[since]) >= 3 else float("nan"))
        rows.append(dict(run=label, cell=name, state=state, velocity_um_s=np.polyfit(t[half], x[half, i], 1)[0] * 1e6,
                         mean_velocity_um_s=(x[-1, i] - x[0, i]) / (t[-1] - t[0]) * 1e6,
                         free_velocity_um_s=u[0, i] * 1e6, bonds_max=int(bonds[:, i].max()),
                         bonds_end=int(bonds[-1, i]), lowest_tip_nm=lowest_tip * 1e9,
                         first_bond_ms=t[bound[0]] * 1e3 if len(bound) else float("nan"),
                         velocity_since_bond_um_s=since_bond))
    return rows


def release(path: Path, label: str, window: float) -> list[dict]:
    """Table 3 rows: each cell's velocity before any bond and its mean velocity over ``window``
    seconds from release."""
    with open_result(path) as f:
        names = json.loads(f.attrs["body_names"])
        t, x, u = f["time"][:], f["position"][:, :, 0], f["velocity"][:, :, 0]
    if t[-1] < window * (1 - 1e-9):
        print(f"{path}: ends at {t[-1]:g} s, before the {window:g} s window: left out")
        return []
    x_end = np.array([np.interp(window, t, x[:, i]) for i in range(len(names))])
    return [dict(run=label, cell=name, bondless_um_s=u[0, i] * 1e6,
                 mean_um_s=(x_end[i] - x[0, i]) / window * 1e6) for i, name in enumerate(names)]


def several_rolling_chart(trio: Path, lone: list[Path], window: float, path: Path) -> Path:
    """x(t) of the three cells and of the lone cell's seeds over the trio's run."""
    from warpbem.app.plotting import _pyplot

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    with open_result(trio) as f:
        names = json.loads(f.attrs["body_names"])
        t, x = f["time"][:], f["position"][:, :, 0]
    for i, name in enumerate(names):
        ax.plot(t * 1e3, (x[:, i] - x[0, i]) * 1e6, lw=2, label=f"{name} cell of three, 12 um apart")
    for k, p in enumerate(lone):
        with open_result(p) as f:
            t, x = f["time"][:], f["position"][:, 0, 0]
        keep = t <= window * (1 + 1e-9)
        ax.plot(t[keep] * 1e3, (x[keep] - x[0]) * 1e6, color="0.5", lw=1, label="lone cell (seeds 1-5)" if k == 0 else None)
    ax.set(xlabel="time [ms]", ylabel="distance rolled [um]",
           title="rigid 5 um cells on stiff bonds (k_r0 = 1 /s, r0 = 0.6 A), 100 1/s")
    return save_chart(plt, fig, ax, path, legend_size=8)


def several_rolling() -> list[dict]:
    trio = ROOT / "results" / "rolling_cells.h5"
    if not trio.exists():
        print("rolling_cells: no run (see this script's docstring)")
        return []
    with open_result(trio) as f:
        window = float(f["time"][-1])
    lone = sorted((ROOT / "results" / "rolling_alone").glob("point*.h5"))  # seeds 1-5
    rows = release(trio, "three cells 12 um apart", window)
    for path in lone:
        if path.exists():
            with open_result(path) as f:
                seed = json.loads(f.attrs["scene"])["adhesion"]["seed"]
            rows += release(path, f"lone cell, seed {seed}", window)
    print("chart:", several_rolling_chart(trio, [p for p in lone if p.exists()], window,
                                          ROOT / "docs" / "figures" / "rolling_cells.png"))
    alone = [r for r in rows if r["run"].startswith("lone")]
    if alone:
        for r in rows:
            r["bondless_vs_lone"] = r["bondless_um_s"] / alone[0]["bondless_um_s"]
        means = np.array([r["mean_um_s"] for r in alone])
        print(f"lone cell over {window * 1e3:g} ms: mean velocity {means.mean():.1f} um/s, SD {means.std(ddof=1) if len(means) > 1 else float('nan'):.1f}"
              f" over {len(means)} seeds")
    return rows


def sweep(name: str, table) -> list[dict]:
    """The rows of every point of the sweep in results/<name>."""
    summary = ROOT / "results" / name / "summary.csv"
    if not summary.exists():
        print(f"{name}: no runs (see this script's docstring)")
        return []
    rows = []
    with summary.open() as f:
        for point in csv.DictReader(f):
            path = Path(point["file"])
            label = ", ".join(f"{k} = {v}" for k, v in point.items() if k != "file" and not k.endswith("_m"))
            rows += table(path if path.is_absolute() else ROOT / path, f"{name}: {label}")
    return rows


def sweep_folders(argv: list[str], name: str) -> list[Path]:
    """The sweep folders named on the command line, else results/<name>."""
    return [Path(arg) for arg in argv] or [ROOT / "results" / name]


def write(rows: list[dict], name: str):
    if not rows:
        return
    out = ROOT / "results" / name
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    keys = list(rows[0])
    print(" | ".join(keys))
    for r in rows:
        print(" | ".join(f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys))
    print("table:", out, "\n")


def main():
    write([row for name in ROLLING for row in sweep(name, rolling)], "thesis_ch4.csv")
    print("chart:", compliant_rolling_chart(ROOT / "docs" / "figures" / "compliant_rolling.png"))
    print("chart:", tethered_profile_chart(ROOT / "docs" / "figures" / "compliant_tether.png"))
    single = ROOT / "results" / "free_meets_rolling.h5"
    write(several_rolling(), "rolling_cells.csv")
    trio = ROOT / "results" / "rolling_cells.h5"
    write((cells(trio, "rolling_cells") if trio.exists() else [])
          + (cells(single, "free_meets_rolling") if single.exists() else [])
          + sweep("recruitment_capture", cells) + sweep("collision_binding", cells), "adhesion_summary.csv")


if __name__ == "__main__":
    main()
