"""Shape dynamics of deformable cells (thesis ch. 2.3 B, appendix B) from the runs of

    warpbem sweep scenes/fig2_09_11_tank_treading.toml --output-dir results/tank_treading
    warpbem sweep scenes/fig2_13_14_tumbling.toml --output-dir results/tumbling
    warpbem sweep scenes/tumbling_trembling.toml --output-dir results/tumbling_trembling
    warpbem sweep scenes/tumbling_trembling.toml --vary bodies.0.mesh.aspect_ratio=0.625,0.775 \
        --output-dir results/tumbling_trembling_fine
    warpbem sweep scenes/tumbling_trembling.toml --vary Vi=0.2 --vary bodies.0.mesh.aspect_ratio=0.625 \
        --output-dir results/tumbling_trembling_fine2
    warpbem sweep scenes/tumbling_trembling.toml --vary Vi=0.1 --vary bodies.0.mesh.aspect_ratio=0.775,0.8 \
        --vary bodies.0.mesh.subdivisions=6 --output-dir results/tumbling_trembling_k6
    python scenes/thesis_ch2.py

for scenes/README.md:

* tank-treading (figs. 2.9-2.12): each sphere's Taylor deformation D and inclination over the
  last 10 ms beside Roscoe's linear steady state in unbounded shear (warpbem/elastic/
  deformable.py), the shapes in the shear plane and the paths of material points around the
  steady shape: docs/figures/tank_treading.png, results/tank_treading.csv;
* tumbling and trembling (figs. 2.13-2.14, B-1, B-2, and the sweep): each run classified by its
  long axis (``regime``: tumbling if the unwrapped inclination turns through pi, trembling if
  it stays within a band narrower than pi/2 over a run of at least a rigid half Jeffery period)
  and the transition aspect ratio bracketed at each viscous number, beside the thesis (0.85-0.91
  at Vi = 0.1, 0.5-0.75 at Vi = 0.2) and Gao, Hu & Ponte Castaneda 2012 (0.681 at Vi = 0.2):
  docs/figures/tumbling_trembling.png, results/tumbling_trembling.csv.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from warpbem.app.io import open_result
from warpbem.app.xdmf import read_frames
from warpbem.surfaces.body import rotation_matrix

ROOT = Path(__file__).resolve().parent.parent
THESIS = {0.1: (0.85, 0.91), 0.2: (0.5, 0.75)}
GAO_2012 = {0.2: 0.681}


def roscoe(vi):
    """(D, inclination rad) of an elastic sphere in unbounded shear, linear theory."""
    return 5 * vi / (2 * np.sqrt(4 + 9 * vi ** 2)), 0.5 * np.arctan(2 / (3 * vi))


def run_summary(path: Path) -> dict:
    with open_result(path) as f:
        scene = json.loads(f.attrs["scene"])
        t = f["time"][:]
        d, angle = f["taylor_deformation"][:, 0], f["inclination_angle"][:, 0]
    body, flow = scene["bodies"][0], scene["flow"]
    vi = flow["viscosity"] * flow["shear_rate"] / body["shear_modulus"]
    kappa = body["mesh"].get("aspect_ratio", 1.0)
    turned = np.unwrap(2 * angle) / 2  # the long axis has no sign: period pi
    half_period = np.pi * (kappa + 1 / kappa) / flow["shear_rate"]  # rigid Jeffery, eq. 2.33
    band = turned.max() - turned.min()
    if band >= np.pi:
        regime = "tumbling"
    elif band < np.pi / 2 and t[-1] >= half_period:
        regime = "trembling"
    else:
        regime = "undecided"
    return dict(run=path.stem, Vi=vi, kappa=kappa, wall=flow.get("wall", True), shear_rate=flow["shear_rate"],
                modulus_Pa=body["shear_modulus"], end_s=t[-1], regime=regime, axis_turned_deg=np.degrees(band),
                D_mean=d.mean(), D_min=d.min(), D_max=d.max(), t=t, D=d, angle=turned)


def runs(folder: Path) -> list[dict]:
    return [run_summary(p) for p in sorted(folder.glob("point*.h5"))]


def write(rows, path, keys):
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {path}")


def tank_treading(rows, folder, chart):
    import matplotlib.pyplot as plt
    table = []
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for r in sorted(rows, key=lambda r: r["modulus_Pa"]):
        late = r["t"] >= r["t"][-1] - 10e-3
        d_th, angle_th = roscoe(r["Vi"])
        table.append(dict(modulus_Pa=r["modulus_Pa"], Vi=r["Vi"], D=r["D"][late].mean(), D_roscoe=d_th,
                          inclination_deg=np.degrees(r["angle"][late].mean()), inclination_roscoe_deg=np.degrees(angle_th)))
        label = f"eta = {r['modulus_Pa']:g} Pa (Vi = {r['Vi']:.3g})"
        axes[0].plot(r["t"] * 1e3, r["D"], label=label)
        axes[0].axhline(d_th, color=axes[0].lines[-1].get_color(), ls=":", lw=0.8)
        axes[1].plot(r["t"] * 1e3, np.degrees(r["angle"]), label=label)
    axes[0].set(xlabel="t [ms]", ylabel="Taylor deformation D", title="D (dotted: Roscoe, unbounded)")
    axes[1].set(xlabel="t [ms]", ylabel="inclination [deg]", title="long axis from the flow direction")
    softest = min(rows, key=lambda r: r["modulus_Pa"])
    meshes, t, pos, quat, disp = read_frames(folder / f"{softest['run']}.h5")
    mesh, ax = meshes[0], axes[2]
    section = np.flatnonzero(np.abs(mesh.nodes[:, 1]) < 0.05 * np.abs(mesh.nodes).max())  # y = 0 nodes
    marked = section[:: max(1, len(section) // 6)]
    for frame, style in ((0, "k."), (len(t) - 1, "b.")):
        world = (mesh.nodes + disp[frame, 0, :len(mesh.nodes)]) @ rotation_matrix(quat[frame, 0]).T
        ax.plot(world[section, 0] * 1e6, world[section, 2] * 1e6, style, ms=3,
                label="reference" if frame == 0 else f"t = {t[frame] * 1e3:.0f} ms")
    late = np.flatnonzero(t >= t[-1] - 20e-3)
    paths = np.array([(mesh.nodes[marked] + disp[f, 0, marked]) @ rotation_matrix(quat[f, 0]).T for f in late])
    for j in range(len(marked)):
        ax.plot(paths[:, j, 0] * 1e6, paths[:, j, 2] * 1e6, "-", lw=0.8, color="tab:red")
    ax.plot([], [], "-", color="tab:red", label="material points, last 20 ms")
    ax.set(xlabel="x [um] (flow)", ylabel="z [um] (about the centre)", aspect="equal",
           title=f"shear-plane section, eta = {softest['modulus_Pa']:g} Pa")
    for a in axes:
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(chart, dpi=130)
    print(f"wrote {chart}")
    return table


def transitions(rows):
    """{(Vi, wall): (largest tumbling kappa, smallest trembling kappa above it)}."""
    out = {}
    for key in sorted({(r["Vi"], r["wall"]) for r in rows}):
        group = sorted((r for r in rows if (r["Vi"], r["wall"]) == key), key=lambda r: r["kappa"])
        tumbling = [r["kappa"] for r in group if r["regime"] == "tumbling"]
        trembling = [r["kappa"] for r in group if r["regime"] == "trembling" and (not tumbling or r["kappa"] > max(tumbling))]
        out[key] = (max(tumbling) if tumbling else None, min(trembling) if trembling else None)
    return out


def tumbling_chart(sweep, thesis_cases, chart):
    import matplotlib.pyplot as plt
    vis = sorted({round(r["Vi"], 6) for r in sweep + thesis_cases})
    fig, axes = plt.subplots(1, len(vis) + 1, figsize=(5 * (len(vis) + 1), 4.2))
    for ax, vi in zip(axes, vis):
        for r in sorted((r for r in sweep + thesis_cases if round(r["Vi"], 6) == vi), key=lambda r: r["kappa"]):
            style = "-" if not r["wall"] else "--"
            ax.plot(r["t"] * r["shear_rate"], np.degrees(r["angle"]), style, lw=1,
                    label=f"kappa {r['kappa']:g}{' wall' if r['wall'] else ''}: {r['regime']}")
        ax.set(xlabel="gdot t", ylabel="long axis, unwrapped [deg]", title=f"Vi = {vi:g}")
        ax.legend(fontsize=6)
    ax = axes[-1]
    for r in sweep:
        ax.plot(r["kappa"], r["Vi"], "o" if r["regime"] == "tumbling" else ("s" if r["regime"] == "trembling" else "x"),
                color={"tumbling": "tab:blue", "trembling": "tab:orange"}.get(r["regime"], "gray"), mfc="none")
    for vi, (low, high) in THESIS.items():
        ax.plot([low, high], [vi, vi], "k-", lw=4, alpha=0.3, label="thesis transition" if vi == 0.1 else None)
    for vi, kappa in GAO_2012.items():
        ax.plot(kappa, vi, "k*", ms=10, label="Gao et al. 2012")
    ax.plot([], [], "o", color="tab:blue", mfc="none", label="tumbling (this model)")
    ax.plot([], [], "s", color="tab:orange", mfc="none", label="trembling (this model)")
    ax.set(xlabel="aspect ratio kappa", ylabel="Vi = mu gdot / eta", title="regimes (unbounded sweep)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(chart, dpi=130)
    print(f"wrote {chart}")


def main():
    results, figures = ROOT / "results", ROOT / "docs" / "figures"
    keys = ["run", "Vi", "kappa", "wall", "shear_rate", "modulus_Pa", "end_s", "regime", "axis_turned_deg",
            "D_mean", "D_min", "D_max"]
    if (results / "tank_treading").is_dir():
        table = tank_treading(runs(results / "tank_treading"), results / "tank_treading",
                              figures / "tank_treading.png")
        write(table, results / "tank_treading.csv", list(table[0]))
        for row in table:
            print({k: round(v, 4) for k, v in row.items()})
    sweep = [r for name in ("tumbling_trembling", "tumbling_trembling_fine", "tumbling_trembling_fine2")
             if (results / name).is_dir() for r in runs(results / name)]
    if (results / "tumbling_trembling_k6").is_dir():  # the bracket's ends again at k = 6 (216 elements)
        for r in runs(results / "tumbling_trembling_k6"):
            print(f"k = 6: Vi = {r['Vi']:g}, kappa = {r['kappa']:g}: {r['regime']} (axis turned"
                  f" {r['axis_turned_deg']:.0f} deg)")
    thesis_cases = runs(results / "tumbling") if (results / "tumbling").is_dir() else []
    if sweep or thesis_cases:
        write(sweep + thesis_cases, results / "tumbling_trembling.csv", keys)
        for r in sweep + thesis_cases:
            print({k: r[k] for k in keys})
        for (vi, wall), (low, high) in transitions(sweep + thesis_cases).items():
            print(f"Vi = {vi:g}{' (wall)' if wall else ''}: tumbling up to kappa = {low}, trembling from {high};"
                  f" thesis {THESIS.get(round(vi, 6))}, Gao et al. 2012 {GAO_2012.get(round(vi, 6))}")
        tumbling_chart(sweep, thesis_cases, figures / "tumbling_trembling.png")


if __name__ == "__main__":
    main()
