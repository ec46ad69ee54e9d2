"""Reproduce thesis ch. 5 (hydrodynamic recruitment, figs. 5.3-5.20): run every case of the
ch. 5 scene files with ``warpbem sweep`` and summarise the free-stream cell's trajectory next to
the thesis's statements.

    python scenes/thesis_ch5.py --run --workers 2   # runs what is missing (about an hour on 2 cores)
    python scenes/thesis_ch5.py                      # table and figures from the runs on disk
    warpbem sweep scenes/fig5_14_18_deformable_free.toml --output-dir results/deformable_free
    python scenes/thesis_ch5.py                      # also tabulates those (issue 10 item 8)

Runs go to results/ch5/<scene>/pointNNN.h5 (the sweep's grid order); this writes
results/ch5/summary.csv (one row per case, lengths in nm; the lone cell of
reference_free_cell.toml gives the sedimentation to subtract) and results/ch5/<scene>.png: the free
cell's height change Z(t) - Z(0) for every case, one panel per value of the scene's first sweep
axis when it has two (as the thesis's figures pair them), and the closest surface gap.

The deformable free cell (scenes/fig5_14_18_deformable_free.toml, results/deformable_free): per
figure and material, the free cell's dZ across the adherent cell, the same for the free cell
alone (the adherent cell 1 mm aside: its own drift over the same path), and their difference,
the adherent cell's net effect (results/deformable_free.csv).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import h5py
import numpy as np

HERE = Path(__file__).resolve().parent
REFERENCE = "reference_free_cell"
SCENES = [REFERENCE, "fig5_03_sphere_glance", "fig5_04_05_shapes", "fig5_07_dome_glance", "fig5_09_box_glance",
          "fig5_11_two_domes", "fig5_12_two_boxes", "fig5_13_14_near_wall", "fig5_16_17_shear",
          "fig5_18_neutral", "fig5_19_20_glance"]


def cases(scene_name):
    from warpbem.app import scene
    from warpbem.app.sweep import grid

    path = HERE / f"{scene_name}.toml"
    return path, grid([], scene.load(path).sweep)


def free_cell_metrics(h5_path, references) -> dict:
    """The free cell's height changes (nm).

    * rise / deepest / final: Z(t) - Z(0) at its highest, lowest and at the end, as the thesis
      reads its figures;
    * across: Z where the cell has passed as far downstream of the adherent cells' middle as it
      started upstream (x' = 2 x_c - x_0) minus Z(0). Without repulsion and gravity Stokes
      reversibility makes every trajectory past a fore-aft symmetric obstacle mirror-symmetric,
      so this is exactly zero; it isolates what the irreversible forces (repulsion in contact,
      gravity) did, while the 'final' value also holds the reversible descent of a cell that
      started on the rising branch of its trajectory, 9 um upstream;
    * settling: the lone cell's sedimentation over the same time from the same height
      (``references``: start height in um -> (t, z); zero without gravity), and across minus
      settling, the adherent cells' own effect.
    """
    with h5py.File(h5_path, "r") as f:
        names = json.loads(f.attrs["body_names"])
        scene = json.loads(f.attrs["scene"])
        i = names.index("free") if "free" in names else 0
        t = f["time"][:]
        x, y, z = (f["position"][:, i, k] for k in range(3))
        fixed_x = [b["position"][0] for b in scene["bodies"] if b.get("fixed", False)]
        closest = float(np.min(f["closest_gap"][:]))
    mirror = 2 * float(np.mean(fixed_x)) - x[0] if fixed_x else np.nan
    reached = np.isfinite(mirror) and x.max() >= mirror
    t_across = float(np.interp(mirror, x, t)) if reached else np.nan
    z_across = float(np.interp(mirror, x, z)) if reached else np.nan

    def settling(time):
        if not scene.get("physics", {}).get("gravity", False) or not np.isfinite(time):
            return 0.0 if np.isfinite(time) else np.nan
        if round(z[0] * 1e6, 2) not in references:  # reference_free_cell.toml not run for this height
            return np.nan
        ref_t, ref_z = references[round(z[0] * 1e6, 2)]
        return float(np.interp(time, ref_t, ref_z) - ref_z[0])

    nm = 1e9
    return {"rise_nm": nm * max(z.max() - z[0], 0.0), "deepest_nm": nm * min(z.min() - z[0], 0.0),
            "final_dz_nm": nm * (z[-1] - z[0]), "across_dz_nm": nm * (z_across - z[0]),
            "settling_across_nm": nm * settling(t_across),
            "adherent_effect_nm": nm * (z_across - z[0] - settling(t_across)),
            "final_dy_nm": nm * (y[-1] - y[0]), "closest_gap_nm": nm * closest,
            "end_time_s": float(t[-1]), "steps": int(len(z) - 1)}


def reference_curves(results) -> dict:
    """Start height (um) -> (t, z) of the lone free cell of reference_free_cell.toml."""
    curves = {}
    for f in sorted((results / REFERENCE).glob("point*.h5")):
        with h5py.File(f, "r") as h:
            z = h["position"][:, 0, 2]
            curves[round(z[0] * 1e6, 2)] = (h["time"][:], z)
    return curves


def plot(scene_name, rows, out_png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes_names = [k for k in rows[0]["labels"]]
    panel_axis = axes_names[0] if len(axes_names) == 2 else None
    panels = list(dict.fromkeys(r["labels"][panel_axis] for r in rows)) if panel_axis else [None]  # in grid order
    fig, axes = plt.subplots(1, len(panels) + 1, figsize=(5 * (len(panels) + 1), 3.8), squeeze=False)
    for k, panel in enumerate(panels):
        ax = axes[0, k]
        for r in rows:
            if panel is not None and r["labels"][panel_axis] != panel:
                continue
            curve = ", ".join(f"{a} {v}" for a, v in r["labels"].items() if a != panel_axis)
            with h5py.File(r["file"], "r") as f:
                names = json.loads(f.attrs["body_names"])
                i = names.index("free")
                t, z = f["time"][:], f["position"][:, i, 2]
                gap = f["closest_gap"][:]
            ax.plot(t, (z - z[0]) * 1e9, label=curve)
            axes[0, -1].plot(t, gap * 1e9, label=", ".join(f"{a} {v}" for a, v in r["labels"].items()))
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set(xlabel="t [s]", ylabel="Z(t) - Z(0) of the free cell [nm]",
               title=f"{panel_axis} {panel}" if panel is not None else scene_name)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, -1].set(xlabel="t [s]", ylabel="closest surface gap [nm]", yscale="log", title="no overlap: gap > 0")
    axes[0, -1].legend(fontsize=7)
    axes[0, -1].grid(alpha=0.3)
    fig.suptitle(f"{scene_name} (thesis ch. 5)")
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)


def deformable_free(folder: Path) -> list[dict]:
    """Rows of the deformable free cell sweep (module docstring), of the runs on disk."""
    _, points = cases("fig5_14_18_deformable_free")
    runs = {}
    for i, (labels, _) in enumerate(points):
        path = folder / f"point{i:03d}.h5"
        if path.exists():
            runs[(labels["case"], labels["cell"], labels["obstacle"])] = free_cell_metrics(path, {})
    rows = []
    for (case, cell, obstacle), metrics in runs.items():
        if obstacle != "adherent" or (case, cell, "none") not in runs:
            continue
        alone = runs[(case, cell, "none")]
        rows.append(dict(case=case, cell=cell, across_dz_nm=metrics["across_dz_nm"],
                         alone_across_dz_nm=alone["across_dz_nm"],
                         adherent_effect_nm=metrics["across_dz_nm"] - alone["across_dz_nm"],
                         rise_nm=metrics["rise_nm"], closest_gap_nm=metrics["closest_gap_nm"],
                         end_time_s=metrics["end_time_s"]))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", action="store_true", help="run the cases that have no result yet")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--results", default="results/ch5")
    args = parser.parse_args()
    results = Path(args.results)
    table = []
    references = {}
    for name in SCENES:
        path, points = cases(name)
        folder = results / name
        files = [folder / f"point{i:03d}.h5" for i in range(len(points))]
        if args.run and not all(f.exists() for f in files):
            from warpbem.app.sweep import sweep

            sweep(path, [], folder, workers=args.workers)
        rows = [{"labels": labels, "file": f} for (labels, _), f in zip(points, files) if f.exists()]
        if name == REFERENCE:
            references = reference_curves(results)
        for r in rows:
            r.update(free_cell_metrics(r["file"], references))
            table.append({"scene": name, "case": ", ".join(f"{k} {v}" for k, v in r["labels"].items()),
                          **{k: v for k, v in r.items() if k not in ("labels", "file")}})
        if rows:
            plot(name, rows, results / f"{name}.png")
    shaped = deformable_free(HERE.parent / "results" / "deformable_free")
    if shaped:
        with (HERE.parent / "results" / "deformable_free.csv").open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(shaped[0]))
            writer.writeheader()
            writer.writerows(shaped)
        print("| case | free cell | dZ across | alone | adherent cell's effect | rise | closest gap | t end [s] |")
        print("|---|---|---|---|---|---|---|---|")
        for r in shaped:
            print(f"| {r['case']} | {r['cell']} | {r['across_dz_nm']:.1f} | {r['alone_across_dz_nm']:.1f}"
                  f" | {r['adherent_effect_nm']:.1f} | {r['rise_nm']:.0f} | {r['closest_gap_nm']:.0f}"
                  f" | {r['end_time_s']:.3f} |")
    if not table:
        raise SystemExit(f"no runs under {results}; use --run")
    with (results / "summary.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(table[0]))
        writer.writeheader()
        writer.writerows(table)
    print("| scene | case | rise | final dZ | dZ across | settling | adherent cells' effect | final dY |"
          " closest gap | t end [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in table:
        if r["scene"] == REFERENCE:
            continue
        print(f"| {r['scene']} | {r['case']} | {r['rise_nm']:.0f} | {r['final_dz_nm']:.0f} | {r['across_dz_nm']:.0f}"
              f" | {r['settling_across_nm']:.0f} | {r['adherent_effect_nm']:.0f} | {r['final_dy_nm']:.0f}"
              f" | {r['closest_gap_nm']:.0f} | {r['end_time_s']:.3f} |")


if __name__ == "__main__":
    main()
