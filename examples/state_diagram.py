"""A small adhesion state diagram (Chang, Tees & Hammer 2000, PNAS 97:11262): a rigid 5 um cell on
stiff bonds released at the wall in shear, for two unstressed off-rates k_r0 and two reactive
compliances r0 (Bell's rupture rate k_r = k_r0 exp(r0 F / kT), thesis eq. 4.1), each run
classified as firm adhesion, rolling or no adhesion, printed as a grid and charted.

    python examples/state_diagram.py [--end 0.05] [--subdivisions 3] [--workers 2] \\
        [--output-dir results/state_diagram_2x2]

The runs are ``scenes/state_diagram.toml`` (100 1/s, 1 mPa s, sigma = 100 dyn/cm, the rest of
thesis Table 4.1) swept by ``warpbem.app.sweep.sweep`` (``warpbem sweep``) over k_r0 = 1 and
100 /s and r0 = 0.1 and 1.2 A, in local worker processes; one run file per point and
``summary.csv`` go to the output folder, with ``states.png``. Each run is classified by the
library's rule (``warpbem.app.adhesion_states.classify``): over the last half of the run the mean
velocity along the flow V against the velocity before any bond V_h (the first frame's): firm
adhesion below 1 %, no adhesion from 50 % (or without bonds), rolling between.

The full diagram (scenes/README.md, "The adhesion state diagram": 5 x 4 runs of 0.2 s at k = 3)
has at these four points, V / V_free in brackets:

    k_r0 \\ r0      0.1 A                 1.2 A
    1 /s          firm adhesion (0.0015)   no adhesion (0.67)
    100 /s        rolling (0.11)           no adhesion (0.76)

i.e. the band of rolling runs diagonally between firm adhesion (slow rupture, short reach) and
no adhesion (fast rupture or long reach). SI units at the API (s, m, 1/s).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

from warpbem.app.adhesion_states import classify
from warpbem.app.io import open_result
from warpbem.app.plotting import draw_adhesion_states
from warpbem.app.sweep import sweep

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "state_diagram.toml"
OFF_RATES = (1.0, 100.0)                 # k_r0, 1/s
REACTIVE_COMPLIANCES = (0.1e-10, 1.2e-10)  # r0, m


def run_grid(output_dir, end=0.05, subdivisions=3, workers=2, overrides=()) -> Path:
    """Sweep the 2 x 2 grid to ``end`` (s) with a cell of ``subdivisions`` (k: 6 k^2 elements) on
    ``workers`` local processes; ``overrides``: further scene keys (``key=value``, SI), one value
    each. Returns the sweep's summary.csv (a second call into the same folder resumes it)."""
    varies = [f"adhesion.off_rate={','.join(repr(k) for k in OFF_RATES)}",
              f"adhesion.reactive_compliance={','.join(repr(r) for r in REACTIVE_COMPLIANCES)}",
              f"time.end={end!r}", f"bodies.0.mesh.subdivisions={subdivisions}",
              # the scene's 2 ms frames, closer in runs shorter than 40 ms: the rule reads the last half
              f"time.frame_interval={min(2e-3, end / 20)!r}", *overrides]
    return sweep(SCENE, varies, output_dir, workers=workers)


def states(summary) -> list[dict]:
    """Per point of the summary: k_r0 (1/s), r0 (m), state, V / V_free over the last half and the
    bonds at the end."""
    rows = []
    for point in csv.DictReader(Path(summary).open()):
        with open_result(point["file"]) as f:
            adhesion = json.loads(f.attrs["scene"])["adhesion"]
            t, x, bonds = f["time"][:], f["position"][:, 0, 0], f["bond_count"][:, 0]
            state, ratio = classify(t, x, bonds, f["velocity"][0, 0, 0])
        rows.append({"off_rate": adhesion["off_rate"], "reactive_compliance": adhesion["reactive_compliance"],
                     "state": state, "velocity_ratio": ratio, "bonds_end": int(bonds[-1])})
    return rows


def chart(rows, path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    draw_adhesion_states(ax, rows)  # the full diagram's markers and labels (scenes/state_diagram.py)
    ax.set(xlim=(0.05, 2.5), ylim=(0.3, 300), title="adhesion states (labels: V / V_free, last half of the run)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def main(output_dir="results/state_diagram_2x2", end=0.05, subdivisions=3, workers=2, overrides=()) -> list[dict]:
    rows = states(run_grid(output_dir, end, subdivisions, workers, overrides))
    cell = {(r["off_rate"], r["reactive_compliance"]): r for r in rows}
    print("k_r0 [1/s] \\ r0 [A] | " + " | ".join(f"{r0 * 1e10:^24.2g}" for r0 in REACTIVE_COMPLIANCES))
    for k in OFF_RATES:
        print(f"{k:19g} | " + " | ".join(
            f"{cell[k, r0]['state']:>13s} ({cell[k, r0]['velocity_ratio']:8.2g})" for r0 in REACTIVE_COMPLIANCES))
    print("chart:", chart(rows, Path(output_dir) / "states.png"))
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--end", type=float, default=0.05, help="simulated time per run, s")
    parser.add_argument("--subdivisions", type=int, default=3, help="k: 6 k^2 elements on the cell")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--output-dir", default="results/state_diagram_2x2")
    args = parser.parse_args()
    main(args.output_dir, args.end, args.subdivisions, args.workers)
