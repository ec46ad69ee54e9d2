"""The deformable model's additions to the thesis's, one at a time (issue 24 item 4;
warpbem/elastic/deformable.py): the relaxation time tau = 3 mu / 2G (``relaxation``), the
surface's slip with the material (``surface_velocity``) and the gaps that leave out the cell's
response to its own loads (``own_loads_in_gaps = false``). All three off is the thesis's step
(each step's traction on the shape at the instant, solved as a rigid body, turned into the new
shape by eq. 2.25-2.31). From the runs of

    warpbem sweep scenes/fig2_09_11_tank_treading.toml --vary modulus=0.5,1 \\
        --vary deformation.relaxation=true,false --vary deformation.surface_velocity=true,false \\
        --vary time.end=0.03 --output-dir results/additions_tank_treading --workers 2
    warpbem sweep scenes/tumbling_trembling.toml --vary Vi=0.1 \\
        --vary bodies.0.mesh.aspect_ratio=0.7,0.775,0.8,0.85,0.9 \\
        --vary deformation.relaxation=true,false --vary deformation.surface_velocity=true,false \\
        --output-dir results/additions_tumbling --workers 2
    python scenes/deformable_additions.py

for scenes/README.md: the tank-treading cells' Taylor deformation D and inclination over the
last 10 ms and their rise off the wall, beside Roscoe's unbounded linear values, per model; the
tumbling-to-trembling bracket at Vi = 0.1 per model beside the thesis's 0.85-0.91. Neither
scene has a contact, bond or body load, so ``own_loads_in_gaps`` cannot act in them (the
contact part of the displacement is zero by construction); its effect is measured here on the
cell pressed on the wall by 350 pN of tests/verification/test_deformable.py (the repulsion's
force at each of 12 steps of 20 us, with and without it). results/deformable_additions.csv.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from thesis_ch2 import THESIS, roscoe, run_summary, transitions  # noqa: E402

from warpbem.app.io import open_result  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "results"


def model_name(relaxation: bool, slip: bool) -> str:
    if relaxation and slip:
        return "this model (relaxation, slip)"
    if not relaxation and not slip:
        return "the thesis's step (neither)"
    return "without relaxation" if slip else "without slip"


def switches(path: Path) -> tuple[bool, bool]:
    import json

    with open_result(path) as f:
        options = json.loads(f.attrs["scene"]).get("deformation", {})
    return options.get("relaxation", True), options.get("surface_velocity", True)


def tank_treading() -> list[dict]:
    rows = []
    for path in sorted((RESULTS / "additions_tank_treading").glob("point*.h5")):
        r = run_summary(path)
        with open_result(path) as f:
            z = f["position"][:, 0, 2]
        late = r["t"] >= r["t"][-1] - 10e-3
        d_th, angle_th = roscoe(r["Vi"])
        rows.append(dict(scene="tank-treading", model=model_name(*switches(path)), eta_Pa=r["modulus_Pa"],
                         Vi=r["Vi"], D=r["D"][late].mean(), D_roscoe=d_th,
                         inclination_deg=np.degrees(r["angle"][late].mean()),
                         inclination_roscoe_deg=np.degrees(angle_th), rise_um=(z[-1] - z[0]) * 1e6,
                         t_end_ms=r["t"][-1] * 1e3))
    return sorted(rows, key=lambda r: (r["eta_Pa"], r["model"]))


def tumbling() -> list[dict]:
    groups = {}
    for path in sorted((RESULTS / "additions_tumbling").glob("point*.h5")):
        groups.setdefault(model_name(*switches(path)), []).append(run_summary(path))
    rows = []
    for model, runs in sorted(groups.items()):
        for (vi, _), (low, high) in transitions(runs).items():
            regimes = ", ".join(f"{r['kappa']:g} {r['regime']}" for r in sorted(runs, key=lambda r: r["kappa"])
                                if round(r["Vi"], 6) == round(vi, 6))
            rows.append(dict(scene="tumbling/trembling", model=model, Vi=vi, tumbling_up_to=low, trembling_from=high,
                             thesis=f"{THESIS[round(vi, 6)][0]}-{THESIS[round(vi, 6)][1]}", regimes=regimes))
    return rows


def pressed_cell(steps: int = 12) -> list[dict]:
    """The repulsion's force (pN) at each step of a G = 4 kPa cell pressed on the wall by 350 pN
    (tests/verification/test_deformable.py), the gaps without and with the cell's own loads."""
    import warpbem as wb
    from warpbem.dynamics import Flow, Model, Simulator, StepPolicy
    from warpbem.elastic.deformable import Deformation, DeformationOptions
    from warpbem.forces.external import ExternalLoads
    from warpbem.forces.repulsion import Repulsion

    force, radius = 350e-12, 5e-6
    mesh = wb.mesh.sphere(radius, 4)
    layers = np.log(1 + 1e-12 * 2e9 / force) / 2e9  # eq. 3.1 (F0 = 1e-12 J, 2 /nm) at 350 pN
    rows = []
    for counted in (False, True):
        model = Model([mesh], [False], Flow(0.0, 1e-3, True), interactions=[
            Repulsion(), ExternalLoads([[0.0, 0.0, -force]], [[0.0, 0.0, 0.0]]),
            Deformation([True], [4e3], [0.33], DeformationOptions(own_loads_in_gaps=counted))],
            policy=StepPolicy(2e-5, 1e-7, 1e-9), scheme="euler")
        sim = Simulator(model)
        state = model.initial_state([[0.0, 0.0, radius + 225e-9 + layers]])
        held = []
        for _ in range(steps):
            state, frame = sim.step(state)
            held.append(np.linalg.norm(frame.loads["repulsion"].force[0]) * 1e12)
        rows.append(dict(scene="cell pressed on the wall by 350 pN", model=f"own_loads_in_gaps = {counted}".lower(),
                         repulsion_pN=" ".join(f"{f:.0f}" for f in held), low_pN=min(held), high_pN=max(held)))
    return rows


def main():
    rows = tank_treading() + tumbling() + pressed_cell()
    out = RESULTS / "deformable_additions.csv"
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=keys)
        writer.writeheader()
        writer.writerows(rows)
    for r in rows:
        print(" | ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in r.items()))
    print("table:", out)


if __name__ == "__main__":
    main()
