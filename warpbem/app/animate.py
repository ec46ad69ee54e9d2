"""``warpbem animate RUN.h5 --output RUN.gif``: a run as an animated GIF, written by matplotlib's
Pillow writer (Pillow comes with matplotlib; no ffmpeg). Side (X-Z) and top (X-Y) views with
every body drawn to scale as the outline of its mesh's nodes (deformable cells as they deform,
from the frames' node displacements), farther bodies under nearer ones (``plotting.VIEWS``),
the wall, the ligand ends of an adhesive run's bonds and the time of each frame. Axes are
fixed over the run, so motion reads as motion."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .io import open_result
from .plotting import VIEWS, _pyplot, depth_order, outline
from .xdmf import read_frames, world_nodes

UM = 1e6
MAX_FRAMES = 200  # a GIF of more frames grows large and plays slowly; the run's frames are sampled evenly


def frame_indices(count: int, most: int) -> np.ndarray:
    """``most`` frame indices spread evenly over ``count`` frames, first and last included."""
    return np.arange(count) if count <= most else np.unique(np.linspace(0, count - 1, most).round().astype(int))


def _bond_ends(f, frames):
    """The ligand ends (frame -> (k, 3) m) of the bonds held in each of ``frames``, or None for a
    run without bonds."""
    if "bond_anchor" not in f:
        return None
    anchors, receptors = f["bond_anchor"], f["bond_receptor"]
    return {int(j): anchors[j][receptors[j] >= 0] for j in frames}


def animate(run_path, gif_path=None, most: int = MAX_FRAMES, fps: float = 10.0, dpi: int = 80) -> Path:
    """Write the GIF of the run file ``run_path`` (default: beside it, .gif); ``most`` frames at
    most, ``fps`` frames per second of the GIF. Returns its path."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    if most < 1 or fps <= 0 or dpi < 10:
        raise ValueError(f"animate: frames {most} (at least 1), fps {fps} (> 0) and dpi {dpi} (at least 10)")
    plt = _pyplot()
    run_path = Path(run_path)
    gif_path = Path(gif_path) if gif_path else run_path.with_suffix(".gif")
    meshes, t, pos, orientations, displacement = read_frames(run_path)
    frames = frame_indices(len(t), most)
    with open_result(run_path) as f:
        names = json.loads(f.attrs.get("body_names", "[]")) or [f"body {i}" for i in range(pos.shape[1])]
        bonds = _bond_ends(f, frames)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    reach = max(np.linalg.norm(m.nodes, axis=1).max() for m in meshes) * UM * 1.3  # room for deformation
    low, high = pos[frames].min(axis=(0, 1)) * UM - reach, pos[frames].max(axis=(0, 1)) * UM + reach
    fig, (side, top) = plt.subplots(2, 1, figsize=(8, 7))

    def draw(j):
        shape = None if displacement is None else displacement[j]
        for ax, view, title in ((side, "side", "side view (X-Z), seen from -Y: farther drawn behind"),
                                (top, "top", "top view (X-Y), seen from above: lower drawn behind")):
            ax.clear()
            (_, axis), depth_axis, farther = VIEWS[view]
            for rank, i in enumerate(depth_order(pos[j, :, depth_axis], farther)):
                nodes = world_nodes(meshes[i:i + 1], pos[j, i:i + 1], orientations[j, i:i + 1],
                                    None if shape is None else shape[i:i + 1]) * UM
                line = outline(nodes[:, [0, axis]])
                colour = colours[i % len(colours)]
                # translucent fills: a cell behind another shows through it
                ax.fill(line[:, 0], line[:, 1], color=colour, alpha=0.25, zorder=1.0 + rank)
                depth = f"{'xyz'[depth_axis]} = {pos[j, i, depth_axis] * UM:.3g} um"
                ax.plot(line[:, 0], line[:, 1], color=colour, lw=1.2, zorder=1.5 + rank,
                        label=f"{names[i]} ({depth})" if len(names) <= 8 else None)
            if bonds is not None and len(bonds[j]):
                ax.plot(bonds[j][:, 0] * UM, bonds[j][:, axis] * UM, ".", color="k", ms=2, zorder=len(meshes) + 2,
                        label=f"{len(bonds[j])} bonds' ligand ends")
            ax.set(xlim=(low[0], high[0]), ylim=(0.0 if axis == 2 else low[1], high[axis]),
                   xlabel="X [um]", ylabel=("Z" if axis == 2 else "Y") + " [um]", title=title)
            ax.set_aspect("equal", adjustable="box")
            ax.grid(alpha=0.3)
        side.axhline(0.0, color="k", lw=2)
        if side.get_legend_handles_labels()[0]:
            side.legend(fontsize=7, loc="upper right")
        fig.suptitle(f"{run_path.name}   t = {t[j] * 1e3:.3f} ms")

    animation = FuncAnimation(fig, draw, frames=frames, blit=False)
    animation.save(gif_path, writer=PillowWriter(fps=fps), dpi=dpi)
    plt.close(fig)
    return gif_path
