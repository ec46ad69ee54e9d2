"""A linearly elastic cell in unbounded simple shear (thesis ch. 2.3): stepped until its shape
settles, its Taylor deformation D = (L - B) / (L + B) (L, B the long and short semi-axes of
the best-fit ellipsoid's section in the shear plane) against the capillary-like number
Ca = mu gdot / G (mu the fluid's viscosity, gdot the shear rate, G the cell's shear modulus).

The reference is the small-deformation limit of an elastic sphere in shear used in
docs/deformation.md: D = 5 Ca / 4 (the sphere's surface traction is that of the uniform stress
5 mu E, Roscoe 1967 J. Fluid Mech. 28:273, after Taylor 1932), and with the fluid's resistance
to the deformation D = 5 Ca / (2 sqrt(4 + 9 Ca^2)) = 5 Ca / 4 - O(Ca^3) (Roscoe's linear
steady state, derived in warpbem/elastic/deformable.py), which parts from 5 Ca / 4 by 1.1 %
at Ca = 0.1.

    python examples/deformable_cell_in_shear.py        # k = 4 cell, Ca = 0.01 ... 0.1

Prints a table (Ca, D, 5 Ca / 4, Roscoe's D, the time to settle) and writes the chart
deformable_cell_in_shear.png (D against Ca with the 5 Ca / 4 line) in the working directory.
"""

import numpy as np

import warpbem as wb
from warpbem import Deformation, DeformationOptions, Flow, Model, Simulator, StepPolicy

RADIUS = 5e-6          # m
SHEAR_RATE = 100.0     # 1/s
VISCOSITY = 1e-3       # Pa s
POISSON_RATIO = 0.33   # the cell's; D at small Ca does not depend on it (the traction is set by the fluid)
STEP = 1e-4            # s: 0.005 rad of the cell's spin per step (docs/deformation.md: D does not depend on it)
SETTLED = 1e-3         # D has settled when it changes by less than this share over one relaxation time


def settled_deformation(ca, subdivisions=4, device="cpu", max_steps=200):
    """(D, time to settle in s) of a cell of Ca = mu gdot / G in unbounded shear, released
    undeformed and stepped until D changes by less than ``SETTLED`` of itself over one relaxation
    time tau = 3 mu / (2 G) (the l = 2 mode's, Roscoe 1967; the displacement approaches its steady
    state as exp(-t / tau), so a settled D is within about SETTLED of the steady one)."""
    modulus = VISCOSITY * SHEAR_RATE / ca                       # Pa
    tau = 1.5 * VISCOSITY / modulus                             # s
    window = max(1, int(np.ceil(tau / STEP)))                   # steps per relaxation time
    model = Model([wb.mesh.sphere(RADIUS, subdivisions)], [False], Flow(SHEAR_RATE, VISCOSITY, wall=False),
                  policy=StepPolicy(STEP), scheme="euler",
                  interactions=[Deformation([True], [modulus], [POISSON_RATIO], DeformationOptions())])
    sim = Simulator(model, device)
    state = model.initial_state([[0.0, 0.0, 0.0]])
    history = []
    for _ in range(max_steps):
        state, frame = sim.step(state)
        history.append(frame.derived["taylor_deformation"][0])
        if len(history) > window and abs(history[-1] - history[-1 - window]) < SETTLED * history[-1]:
            return history[-1], state.time
    raise RuntimeError(f"Ca = {ca}: D did not settle in {max_steps} steps of {STEP} s (last D {history[-3:]})")


def roscoe(ca):
    """Roscoe's linear steady state of an elastic sphere in shear, D = 5 Ca / (2 sqrt(4 + 9 Ca^2))."""
    return 5 * ca / (2 * np.sqrt(4 + 9 * np.asarray(ca) ** 2))


def chart(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ca = np.array([r[0] for r in rows])
    line = np.linspace(0.0, 1.1 * ca.max(), 100)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    ax.plot(line, 1.25 * line, "k:", label="5 Ca / 4 (small deformation)")
    ax.plot(line, roscoe(line), "k-", lw=0.8, label="Roscoe (1967): 5 Ca / (2 sqrt(4 + 9 Ca^2))")
    ax.plot(ca, [r[1] for r in rows], "o", mfc="none", label="warpbem, relaxing linear elastic cell")
    ax.set(xlabel="Ca = mu gdot / G", ylabel="Taylor deformation D = (L - B) / (L + B)",
           title="elastic cell in unbounded shear")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(cas=(0.01, 0.02, 0.05, 0.1), subdivisions=4, device="cpu", chart_path="deformable_cell_in_shear.png"):
    """Each Ca's (Ca, D, settling time in s); the chart to ``chart_path`` (None: no chart)."""
    rows = [(ca, *settled_deformation(ca, subdivisions, device)) for ca in cas]
    print("   Ca  |    D    | 5 Ca / 4 | D / (5 Ca / 4) | Roscoe D | settled at [ms]")
    for ca, d, t in rows:
        print(f"{ca:6.3f} | {d:.5f} | {1.25 * ca:.5f}  |     {d / (1.25 * ca):.4f}     | {roscoe(ca):.5f}  | "
              f"{t * 1e3:.1f}")
    if chart_path is not None:
        print("chart:", chart(rows, chart_path))
    return rows


if __name__ == "__main__":
    main()
