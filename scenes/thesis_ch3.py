"""Binary collisions of deformable cells near the wall (thesis ch. 3.2-3.3) from the runs of

    warpbem sweep scenes/fig3_01_04_collision.toml --output-dir results/collision
    python scenes/thesis_ch3.py

for scenes/README.md: each case's closest approach between the cells, the change of each cell's
height across the collision (fig. 3.4: the lower cell nudged towards the wall), how far each
cell's surface moved in where they met (figs. 3.1-3.2: the contact flattening, largest inward
normal displacement over the run), and the lubrication forces of eq. 3.7-3.8 evaluated along
each run from its separation and relative velocity (fig. 3.3; charted, not applied:
warpbem/forces/lubrication.py); the heights also at the end of the shortest run, so that runs of
different lengths compare. Writes results/collision.csv and docs/figures/collision.png.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from warpbem.app.io import open_result
from warpbem.app.scene import parse
from warpbem.forces.lubrication import shear_force, squeeze_force

ROOT = Path(__file__).resolve().parent.parent
A = 5e-6


def case(path: Path) -> dict:
    with open_result(path) as f:
        scene = json.loads(f.attrs["scene"])
        t, x, v = f["time"][:], f["position"][:], f["velocity"][:]
        u = f["deformation_node_displacement"][:] if "deformation_node_displacement" in f else None
    bodies = scene["bodies"]
    label = "rigid" if not bodies[0].get("deformable") else f"{bodies[0]['shear_modulus'] / 1e3:g} kPa"
    line = x[:, 1] - x[:, 0]
    distance = np.linalg.norm(line, axis=1)
    eps = distance - 2 * A
    l = line / distance[:, None]
    relative = v[:, 0] - v[:, 1]
    mu = scene["flow"].get("viscosity", 1.2e-3)
    film = eps < A  # the formulas' range; nan elsewhere
    squeeze = np.array([np.linalg.norm(squeeze_force(A, mu, e, r, d)) if near else np.nan
                        for e, r, d, near in zip(eps, relative, l, film)])
    shear = np.array([np.linalg.norm(shear_force(A, mu, e, r, d)) if near else np.nan
                      for e, r, d, near in zip(eps, relative, l, film)])
    indent = np.zeros(2)
    if u is not None:
        mesh = parse(scene, path.parent).bodies[0].mesh
        normals = mesh.nodes / np.linalg.norm(mesh.nodes, axis=1)[:, None]
        for i in range(2):
            inward = -np.einsum("fnk,nk->fn", u[:, i, :len(mesh.nodes)], normals)
            indent[i] = inward.max()
    closest = np.argmin(eps)
    return dict(case=label, closest_separation_nm=eps[closest] * 1e9, at_s=t[closest],
                lower_dz_um=(x[-1, 0, 2] - x[0, 0, 2]) * 1e6, upper_dz_um=(x[-1, 1, 2] - x[0, 1, 2]) * 1e6,
                lower_min_z_um=x[:, 0, 2].min() * 1e6,
                lower_indent_nm=indent[0] * 1e9, upper_indent_nm=indent[1] * 1e9,
                squeeze_max_pN=np.nanmax(squeeze) * 1e12, shear_max_pN=np.nanmax(shear) * 1e12,
                t=t, x=x, eps=eps, squeeze=squeeze, shear=shear)


def chart(cases, path):
    import matplotlib.pyplot as plt
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(15, 4.3))
    for c, style in zip(cases, ("-", "--", ":")):
        for i, name in enumerate(("lower", "upper")):
            left.plot(c["x"][:, i, 0] * 1e6, c["x"][:, i, 2] * 1e6, style, color=f"C{i}",
                      label=f"{name}, {c['case']}")
        middle.plot(c["t"] * 1e3, (c["x"][:, 0, 2] - c["x"][0, 0, 2]) * 1e9, style, color="C0",
                    label=f"lower cell, {c['case']}")
        right.loglog(c["eps"] * 1e9, c["squeeze"] * 1e12, style, color="C2", label=f"squeeze (eq. 3.7), {c['case']}")
        right.loglog(c["eps"] * 1e9, c["shear"] * 1e12, style, color="C3", label=f"shear (eq. 3.8), {c['case']}")
    left.set(xlabel="x [um] (flow)", ylabel="z [um] (above the wall)", title="trajectories (thesis fig. 3.4)")
    middle.set(xlabel="t [ms]", ylabel="height change [nm]", title="the lower cell nudged towards the wall")
    right.set(xlabel="separation of the cells' surfaces [nm]", ylabel="lubrication force [pN]",
              title="film forces along the runs (thesis fig. 3.3)")
    for a in (left, middle, right):
        a.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    print(f"wrote {path}")


def main():
    folder = ROOT / "results" / "collision"
    cases = [case(p) for p in sorted(folder.glob("point*.h5"))]
    if not cases:
        raise SystemExit(f"no runs in {folder}: warpbem sweep scenes/fig3_01_04_collision.toml --output-dir {folder}")
    common = min(c["t"][-1] for c in cases)  # runs of different lengths side by side
    for c in cases:
        i = np.searchsorted(c["t"], common * (1 + 1e-9), side="right") - 1
        c.update(common_s=c["t"][i], lower_dz_common_um=(c["x"][i, 0, 2] - c["x"][0, 0, 2]) * 1e6,
                 upper_dz_common_um=(c["x"][i, 1, 2] - c["x"][0, 1, 2]) * 1e6, end_s=c["t"][-1])
    keys = [k for k in cases[0] if k not in ("t", "x", "eps", "squeeze", "shear")]
    out = ROOT / "results" / "collision.csv"
    with out.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(cases)
    for c in cases:
        print({k: (round(c[k], 4) if isinstance(c[k], float) else c[k]) for k in keys})
    print(f"wrote {out}")
    chart(cases, ROOT / "docs" / "figures" / "collision.png")


if __name__ == "__main__":
    main()
