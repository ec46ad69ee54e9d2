"""Thesis ch. 4 (solitary rolling, figs. 4.4-4.14) from the runs of the fig4_* scene files:
the figures the thesis reports, from each run, for scenes/README.md.

    warpbem sweep scenes/fig4_04_06_stiff_bonds.toml --output-dir results/fig4_04_06_stiff_bonds
    warpbem sweep scenes/fig4_09_11_soft_bonds.toml --output-dir results/fig4_09_11_soft_bonds
    warpbem sweep scenes/fig4_12_14_bond_cap.toml --output-dir results/fig4_12_14_bond_cap
    python scenes/thesis_ch4.py

The thesis ran 2000 (figs. 4.4-4.6) and 10000 steps (figs. 4.12-4.14) of 1e-8 - 1e-6 s, so it
reports at most 2 and 10 ms of rolling; each run here gives the velocity at those times, when
the cell came to rest (velocity below 1 % of the free one), the distance it rolled, its bonds at
the end, and its Hertz contact area (mean over the run and at the end). Writes
results/thesis_ch4.csv.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import h5py
import numpy as np

HERE = Path(__file__).resolve().parent
SCENES = ["fig4_04_06_stiff_bonds", "fig4_09_11_soft_bonds", "fig4_12_14_bond_cap"]


def metrics(path: Path, labels: str) -> dict:
    with h5py.File(path) as f:
        t, u = f["time"][:], f["velocity"][:, 0, 0]
        x = f["position"][:, 0, 0]
        bonds, area = f["bond_count"][:, 0], f["contact_area"][:, 0]
    rest = np.flatnonzero(u < 0.01 * u[0])
    return dict(scene=path.parent.name, case=labels, free_um_s=u[0] * 1e6,
                u_2ms_um_s=np.interp(2e-3, t, u) * 1e6, u_10ms_um_s=np.interp(10e-3, t, u) * 1e6,
                u_end_um_s=u[-1] * 1e6, rest_ms=t[rest[0]] * 1e3 if len(rest) else float("nan"),
                rolled_um=(x[-1] - x[0]) * 1e6, bonds_end=int(bonds[-1]), bonds_max=int(bonds.max()),
                area_mean_um2=np.mean(area) * 1e12, area_end_um2=area[-1] * 1e12, t_end_ms=t[-1] * 1e3)


def main():
    rows = []
    for name in SCENES:
        folder = HERE.parent / "results" / name
        summary = folder / "summary.csv"
        if not summary.exists():
            print(f"{name}: no runs (warpbem sweep scenes/{name}.toml --output-dir {folder})")
            continue
        with summary.open() as f:
            for point in csv.DictReader(f):
                labels = ", ".join(f"{k} = {v}" for k, v in point.items() if k not in ("file",) and not k.endswith("_m"))
                path = Path(point["file"])
                rows.append(metrics(path if path.is_absolute() else HERE.parent / path, labels))
    if not rows:
        raise SystemExit("no runs found")
    out = HERE.parent / "results" / "thesis_ch4.csv"
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    keys = list(rows[0])
    print(" | ".join(keys))
    for r in rows:
        print(" | ".join(f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys))
    print("table:", out)


if __name__ == "__main__":
    main()
