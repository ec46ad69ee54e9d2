"""Rolling velocity against shear rate for one selectin-like parameter set (issue 24 item 2):
the state diagram's rolling point, k_r0 = 1 /s and r0 = 0.6 A (E-selectin-sLeX: k_r0 0.72-2.2 /s,
r0 0.16-0.48 A, Tees, Waugh & Hammer 2001; docs/reference/adhesion-anchors.md), stiff bonds
(100 dyn/cm) on the rigid 5 um cell of scenes/state_diagram.toml, at 50, 100 and 200 1/s, three
seeds each:

    warpbem sweep scenes/state_diagram.toml --vary adhesion.off_rate=1.0 \\
        --vary adhesion.reactive_compliance=0.6e-10 --vary flow.shear_rate=50,100,200 \\
        --vary adhesion.seed=1,2,3 --output-dir results/rolling_shear --workers 2
    python scenes/rolling_shear.py

Per shear rate: the free velocity (first frame), the mean rolling velocity over the last half
of the run (``warpbem/app/adhesion_states.py``), its ratio to the free one, the state, and the
bonds, each as the mean and range over the seeds. The published trend to set it against
(docs/reference/adhesion-anchors.md, section D): on selectins the rolling velocity rises
little with the wall shear stress and tends to a plateau (Lawrence & Springer 1993; PMC2148129),
where the free velocity rises in proportion. results/rolling_shear.csv and
docs/figures/rolling_shear.png.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from warpbem.app.adhesion_states import classify
from warpbem.app.io import open_result

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch4 import write  # noqa: E402  (the scenes' table writer)

ROOT = Path(__file__).resolve().parent.parent
RUNS = ROOT / "results" / "rolling_shear"


def run(path: Path) -> dict:
    with open_result(path) as f:
        scene = json.loads(f.attrs["scene"])
        t, x = f["time"][:], f["position"][:, 0, 0]
        bonds, free = f["bond_count"][:, 0], f["velocity"][0, 0, 0]
    state, ratio = classify(t, x, bonds, free)
    late = t >= 0.5 * t[-1]
    return dict(shear_rate=scene["flow"]["shear_rate"], seed=scene["adhesion"]["seed"], free_um_s=free * 1e6,
                rolling_um_s=ratio * free * 1e6, ratio=ratio, state=state, bonds_mean=float(bonds[late].mean()),
                t_end_s=t[-1], t=t, x=x)


def main():
    runs = [run(p) for p in sorted(RUNS.glob("point*.h5"))]
    if not runs:
        raise SystemExit(f"{RUNS}: no runs (see this script's docstring)")
    rows = []
    for rate in sorted({r["shear_rate"] for r in runs}):
        group = [r for r in runs if r["shear_rate"] == rate]
        row = dict(shear_rate=rate, seeds=len(group), states=" ".join(r["state"].replace(" ", "_") for r in group))
        for key in ("free_um_s", "rolling_um_s", "ratio", "bonds_mean"):
            values = np.array([r[key] for r in group])
            row[key], row[key + "_range"] = float(values.mean()), f"{values.min():.3g}-{values.max():.3g}"
        rows.append(row)
    write(rows, "rolling_shear.csv")

    from warpbem.app.plotting import _pyplot

    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        left.plot(r["t"] * 1e3, (r["x"] - r["x"][0]) * 1e6, lw=1, label=f"{r['shear_rate']:g} 1/s, seed {r['seed']}")
    left.set(xlabel="time [ms]", ylabel="distance rolled [um]", title="k_r0 = 1 /s, r0 = 0.6 A, 100 dyn/cm")
    left.legend(fontsize=6, ncol=3)
    rates = [r["shear_rate"] for r in rows]
    right.errorbar(rates, [r["rolling_um_s"] for r in rows], fmt="s-", capsize=3, label="rolling (mean of seeds)",
                   yerr=np.array([[r["rolling_um_s"] - float(r["rolling_um_s_range"].split("-")[0]),
                                   float(r["rolling_um_s_range"].split("-")[1]) - r["rolling_um_s"]] for r in rows]).T)
    right.plot(rates, [r["free_um_s"] for r in rows], "o--", label="free (no bonds)")
    right.set(xlabel="shear rate [1/s]", ylabel="velocity [um/s]", xscale="log", yscale="log",
              title="rolling velocity against shear rate (last half of each run)")
    for a in (left, right):
        a.grid(alpha=0.3, which="both")
    right.legend(fontsize=8)
    fig.tight_layout()
    chart = ROOT / "docs" / "figures" / "rolling_shear.png"
    fig.savefig(chart, dpi=120)
    plt.close(fig)
    print("chart:", chart)


if __name__ == "__main__":
    main()
