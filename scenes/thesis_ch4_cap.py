"""Thesis figs. 4.12-4.14 with the 40-bond cap reached (issue 24 item 3): the runs of
scenes/fig4_12_14_cap_reached.toml, tabulated and charted.

    warpbem sweep scenes/fig4_12_14_cap_reached.toml --vary adhesion.seed=1,2,3 \\
        --vary cap=refuse,replace --vary bonds=tension,tension_and_compression \\
        --output-dir results/fig4_12_14_cap_reached --workers 2
    python scenes/thesis_ch4_cap.py

Per case (cap rule x bonds in tension only or also in compression), mean and spread over the
seeds: when the cap was reached; the velocity at 10 ms, the end of the thesis's 10^4 steps of at
most 1 us (fig. 4.12: 1 um/s in tension only, 48 um/s with compression); after the cap, the
mean rolling velocity (distance over time), the root mean square of the frames' velocities (the
thesis's "average rolling velocity (RMS)", fig. 4.13: 135 and 123 um/s; it does not say how it
took the RMS, so both are given), and the contact area's mean and spread (fig. 4.14: noisy after
the cap). results/thesis_ch4_cap.csv; docs/figures/fig4_12_14_cap.png (seed 1: velocity, bonds,
contact area against time, as figs. 4.12-4.14).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from warpbem.app.io import open_result

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch4 import write  # noqa: E402  (the scenes' table writer)

ROOT = Path(__file__).resolve().parent.parent
RUNS = ROOT / "results" / "fig4_12_14_cap_reached"
THESIS_END = 10e-3  # s: 10^4 steps of at most 1 us (thesis L811, L898)
THESIS = {False: "1 um/s at the end; RMS 135 um/s", True: "48 um/s at the end; RMS 123 um/s"}  # L898, L912


def run(path: Path) -> dict:
    """The figures of one run (module docstring)."""
    with open_result(path) as f:
        bonds = json.loads(f.attrs["scene"])["adhesion"]
        t, u, x = f["time"][:], f["velocity"][:, 0, 0], f["position"][:, 0, 0]
        count, area = f["bond_count"][:, 0], f["contact_area"][:, 0]
    full = np.flatnonzero(count >= bonds["max_bonds"])
    after = slice(full[0], None) if len(full) else slice(len(t), None)
    span = t[-1] - t[after][0] if len(full) else float("nan")
    return dict(cap_rule=bonds["cap_rule"], compression=bool(bonds["compression"]), seed=bonds["seed"],
                cap_ms=t[full[0]] * 1e3 if len(full) else float("nan"),
                u_10ms_um_s=np.interp(THESIS_END, t, u) * 1e6,
                mean_after_um_s=(x[-1] - x[after][0]) / span * 1e6 if len(full) else float("nan"),
                rms_after_um_s=np.sqrt(np.mean(u[after] ** 2)) * 1e6 if len(full) else float("nan"),
                area_after_um2=np.mean(area[after]) * 1e12, area_spread_um2=np.std(area[after]) * 1e12,
                bonds_end=int(count[-1]), t_end_ms=t[-1] * 1e3, file=str(path.relative_to(ROOT)),
                series=(t, u, count, area))


def table(runs: list[dict]) -> list[dict]:
    """One row per case: each figure's mean over the seeds and its range."""
    rows = []
    for rule in ("refuse", "replace"):
        for compression in (False, True):
            case = [r for r in runs if r["cap_rule"] == rule and r["compression"] == compression]
            if not case:
                continue
            row = dict(cap_rule=rule, bonds="tension and compression" if compression else "tension only",
                       seeds=len(case), thesis=THESIS[compression])
            for key in ("cap_ms", "u_10ms_um_s", "mean_after_um_s", "rms_after_um_s", "area_after_um2",
                        "area_spread_um2"):
                values = np.array([r[key] for r in case])
                row[key] = float(np.mean(values))
                row[key + "_range"] = f"{np.min(values):.3g}-{np.max(values):.3g}"
            rows.append(row)
    return rows


def chart(runs: list[dict], path: Path) -> Path:
    """Velocity, bonds and contact area against time of each case's first seed (figs. 4.12-4.14)."""
    from warpbem.app.plotting import _pyplot

    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True)
    seed = min(r["seed"] for r in runs)
    for r in (r for r in runs if r["seed"] == seed):
        t, u, count, area = r["series"]
        label = f"cap: {r['cap_rule']}, {'tension and compression' if r['compression'] else 'tension only'}"
        style = "-" if r["cap_rule"] == "replace" else ":"
        axes[0].plot(t * 1e3, u * 1e6, style, lw=1, label=label)
        axes[1].plot(t * 1e3, count, style, lw=1, label=label)
        axes[2].plot(t * 1e3, area * 1e12, style, lw=1, label=label)
    for ax, what in zip(axes, ("rolling velocity U [um/s]", "bonds", "contact area [um^2]")):
        ax.set_ylabel(what)
        ax.axvline(THESIS_END * 1e3, color="grey", lw=0.8)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[-1].set_xlabel("time [ms] (grey: 10 ms, the end of the thesis's 10^4 steps of at most 1 us)")
    fig.suptitle(f"figs. 4.12-4.14: a = 3 um, G = 8 kPa, 60 receptors/um^2, cap 40 (seed {seed})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main():
    paths = sorted(RUNS.glob("point*.h5"))
    if not paths:
        print(f"{RUNS}: no runs (see this script's docstring)")
        return
    runs = [run(p) for p in paths]
    rows = table(runs)
    write(rows, "thesis_ch4_cap.csv")
    print("chart:", chart(runs, ROOT / "docs" / "figures" / "fig4_12_14_cap.png"))


if __name__ == "__main__":
    main()
