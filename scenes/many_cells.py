"""Charts and table of a run of many rolling cells (issue 25 item 2), e.g.

    warpbem run scenes/rolling_patch_4x4.toml --output results/rolling_patch_4x4.h5
    python scenes/many_cells.py results/rolling_patch_4x4.h5

writes results/<run>.csv (per cell: state, velocity over the last half, bonds, first bond) and docs/figures/<run>.png: the velocity of each cell and its bonds over
time, and the patch seen from above at the start, the middle and the end of the run, each cell
to scale and coloured by its velocity.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch4 import ROOT, write  # noqa: E402

from warpbem.app.adhesion_states import classify  # noqa: E402
from warpbem.app.io import open_result  # noqa: E402
from warpbem.app.plotting import _pyplot  # noqa: E402


def radii(scene: dict) -> np.ndarray:
    """Each body's sphere radius (m): the [[bodies]] entries, then each [[arrays]] entry's members."""
    entries = list(scene.get("bodies", []))
    for spec in scene.get("arrays", []):
        entries += [spec] * int(np.prod(spec["count"]))
    return np.array([e["mesh"]["radius"] for e in entries])


def table(path: Path) -> list[dict]:
    """Per cell: its state (adhesion_states.classify), velocity over the last half, bonds, first bond."""
    with open_result(path) as f:
        names = json.loads(f.attrs["body_names"])
        t, x, u, bonds = f["time"][:], f["position"][:, :, 0], f["velocity"][:, :, 0], f["bond_count"][:]
    half = t >= 0.5 * t[-1]
    rows = []
    for i, name in enumerate(names):
        state, ratio = classify(t, x[:, i], bonds[:, i], u[0, i])
        bound = np.flatnonzero(bonds[:, i] > 0)
        rows.append(dict(cell=name, state=state, free_velocity_um_s=u[0, i] * 1e6,
                         velocity_last_half_um_s=np.polyfit(t[half], x[half, i], 1)[0] * 1e6,
                         bonds_end=int(bonds[-1, i]), bonds_max=int(bonds[:, i].max()),
                         first_bond_ms=t[bound[0]] * 1e3 if len(bound) else float("nan")))
    return rows


def chart(path: Path, out: Path) -> Path:
    with open_result(path) as f:
        scene = json.loads(f.attrs["scene"])
        t, position = f["time"][:], f["position"][:]
        u, bonds = f["velocity"][:, :, 0], f["bond_count"][:]
    radius = radii(scene)
    plt = _pyplot()
    from matplotlib.patches import Circle

    fig = plt.figure(figsize=(12, 7.5))
    ax_u, ax_b = fig.add_subplot(2, 3, (1, 2)), fig.add_subplot(2, 3, (4, 5))
    for i in range(position.shape[1]):
        ax_u.plot(t * 1e3, u[:, i] * 1e6, lw=1)
        ax_b.plot(t * 1e3, bonds[:, i], lw=1)
    ax_u.set(ylabel="velocity along the flow [um/s]", title=f"{path.stem}: {position.shape[1]} cells, one line each")
    ax_b.set(xlabel="time [ms]", ylabel="bonds")
    top = fig.add_subplot(1, 3, 3)
    norm = plt.Normalize(0.0, max(float(u.max()) * 1e6, 1.0))
    colours = plt.get_cmap("viridis")
    for k, alpha in zip((0, len(t) // 2, len(t) - 1), (0.25, 0.5, 1.0)):
        for i in range(position.shape[1]):
            top.add_patch(Circle(position[k, i, :2] * 1e6, radius[i] * 1e6, alpha=alpha, lw=0.5,
                                 facecolor=colours(norm(u[k, i] * 1e6)), edgecolor="k"))
    lo, hi = position[:, :, :2].min(axis=(0, 1)) * 1e6 - radius.max() * 1e6, \
        position[:, :, :2].max(axis=(0, 1)) * 1e6 + radius.max() * 1e6
    top.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), aspect="equal", xlabel="x (flow) [um]", ylabel="y [um]",
            title=f"from above: {t[0] * 1e3:.3g}, {t[len(t) // 2] * 1e3:.3g}, {t[-1] * 1e3:.3g} ms\n(faint to solid)")
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=colours), ax=top, label="velocity [um/s]", shrink=0.6)
    for ax in (ax_u, ax_b, top):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def main():
    for name in sys.argv[1:] or [str(ROOT / "results" / "rolling_patch_4x4.h5")]:
        path = Path(name)
        if not path.exists():
            print(f"{path}: no run (see this script's docstring)")
            continue
        write(table(path), f"{path.stem}.csv")
        print("chart:", chart(path, ROOT / "docs" / "figures" / f"{path.stem}.png"))


if __name__ == "__main__":
    main()
