"""The wall's ligand geometry side by side (issue 24 item 1): the same adhesive runs with the
ligands spread through the wall's layer ("layer", a tip binds at its rest length anywhere in a
50 nm band), on a plane at the layer's top ("plane", eq. 4.2's deviation measured to it), and
as sites of a given density on that plane ("sites", 3000 /um^2: one bond per site, eq. 4.2
summed over the sites in reach; forces/bond_model.py).

Cases: thesis Table 4.1 with stiff (100 dyn/cm, fig4_04_06_stiff_bonds.toml) and soft bonds
(0.5 dyn/cm, fig4_09_11_soft_bonds.toml), each a rigid cell and a compliant one (0.508 and
4 kPa, the thesis's), 10 ms on the k = 3 sphere; and three points of the state diagram
(state_diagram.toml, k_r0 = 1 /s at r0 = 0.3, 0.6 and 1.2 A: firm, rolling and no adhesion
under the layer rule), 0.1 s. Each run is ``warpbem run`` in a process of its own (two side by
side with ``--workers 2``), its file kept under ``--output-dir`` (a finished one is read, not run
again; an interrupted one resumes). Per run: the time of the first bond (capture), bonds at the
end, the mean velocity over the last half (a line fitted to x(t)), the state
(``warpbem/app/adhesion_states.py``) and the wall time. A table is printed, a CSV and a chart
written.

    python benchmarks/ligand_geometry.py --workers 2
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from warpbem.app.progress import Progress

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
RULES = {"layer": ["adhesion.ligand_geometry=layer"], "plane": ["adhesion.ligand_geometry=plane"],
         "sites": ["adhesion.ligand_geometry=sites", "adhesion.ligand_density=3.0e15"]}
RIGID = "bodies.0.shear_modulus=1.0e12"  # a_s ~ 0: no contact patch, as the scenes' rigid case
# the Table 4.1 scenes' k = 4 sphere costs 1.5 s per step of a cell that no bond holds (a full
# solve each step); k = 3, as the state diagram's, a few tenths: both rules on the same mesh
K3 = "bodies.0.mesh.subdivisions=3"
CASES = {  # label: (scene, overrides, end time s)
    "stiff, rigid": ("fig4_04_06_stiff_bonds.toml", [RIGID, K3], 0.01),
    "stiff, 0.508 kPa": ("fig4_04_06_stiff_bonds.toml", ["bodies.0.shear_modulus=508.0", K3], 0.01),
    "soft, rigid": ("fig4_09_11_soft_bonds.toml", [RIGID, K3], 0.01),
    "soft, 4 kPa": ("fig4_09_11_soft_bonds.toml", ["bodies.0.shear_modulus=4.0e3", K3], 0.01),
    "k_r0 1, r0 0.3 A": ("state_diagram.toml", ["adhesion.off_rate=1.0", "adhesion.reactive_compliance=0.3e-10"], 0.1),
    "k_r0 1, r0 0.6 A": ("state_diagram.toml", ["adhesion.off_rate=1.0", "adhesion.reactive_compliance=0.6e-10"], 0.1),
    "k_r0 1, r0 1.2 A": ("state_diagram.toml", ["adhesion.off_rate=1.0", "adhesion.reactive_compliance=1.2e-10"], 0.1),
}


def file_name(label: str, rule: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in f"{label}_{rule}") + ".h5"


def finished(path: Path, end: float) -> bool:
    from warpbem.app.io import open_result

    if not path.exists():
        return False
    with open_result(path) as f:
        return len(f["time"]) > 0 and f["time"][-1] >= end * (1 - 1e-9)


def run(label: str, rule: str, out: Path) -> float:
    """Run one case (or resume it); its wall time (s), 0 when it was finished already."""
    scene, overrides, end = CASES[label]
    path = out / file_name(label, rule)
    if finished(path, end):
        return 0.0
    command = [sys.executable, "-m", "warpbem", "run", str(SCENES / scene), "--output", str(path)]
    if path.exists():
        command += ["--resume", "--set", f"time.end={end}"]
    else:
        for value in [*overrides, *RULES[rule], f"time.end={end}"]:
            command += ["--set", value]
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    return time.perf_counter() - start


def measure(label: str, rule: str, path: Path, wall_s: float) -> dict:
    from warpbem.app.adhesion_states import classify
    from warpbem.app.io import open_result

    with open_result(path) as f:
        t, x, u = f["time"][:], f["position"][:, 0, 0], f["velocity"][:, 0, 0]
        bonds = f["bond_count"][:, 0]
    state, ratio = classify(t, x, bonds, u[0])
    half = t >= 0.5 * t[-1]
    bound = np.flatnonzero(bonds > 0)
    return dict(case=label, ligands=rule, first_bond_ms=t[bound[0]] * 1e3 if len(bound) else float("nan"),
                bonds_end=int(bonds[-1]), bonds_max=int(bonds.max()),
                velocity_um_s=np.polyfit(t[half], x[half], 1)[0] * 1e6, free_um_s=u[0] * 1e6,
                v_over_free=ratio, state=state, t_end_ms=t[-1] * 1e3, wall_s=wall_s)


def chart(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    width = 0.8 / len(RULES)
    for k, rule in enumerate(RULES):
        by = {r["case"]: r for r in rows if r["ligands"] == rule}
        at = np.arange(len(labels)) + (k - 0.5 * (len(RULES) - 1)) * width
        for ax, key in zip(axes, ("first_bond_ms", "bonds_end", "v_over_free")):
            ax.bar(at, [by[c][key] if c in by else np.nan for c in labels], width, label=f"ligands: {rule}")
    for ax, title in zip(axes, ("capture: first bond [ms]", "bonds at the end", "V / V_free, last half")):
        ax.set_xticks(range(len(labels)), labels, rotation=35, ha="right", fontsize=8)
        ax.set_title(title, fontsize=10)
    axes[2].set_yscale("log")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--rules", nargs="+", choices=list(RULES), default=list(RULES))
    parser.add_argument("--output-dir", type=Path, default=ROOT / "results" / "bench" / "ligand_geometry")
    args = parser.parse_args()
    args.output_dir.mkdir(parents=True, exist_ok=True)
    jobs = [(label, rule) for label in args.cases for rule in args.rules]
    walls, progress = {}, Progress(len(jobs))
    with ThreadPoolExecutor(max_workers=args.workers) as pool:
        for job, wall in zip(jobs, pool.map(lambda j: run(*j, args.output_dir), jobs)):
            walls[job] = wall
            progress.done(f"{job[0]} ({job[1]}): {wall:.0f} s")
    rows = [measure(label, rule, args.output_dir / file_name(label, rule), walls[(label, rule)])
            for label, rule in jobs]
    keys = list(rows[0])
    print(" | ".join(keys))
    for r in rows:
        print(" | ".join(f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys))
    with open(args.output_dir / "ligand_geometry.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, keys)
        writer.writeheader()
        writer.writerows(rows)
    chart(rows, args.output_dir / "ligand_geometry.png")
    print(f"wrote {args.output_dir / 'ligand_geometry.csv'} and ligand_geometry.png")


if __name__ == "__main__":
    main()
