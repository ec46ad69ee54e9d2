"""The adhesion state diagram from the runs of ``scenes/state_diagram.toml`` (Chang, Tees &
Hammer 2000, PNAS 97:11262): each run classified from its trajectory by the documented rule of
``warpbem/app/adhesion_states.py`` and drawn on the (reactive compliance, unstressed off-rate)
plane, with the mean velocity over the last half of the run as a fraction of the free one.

    warpbem sweep scenes/state_diagram.toml --output-dir results/state_diagram --workers 2
    python scenes/state_diagram.py [--runs results/state_diagram]

Writes <runs>/states.csv and <runs>/state_diagram.png.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path



from warpbem.app.adhesion_states import classify
from warpbem.app.io import open_result
from warpbem.app.plotting import draw_adhesion_states

HERE = Path(__file__).resolve().parent


def states(runs: Path) -> list[dict]:
    rows = []
    for path in sorted(runs.glob("point*.h5")):
        with open_result(path) as f:
            scene = json.loads(f.attrs["scene"])
            t, x = f["time"][:], f["position"][:, 0, 0]
            bonds, u0 = f["bond_count"][:, 0], f["velocity"][0, 0, 0]
            complete = t[-1] >= scene["time"]["end"] * (1 - 1e-9)
        state, ratio = classify(t, x, bonds, u0)
        rows.append(dict(point=path.stem, off_rate=scene["adhesion"]["off_rate"],
                         reactive_compliance=scene["adhesion"]["reactive_compliance"], state=state,
                         velocity_ratio=ratio, bonds_end=int(bonds[-1]), complete=complete))
    return rows


def chart(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5))
    draw_adhesion_states(ax, rows)
    ax.plot([0.39], [2.4], "*", color="k", markersize=12, label="thesis Table 4.1 (not run here)")
    ax.set_title("adhesion state diagram, sigma = 100 dyn/cm (labels: V / V_free, last half)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=HERE.parent / "results" / "state_diagram")
    args = parser.parse_args()
    rows = states(args.runs)
    if not rows:
        raise SystemExit(f"no runs in {args.runs}: warpbem sweep scenes/state_diagram.toml --output-dir {args.runs}")
    with (args.runs / "states.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    for r in rows:
        print(f"k_r0 = {r['off_rate']:g} /s  r0 = {r['reactive_compliance'] * 1e10:.2g} A  {r['state']:14s}"
              f"  V/V_free = {r['velocity_ratio']:.3g}  bonds {r['bonds_end']}{'' if r['complete'] else '  (partial)'}")
    print("chart:", chart(rows, args.runs / "state_diagram.png"))


if __name__ == "__main__":
    main()
