"""PNG charts of warpbem HDF5 results (matplotlib, the optional ``plot`` extra)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np


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
    with h5py.File(h5_path, "r") as f:
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


def plot_run(h5_path, png_path=None) -> Path:
    """Trajectories of a ``warpbem run`` file, like the thesis figures: height Z(t), lateral
    position Y(t) and the X-Z path of every free body (fixed bodies drawn as their start)."""
    import json

    plt = _pyplot()
    h5_path = Path(h5_path)
    png_path = Path(png_path) if png_path else h5_path.with_suffix(".png")
    with h5py.File(h5_path, "r") as f:
        t = f["time"][:]
        pos = f["position"][:] * 1e6
        names = json.loads(f.attrs.get("body_names", "[]")) or [f"body {i}" for i in range(pos.shape[1])]
        moved = np.ptp(pos, axis=0).max(axis=1) > 0
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for i, name in enumerate(names):
        style = "-" if moved[i] else ":"
        axes[0].plot(t, pos[:, i, 2], style, label=name)
        axes[1].plot(t, pos[:, i, 1], style, label=name)
        axes[2].plot(pos[:, i, 0], pos[:, i, 2], style + ("o" if not moved[i] else ""), label=name)
    axes[0].set(xlabel="t [s]", ylabel="Z: centre height [um]")
    axes[1].set(xlabel="t [s]", ylabel="Y: lateral position [um]")
    axes[2].set(xlabel="X [um]", ylabel="Z [um]", title="X-Z trajectory")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(h5_path.name)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    plt.close(fig)
    return png_path


def plot(h5_path, png_path=None) -> Path:
    """Chart of any warpbem result file: a run's trajectories or the demo's velocities."""
    with h5py.File(h5_path, "r") as f:
        is_run = "position" in f
    return plot_run(h5_path, png_path) if is_run else plot_demo(h5_path, png_path)
