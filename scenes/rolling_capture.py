"""Table and chart of the capture sweep of free-stream cells by a rolling cell (issue 25 item 3;
King & Hammer 2001, PNAS 98:14919), e.g.

    warpbem sweep scenes/rolling_capture.toml --output-dir results/rolling_capture --workers 2
    python scenes/rolling_capture.py results/rolling_capture [more sweep folders]

writes results/rolling_capture.csv (per run: the free cell's lateral offset, whether and when it
binds, where relative to the rolling cell, its gap to the wall, the rolling cell's velocity) and
docs/figures/rolling_capture.png (the free cell's gap to the wall against its position along the
flow relative to the rolling cell, one line per offset, its first bond marked; and its bonds over
time). Body 0 is the free cell, body 1 the rolling one, both 5 um spheres (the scene's).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch4 import ROOT, save_chart, sweep_folders, write  # noqa: E402

from warpbem.app.io import open_result  # noqa: E402
from warpbem.app.plotting import _pyplot  # noqa: E402

RADIUS = 5e-6  # m, both cells (scenes/rolling_capture.toml)
FREE, ROLLING = 0, 1


def table(folders: list[Path]) -> tuple[list[dict], dict]:
    """(rows, traces): one row per run; traces[run] = (time, free cell's x relative to the rolling
    cell, its gap to the wall, its bonds), all in SI units."""
    rows, traces = [], {}
    for path in sorted(path for folder in folders for path in folder.glob("point*.h5")):
        with open_result(path) as f:
            t, position, bonds, seed = f["time"][:], f["position"][:], f["bond_count"][:], int(f.attrs["seed"])
        relative = position[:, FREE, :2] - position[:, ROLLING, :2]
        gap = position[:, FREE, 2] - RADIUS
        distance = np.linalg.norm(position[:, FREE] - position[:, ROLLING], axis=1)
        bound = np.flatnonzero(bonds[:, FREE] > 0)
        first = int(bound[0]) if len(bound) else None
        run = f"{path.parent.name}/{path.stem}"
        rolling_bound = np.flatnonzero(bonds[:, ROLLING] > 0)
        since = int(rolling_bound[0]) if len(rolling_bound) else 0
        rows.append(dict(
            run=run, seed=seed, glance_um=relative[0, 1] * 1e6, start_upstream_um=-relative[0, 0] * 1e6,
            start_gap_nm=gap[0] * 1e9, end_ms=t[-1] * 1e3, captured=first is not None,
            first_bond_ms=t[first] * 1e3 if first is not None else float("nan"),
            # where along the flow it binds, from the rolling cell's centre (> 0: downstream of it)
            bound_at_um=relative[first, 0] * 1e6 if first is not None else float("nan"),
            bound_at_diameters=relative[first, 0] / (2 * RADIUS) if first is not None else float("nan"),
            passed_to_um=relative[-1, 0] * 1e6, closest_surfaces_nm=(distance.min() - 2 * RADIUS) * 1e9,
            lowest_gap_nm=gap.min() * 1e9, free_bonds_end=int(bonds[-1, FREE]),
            rolling_um_s=(position[-1, ROLLING, 0] - position[since, ROLLING, 0]) / (t[-1] - t[since]) * 1e6))
        traces[run] = (t, relative[:, 0], gap, bonds[:, FREE], relative[0, 1])
    return rows, traces


def chart(traces: dict, out: Path) -> Path:
    plt = _pyplot()
    fig, (side, count) = plt.subplots(1, 2, figsize=(11, 4))
    for i, (run, (t, x, gap, bonds, glance)) in enumerate(sorted(traces.items(), key=lambda item: item[1][4])):
        colour, label = f"C{i}", f"offset {glance * 1e6:.1f} um, start gap {gap[0] * 1e9:.0f} nm"
        side.plot(x * 1e6, gap * 1e9, color=colour, label=label)
        count.plot(t * 1e3, bonds, color=colour, label=label)
        bound = np.flatnonzero(bonds > 0)
        if len(bound):
            side.plot(x[bound[0]] * 1e6, gap[bound[0]] * 1e9, "*", color=colour, ms=12)
    side.axvline(0.0, color="0.5", lw=1)
    side.set(xlabel="free cell along the flow from the rolling cell's centre [um]",
             ylabel="free cell's gap to the wall [nm]", title="the pass (star: first bond)")
    count.set(xlabel="time [ms]", ylabel="the free cell's bonds", title="bonds")
    side.grid(alpha=0.3)
    side.legend(fontsize=7)
    fig.suptitle("a free 5 um cell passing a cell rolling on stiff bonds (k_r0 = 1 /s, r0 = 0.6 A)")
    return save_chart(plt, fig, count, out, 7)


def main():
    rows, traces = table(sweep_folders(sys.argv[1:], "rolling_capture"))
    if rows:
        write(rows, "rolling_capture.csv")
        print("chart:", chart(traces, ROOT / "docs" / "figures" / "rolling_capture.png"))
    else:
        print("no runs in the folders given (see this script's docstring)")


if __name__ == "__main__":
    main()
