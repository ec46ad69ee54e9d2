"""PNG charts of warpbem HDF5 results (matplotlib, the optional ``plot`` extra)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .io import RunFileError, open_result


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:
        raise RuntimeError("plotting needs matplotlib: pip install 'warpbem[plot]'") from err
    return plt


def plot_demo(h5_path, png_path=None) -> Path:
    """Velocities of the free cell and loads on the adherent cell along the pass."""
    plt = _pyplot()
    h5_path = Path(h5_path)
    png_path = Path(png_path) if png_path else h5_path.with_suffix(".png")
    with open_result(h5_path, needs=("x", "free_velocity")) as f:
        x = f["x"][:] * 1e6
        u = f["free_velocity"][:] * 1e6
        w = f["free_angular_velocity"][:]
        force = f["adherent_force"][:] * 1e12
        title = f.attrs.get("title", "")
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    axes[0].plot(x, u[:, 0], "o-", label="U (streamwise)")
    axes[0].set_ylabel("velocity [um/s]")
    ax = axes[1]
    ax.plot(x, u[:, 1], "s-", label="V (lateral)")
    ax.plot(x, u[:, 2], "^-", label="W (vertical, + away from wall)")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_ylabel("velocity [um/s]")
    axes[2].plot(x, force[:, 0], "o-", label="F_x")
    axes[2].plot(x, force[:, 1], "s-", label="F_y")
    axes[2].plot(x, force[:, 2], "^-", label="F_z")
    axes[2].set_ylabel("force holding the adherent cell [pN]")
    twin = axes[0].twinx()
    twin.plot(x, w[:, 1], "k--", lw=1, label="Omega_y")
    twin.set_ylabel("spin Omega_y [rad/s]")
    twin.legend(loc="upper center", fontsize=8)
    for ax in axes:
        ax.set_xlabel("free cell position x relative to the adherent cell [um]")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    plt.close(fig)
    return png_path


STATE_MARKS = {"no adhesion": ("o", "white"), "rolling": ("s", "C1"), "firm adhesion": ("D", "C0")}


def draw_adhesion_states(ax, rows) -> None:
    """The adhesion state diagram's points on ``ax``: each row (off_rate in 1/s,
    reactive_compliance in m, state and velocity_ratio, as ``adhesion_states.classify`` gives
    them) a marker of its state on the (r0 in A, k_r0) plane, labelled with its V / V_free; log
    axes, labels and grid (the caller adds title and legend)."""
    from .adhesion_states import STATES

    for state in STATES:
        chosen = [r for r in rows if r["state"] == state]
        if chosen:
            ax.scatter([r["reactive_compliance"] * 1e10 for r in chosen], [r["off_rate"] for r in chosen], s=160,
                       marker=STATE_MARKS[state][0], facecolor=STATE_MARKS[state][1], edgecolor="k", label=state)
    for r in rows:
        ax.annotate(f"{r['velocity_ratio']:.2g}", (r["reactive_compliance"] * 1e10, r["off_rate"]),
                    textcoords="offset points", xytext=(9, 6), fontsize=7)
    ax.set(xscale="log", yscale="log", xlabel="reactive compliance r0 [A]", ylabel="unstressed off-rate k_r0 [1/s]")
    ax.grid(alpha=0.3, which="both")


def outline(points: np.ndarray) -> np.ndarray:
    """Closed outline (k + 1, 2) of 2-D points: their convex hull, the silhouette of a convex
    body's projected nodes (the cells of the thesis are convex)."""
    from scipy.spatial import ConvexHull

    hull = points[ConvexHull(points).vertices]
    return np.vstack([hull, hull[:1]])


def snapshot_frames(time: np.ndarray, count: int = 4) -> np.ndarray:
    """Indices of ``count`` frames evenly spread in time, first and last included."""
    return np.unique([int(np.argmin(np.abs(time - t))) for t in np.linspace(time[0], time[-1], count)])


def plot_run(h5_path, png_path=None) -> Path:
    """The PNG chart of a ``warpbem run`` file (``run_figure``), beside it by default."""
    plt = _pyplot()
    h5_path = Path(h5_path)
    png_path = Path(png_path) if png_path else h5_path.with_suffix(".png")
    fig = run_figure(h5_path)
    fig.savefig(png_path, dpi=120)
    plt.close(fig)
    return png_path


CROWDED = 12  # bodies beyond which a chart groups them in its legend and leaves their names out

# The views (shown axes, depth axis, sign of "farther"): the side view (X-Z) is seen from -y (X to
# the right and Z up in a right-handed frame), so a larger y is farther; the top view (X-Y) from
# above, so a lower z is farther. Farther outlines are drawn first, under the nearer ones.
VIEWS = {"side": ((0, 2), 1, 1.0), "top": ((0, 1), 2, -1.0)}


def depth_order(depths, farther: float) -> np.ndarray:
    """Indices of ``depths`` from the farthest to the nearest (``farther``: +1 where a larger
    coordinate is farther, -1 where a smaller one is), ties in their given order."""
    return np.argsort(-farther * np.asarray(depths, dtype=float), kind="stable")


def read_gaps(f, frames: int) -> list[tuple[str, np.ndarray]]:
    """The surface gaps (label, m per frame) a run file has: the gap to the nearest body and the
    gap to the wall, or for a file written before those columns its closest gap (to either);
    a gap that is infinite throughout (no other body, no wall) left out."""
    if "closest_body_gap" in f and "wall_gap" in f:
        gaps = [("gap to the nearest body", f["closest_body_gap"][:frames]),
                ("gap to the wall", f["wall_gap"][:frames])]
    elif "closest_gap" in f:
        gaps = [("closest gap, to a body or the wall (file without the separate gaps)", f["closest_gap"][:frames])]
    else:
        gaps = []
    return [(label, values) for label, values in gaps if np.isfinite(values).any()]


def run_figure(h5_path):
    """Trajectories of a run, like the thesis figures: height Z(t) and lateral position Y(t) of
    every body, the smallest surface gaps (to the nearest body and to the wall) against time, and
    the side (X-Z) and top (X-Y) views with the cells drawn to scale (their outlines at a few
    times, fading in from the first to the last; fixed cells once; farther ones drawn first and
    seen through the nearer ones, each named) over the reference points' paths, so a reader sees
    where the free cell passed the adherent ones and how close it came."""
    from .xdmf import read_frames, world_nodes

    plt = _pyplot()
    h5_path = Path(h5_path)
    meshes, t, pos, orientations, displacement = read_frames(h5_path)
    with open_result(h5_path) as f:
        names = json.loads(f.attrs.get("body_names", "[]")) or [f"body {i}" for i in range(pos.shape[1])]
        gaps = read_gaps(f, len(t))
        adhesion = {name: f[name][: len(t)] for name in ("velocity", "bond_count", "contact_area")} \
            if "bond_count" in f else None
    moved = np.ptp(pos, axis=0).max(axis=1) > 0
    fig = plt.figure(figsize=(15, 14 if adhesion else 10))
    grid = fig.add_gridspec(3 if adhesion else 2, 6, height_ratios=[1, 1.35, 1][: 3 if adhesion else 2])
    height, lateral, gap = (fig.add_subplot(grid[0, 2 * k: 2 * k + 2]) for k in range(3))
    side, top = fig.add_subplot(grid[1, :3]), fig.add_subplot(grid[1, 3:])
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    um = 1e6
    snapshots = snapshot_frames(t)
    # many bodies (arrays of cells): one colour and one legend entry for the fixed ones, one
    # for the moving ones, no names on the views and no lines of the fixed ones' constant heights
    crowded = len(names) > CROWDED
    first_moving, first_fixed = (np.flatnonzero(moved)[:1], np.flatnonzero(~moved)[:1])
    colour_of = ["0.45" if crowded and not moved[i] else colours[i % len(colours)] for i in range(len(names))]
    outlines = []  # (body, frame, its place among its snapshots, legend label)
    for i, name in enumerate(names):
        if moved[i] or not crowded:
            label = (name if moved[i] else f"{name} (fixed)") if not crowded else \
                f"{moved.sum()} moving cells" if i in first_moving else None
            style = "-" if moved[i] else ":"
            height.plot(t, pos[:, i, 2] * um, style, color=colour_of[i], label=label)
            lateral.plot(t, pos[:, i, 1] * um, style, color=colour_of[i], label=label)
        frames = snapshots if moved[i] else snapshots[:1]
        times = ", ".join(f"{t[j]:.3g}" for j in frames)
        label = (f"{name}, outlines at t = {times} s" if moved[i] else f"{name} (fixed)") if not crowded else \
            f"{moved.sum()} moving cells, outlines at t = {times} s" if i in first_moving else \
            f"{(~moved).sum()} fixed cells" if i in first_fixed else None
        outlines += [(i, frame, (k + 1) / len(frames), label if k == 0 else None) for k, frame in enumerate(frames)]
        if moved[i]:
            side.plot(pos[:, i, 0] * um, pos[:, i, 2] * um, "--", color=colour_of[i], lw=0.8, zorder=0.5)
            top.plot(pos[:, i, 0] * um, pos[:, i, 1] * um, "--", color=colour_of[i], lw=0.8, zorder=0.5)
    nodes = {(i, frame): world_nodes(meshes[i: i + 1], pos[frame, i: i + 1], orientations[frame, i: i + 1],
                                     None if displacement is None else displacement[frame, i: i + 1]) * um
             for i, frame, _, _ in outlines}
    for ax, view in ((side, "side"), (top, "top")):
        shown, depth_axis, farther = VIEWS[view]
        order = depth_order([pos[frame, i, depth_axis] for i, frame, _, _ in outlines], farther)
        for rank, k in enumerate(order):
            i, frame, fade, label = outlines[k]
            line = outline(nodes[(i, frame)][:, shown])
            # translucent fills over every outline: a cell behind another shows through it
            z = 1.0 + rank
            (fill,) = ax.fill(line[:, 0], line[:, 1], color=colour_of[i], alpha=0.18 * fade, lw=0, zorder=z)
            fill.set_gid(f"body {i} frame {frame}")
            ax.plot(line[:, 0], line[:, 1], color=colour_of[i], alpha=0.3 + 0.7 * fade, lw=1.2, zorder=z + 0.5,
                    label=label if ax is side else None)
        if not crowded:  # each body named inside the top of its first outline, with its depth
            for i, frame, _, label in outlines:
                if label is not None:
                    line = outline(nodes[(i, frame)][:, shown])
                    depth = pos[frame, i, depth_axis] * um
                    ax.annotate(f"{names[i]}\n{'xyz'[depth_axis]} = {depth:.3g} um",
                                (line[:, 0].mean(), line[:, 1].max()), xytext=(0, -4), textcoords="offset points",
                                ha="center", va="top", fontsize=8, zorder=len(outlines) + 2)
    side.axhline(0.0, color="k", lw=2)
    # the wall's side shaded, by add_artist: a patch that does not widen the view's data limits
    side.add_artist(plt.Rectangle((-1e9, -1e9), 2e9, 1e9, color="0.9", zorder=0))
    side.annotate("wall", (0.01, 0.02), xycoords="axes fraction", fontsize=8)
    height.set(xlabel="t [s]", ylabel="Z: centre height [um]", title="height (dotted: fixed)")
    lateral.set(xlabel="t [s]", ylabel="Y: lateral position [um]", title="lateral position")
    low, high = lateral.get_ylim()
    if high - low < 1e-3:  # um: below a nanometre (a cell settling straight down: rounding) reads as no motion
        lateral.set_ylim(0.5 * (low + high) - 0.5, 0.5 * (low + high) + 0.5)
    _gap_axes(gap, t, gaps)
    side.set(xlabel="X [um]", ylabel="Z [um]",
             title="side view, seen from -Y (to scale; farther in Y drawn behind; dashed: reference point path)")
    top.set(xlabel="X [um]", ylabel="Y [um]", title="top view, seen from above (to scale; lower drawn behind)")
    for ax in (side, top):
        ax.set_aspect("equal", adjustable="datalim")
    if adhesion:
        row = [fig.add_subplot(grid[2, :3]), fig.add_subplot(grid[2, 3:])]
        _adhesion_axes(row, t, adhesion, names, moved, colours)
    for ax in fig.axes:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.suptitle(h5_path.name)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.98))  # the title above the panels' own
    return fig


def _gap_axes(ax, t, gaps):
    """The smallest surface gaps (``read_gaps``) against time, in nm (a log scale where they
    span more than a decade: contacts of a few nm and passes microns apart on one chart)."""
    for (label, values), style in zip(gaps, ("-", "--", ":")):
        ax.plot(t, values * 1e9, style, color="k", lw=1.2, label=label)
    values = np.concatenate([v[np.isfinite(v)] for _, v in gaps]) if gaps else np.array([])
    if len(values) and values.min() > 0 and values.max() > 10 * values.min():
        ax.set_yscale("log")
    ax.set(xlabel="t [s]", ylabel="surface gap [nm]",
           title="smallest surface gaps of the free bodies" if gaps else "no surface gap in this file")


def _adhesion_axes(row, t, data, names, moved, colours):
    """An adhesive run (thesis figs. 4.4, 4.6, 4.9-4.14): each free cell's translational
    velocity, and its bond count with its Hertz contact area, against time."""
    velocity, bonds = row
    area = bonds.twinx()
    for i, name in enumerate(names):
        if not moved[i]:
            continue
        colour = colours[i % len(colours)]
        velocity.plot(t, data["velocity"][:, i, 0] * 1e6, color=colour, label=name)
        bonds.plot(t, data["bond_count"][:, i], color=colour, label=f"{name}: bonds")
        area.plot(t, data["contact_area"][:, i] * 1e12, "--", color=colour)
    velocity.set(xlabel="t [s]", ylabel="U: translational velocity along the flow [um/s]",
                 title="rolling velocity")
    bonds.set(xlabel="t [s]", ylabel="bonds (solid)", title="bonds and Hertz contact area")
    area.set_ylabel("contact area [um^2] (dashed)")


def plot(h5_path, png_path=None) -> Path:
    """Chart of any warpbem result file: a run's trajectories or the demo's velocities."""
    with open_result(h5_path) as f:
        kind = "run" if "position" in f else "demo" if "free_velocity" in f else None
    if kind is None:
        raise RunFileError(f"{h5_path}: neither a run (warpbem run, sweep) nor a demo (warpbem demo) file")
    return plot_run(h5_path, png_path) if kind == "run" else plot_demo(h5_path, png_path)
