"""Table and chart of the two-cell rolling sweep (issue 25 item 3; King & Hammer 2001, Biophys.
J. 81:799), e.g.

    warpbem sweep scenes/rolling_pair.toml --output-dir results/rolling_pair --workers 2
    python scenes/rolling_pair.py results/rolling_pair [more sweep folders, e.g. other seeds]
    python scenes/rolling_pair.py docs/figures/rolling_pair.csv results/rolling_pair_seeds34

(a .csv argument: the rows of a table this script wrote before, for runs whose files are gone)

writes results/rolling_pair.csv (per run and cell: arrangement, spacing, velocity, pauses,
lateral drift, bonds) and docs/figures/rolling_pair.png (mean rolling velocity, mean pause
and time paused against the spacing, in line and side by side, each cell a point and the mean a
line; the lone cells as a band and their mean).

Measures, per cell, from its first bond to the end of the run (frames every 1 ms):
- the mean rolling velocity, distance over time;
- pauses: maximal runs of frame intervals over which the cell moves slower than PAUSE times its
  velocity before any bond (3 %: 10 um/s for the 5 um cell's 349 um/s); their mean length and
  the fraction of the time paused. King & Hammer's own pause rule could not be read here (the
  papers' text beyond the abstract is not reachable), so this one is ours;
- the lateral drift |y(end) - y(first bond)| (their "deviation motion").
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch4 import ROOT, sweep_folders, write  # noqa: E402

from warpbem.app.io import open_result  # noqa: E402
from warpbem.app.plotting import _pyplot  # noqa: E402

PAUSE = 0.03
KINDS = {"inline": "in line", "side": "side by side"}
CELLS = {"inline": ("upstream", "downstream"), "side": ("first", "second")}


def pauses(t, x, free_velocity) -> tuple[float, float, int]:
    """(mean pause length (s), fraction of the time paused, number of pauses) of one cell's
    frames ``t``, ``x`` (the part after its first bond)."""
    slow = np.diff(x) / np.diff(t) < PAUSE * free_velocity
    edges = np.diff(np.concatenate([[0], slow.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    lengths = np.array([t[e] - t[s] for s, e in zip(starts, ends)])
    paused = float(lengths.sum() / (t[-1] - t[0])) if len(t) > 1 else float("nan")
    return (float(lengths.mean()) if len(lengths) else 0.0), paused, len(lengths)


def arrangement(offset) -> tuple[str, float]:
    """('inline' | 'side' | 'alone', centre-to-centre spacing (m)) of the second cell's start."""
    spacing = float(np.hypot(*offset))
    if spacing > 1e-3:
        return "alone", spacing
    return ("inline" if abs(offset[0]) >= abs(offset[1]) else "side"), spacing


def table(folders: list[Path]) -> list[dict]:
    rows = []
    for path in sorted(path for folder in folders for path in folder.glob("point*.h5")):
        with open_result(path) as f:
            t, position, u = f["time"][:], f["position"][:], f["velocity"][:, :, 0]
            bonds, seed = f["bond_count"][:], int(f.attrs["seed"])
        kind, spacing = arrangement(position[0, 1, :2] - position[0, 0, :2])
        for cell in range(position.shape[1]):
            bound = np.flatnonzero(bonds[:, cell] > 0)
            if len(bound) == 0 or bound[0] >= len(t) - 2:
                continue
            part = slice(bound[0], None)
            ts, x, y = t[part], position[part, cell, 0], position[part, cell, 1]
            mean_pause, paused, count = pauses(ts, x, u[0, cell])
            rows.append(dict(run=f"{path.parent.name}/{path.stem}", arrangement=kind, spacing_um=spacing * 1e6, seed=seed, cell=cell,
                             free_um_s=u[0, cell] * 1e6, first_bond_ms=ts[0] * 1e3, end_ms=t[-1] * 1e3,
                             velocity_um_s=(x[-1] - x[0]) / (ts[-1] - ts[0]) * 1e6,
                             mean_pause_ms=mean_pause * 1e3, paused_fraction=paused, pauses=count,
                             lateral_drift_um=abs(y[-1] - y[0]) * 1e6, bonds_mean=float(bonds[part, cell].mean())))
    return rows


def earlier(path: Path) -> list[dict]:
    """The rows of a table this script wrote before, with its numbers as numbers."""
    def value(key, text):
        return text if key in ("run", "arrangement") else int(text) if key in ("seed", "cell", "pauses") else float(text)

    with path.open(newline="") as f:
        return [{k: value(k, v) for k, v in row.items()} for row in csv.DictReader(f)]


def chart(rows: list[dict], out: Path) -> Path:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    alone = [r for r in rows if r["arrangement"] == "alone"]
    for ax, key, label in zip(axes, ("velocity_um_s", "mean_pause_ms", "paused_fraction"),
                              ("mean rolling velocity [um/s]", "mean pause [ms]", "fraction of the time paused")):
        if alone:
            values = [r[key] for r in alone]
            ax.axhspan(min(values), max(values), color="0.85", label=f"alone ({len(values)} cells)")
            ax.axhline(np.mean(values), color="0.5", lw=1)
        for kind, colour in (("inline", "C0"), ("side", "C1")):
            sel = [r for r in rows if r["arrangement"] == kind]
            if not sel:
                continue
            for cell, fill in ((0, colour), (1, "none")):  # the first cell filled, the second (downstream) open
                cells = [r for r in sel if r["cell"] == cell]
                ax.scatter([r["spacing_um"] for r in cells], [r[key] for r in cells], marker="o", s=22,
                           facecolors=fill, edgecolors=colour, label=f"{KINDS[kind]}, {CELLS[kind][cell]}")
            spacings = sorted({r["spacing_um"] for r in sel})
            ax.plot(spacings, [np.mean([r[key] for r in sel if r["spacing_um"] == s]) for s in spacings],
                    color=colour, lw=1)
        ax.set(xlabel="centre-to-centre spacing [um]", ylabel=label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("two cells rolling on stiff bonds (k_r0 = 1 /s, r0 = 0.6 A), each cell from its first bond")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def main():
    tables = [Path(a) for a in sys.argv[1:] if a.endswith(".csv")]
    folders = sweep_folders([a for a in sys.argv[1:] if not a.endswith(".csv")], "rolling_pair") if (
        len(tables) < len(sys.argv[1:]) or not tables) else []
    rows = [row for path in tables for row in earlier(path)] + table(folders)
    if not rows:
        print(f"{', '.join(map(str, folders))}: no runs (see this script's docstring)")
        return
    write(rows, "rolling_pair.csv")
    print("chart:", chart(rows, ROOT / "docs" / "figures" / "rolling_pair.png"))


if __name__ == "__main__":
    main()
