"""One adhesive cell rolling on a ligand-coated wall in shear flow (thesis ch. 4, figs. 4.9-4.11):
its velocity, its number of bonds and its Hertz contact area against time.

    python examples/rolling_cell.py [--end 0.05] [--subdivisions 4] [--output-dir results/rolling_cell]

The scene is ``scenes/fig4_09_11_soft_bonds.toml`` as committed (Table 4.1: soft bonds, sigma =
0.5 dyn/cm; a 5 um cell of shear modulus 4 kPa, released 240 nm above the wall in 100 1/s shear,
its microvillus tips within reach of the wall's ligands), read by ``warpbem.load_scene`` and run
by ``warpbem.run``, the function behind ``warpbem run``. Writes ``rolling_cell.h5`` (the run's
frames) and ``rolling_cell.png`` (the chart) in the output folder and prints one line per frame.

What to expect: before any bond the cell moves as a free sphere at that height, U = X gdot h with
X from the exact wall series of Goldman, Cox & Brenner (1967b) (U = 345.6 um/s at h/a = 1.048);
bonds then form faster (k_f0 = 365 /s) than they break (k_r0 = 2.4 /s) and bring the cell to rest
within about 10 ms (scenes/README.md, "Rolling results next to the thesis"). The contact area
is the Hertz disc of the cell pressed onto the rigid wall by the normal force F of its bonds
(thesis eq. 4.9; Johnson 1985, Contact Mechanics, ch. 4.2):

    A = pi a_s^2,   a_s = (3 F R / (4 E*))^(1/3),   E* = E / (1 - nu^2),   E = 2 G (1 + nu)

with R the cell's radius, G its shear modulus and nu its Poisson ratio (SI units throughout:
seconds, metres, newtons, pascals).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from warpbem.app.io import open_result
from warpbem import load_scene, run

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "fig4_09_11_soft_bonds.toml"


def roll(output_dir, end=0.05, subdivisions=4, dt_max=None, device="cpu") -> dict:
    """Run the scene to ``end`` (s) with a cell of ``subdivisions`` (k: 6 k^2 elements) and the
    scene's step limit, or ``dt_max`` (s); returns the frames' time (s), velocity along the flow
    (m/s), position along the flow and height (m), bond count, contact area (m^2) and normal bond
    force (N) of the cell."""
    output = Path(output_dir) / "rolling_cell.h5"
    output.parent.mkdir(parents=True, exist_ok=True)
    overrides = [f"time.end={end!r}", f"bodies.0.mesh.subdivisions={subdivisions}"]
    if dt_max is not None:
        overrides.append(f"time.dt_max={dt_max!r}")
    # frames every 0.5 ms as the scene has them, closer in runs shorter than 4 ms (8 at least)
    overrides.append(f"time.frame_interval={min(5e-4, end / 8)!r}")
    run(load_scene(SCENE, overrides), output, device=device, progress=None, overwrite=True)
    with open_result(output) as f:
        return {"time": f["time"][:], "velocity": f["velocity"][:, 0, 0], "x": f["position"][:, 0, 0],
                "height": f["position"][:, 0, 2],
                "bonds": f["bond_count"][:, 0].astype(int), "contact_area": f["contact_area"][:, 0],
                "contact_force": f["contact_force"][:, 0], "file": output}


def chart(frames, path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = frames["time"] * 1e3
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    axes[0].plot(t, frames["velocity"] * 1e6, "o-", ms=3)
    axes[0].set_ylabel("velocity U [um/s]")
    axes[1].step(t, frames["bonds"], where="post")
    axes[1].set_ylabel("bonds")
    axes[2].plot(t, frames["contact_area"] * 1e12, "o-", ms=3)
    axes[2].set(ylabel="Hertz contact area [um^2]", xlabel="time [ms]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title("a 5 um, 4 kPa cell on soft bonds (scenes/fig4_09_11_soft_bonds.toml)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def main(output_dir="results/rolling_cell", end=0.05, subdivisions=4, dt_max=None) -> dict:
    frames = roll(output_dir, end, subdivisions, dt_max)
    print(" t [ms] | U [um/s] | bonds | contact area [um^2]")
    for t, u, n, area in zip(frames["time"], frames["velocity"], frames["bonds"], frames["contact_area"]):
        print(f"{t * 1e3:7.2f} | {u * 1e6:8.1f} | {n:5d} | {area * 1e12:.3f}")
    frames["chart"] = chart(frames, Path(output_dir) / "rolling_cell.png")
    print("run:", frames["file"], " chart:", frames["chart"])
    return frames


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--end", type=float, default=0.05, help="simulated time, s")
    parser.add_argument("--subdivisions", type=int, default=4, help="k: 6 k^2 elements on the cell")
    parser.add_argument("--output-dir", default="results/rolling_cell")
    args = parser.parse_args()
    main(args.output_dir, args.end, args.subdivisions)
