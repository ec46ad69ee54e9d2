"""Adhesion results (thesis ch. 4, and ch. 5 with bonds) from the runs of the adhesive scene
files, for scenes/README.md:

    warpbem sweep scenes/fig4_04_06_stiff_bonds.toml --output-dir results/fig4_04_06_stiff_bonds
    warpbem sweep scenes/fig4_09_11_soft_bonds.toml --output-dir results/fig4_09_11_soft_bonds
    warpbem sweep scenes/fig4_12_14_bond_cap.toml --output-dir results/fig4_12_14_bond_cap
    warpbem sweep scenes/rolling_cells.toml --output-dir results/rolling_cells
    warpbem run scenes/free_meets_rolling.toml --output results/free_meets_rolling.h5
    warpbem sweep scenes/recruitment_capture.toml --output-dir results/recruitment_capture
    warpbem sweep scenes/collision_binding.toml --output-dir results/collision_binding
    python scenes/thesis_ch4.py

Table 1 (results/thesis_ch4.csv), solitary rolling, figs. 4.4-4.14. The thesis ran 2000
(figs. 4.4-4.6) and 10000 steps (figs. 4.12-4.14) of 1e-8 - 1e-6 s, so it reports at most 2 and
10 ms of rolling; each run here gives the velocity at those times, when the cell came to rest
(velocity below 1 % of the free one), the distance it rolled, its bonds at the end, and its
Hertz contact area (mean over the run and at the end).

Table 2 (results/adhesion_summary.csv), several rolling cells, a free cell meeting a rolling
one, recruitment by capture, binding to an adherent cell: each adhesive free cell's state by the rule of
``warpbem/app/adhesion_states.py``, its mean velocity over the last half of the run (a line
fitted to x(t)) and over the whole run, its velocity in the first frame (before any bond: the
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
ROLLING = ["fig4_04_06_stiff_bonds", "fig4_09_11_soft_bonds", "fig4_12_14_bond_cap"]


def rolling(path: Path, label: str) -> list[dict]:
    """Table 1 row of a solitary rolling run."""
    with open_result(path) as f:
        t, u = f["time"][:], f["velocity"][:, 0, 0]
        x = f["position"][:, 0, 0]
        bonds, area = f["bond_count"][:, 0], f["contact_area"][:, 0]
    rest = np.flatnonzero(u < 0.01 * u[0])
    return [dict(run=label, free_um_s=u[0] * 1e6,
                 u_2ms_um_s=np.interp(2e-3, t, u) * 1e6, u_10ms_um_s=np.interp(10e-3, t, u) * 1e6,
                 u_end_um_s=u[-1] * 1e6, rest_ms=t[rest[0]] * 1e3 if len(rest) else float("nan"),
                 rolled_um=(x[-1] - x[0]) * 1e6, bonds_end=int(bonds[-1]), bonds_max=int(bonds.max()),
                 area_mean_um2=np.mean(area) * 1e12, area_end_um2=area[-1] * 1e12, t_end_ms=t[-1] * 1e3)]


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
        rows.append(dict(run=label, cell=name, state=state, velocity_um_s=np.polyfit(t[half], x[half, i], 1)[0] * 1e6,
                         mean_velocity_um_s=(x[-1, i] - x[0, i]) / (t[-1] - t[0]) * 1e6,
                         free_velocity_um_s=u[0, i] * 1e6, bonds_max=int(bonds[:, i].max()),
                         bonds_end=int(bonds[-1, i]), lowest_tip_nm=lowest_tip * 1e9))
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
    single = ROOT / "results" / "free_meets_rolling.h5"
    write(sweep("rolling_cells", cells) + (cells(single, "free_meets_rolling") if single.exists() else [])
          + sweep("recruitment_capture", cells) + sweep("collision_binding", cells), "adhesion_summary.csv")


if __name__ == "__main__":
    main()
