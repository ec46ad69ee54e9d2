"""A free cell carried by wall shear flow across a frozen array of firmly adherent cells (thesis
ch. 5; scenes/array_crossing.toml at a laptop's size): its height and lateral position against
x, its velocity against the lone sphere's.

The adherent cells are the scenes' geometric domes (scenes/adherent_dome.q9, 8.75 um high), in
rows along the flow 30 um apart; the free cell (radius 5 um) passes a row of them at the
thesis's glance of 10.5 um (fig. 5.14), 6 um above the wall. Unlike the scene's 1.05 g/cc cell
it is neutrally buoyant, no load but the flow's, for the second reference below. The domes never
move: their flow is solved once and each solve holds the free cell and the domes within 40 um of
it (``near_far_split``, warpbem/hydro/frozen.py; docs/benchmarks.md, "Frozen adherent arrays").

Two references that do not come from this code. Far upstream the cell moves as a lone sphere in
wall shear, U = X gdot h (Goldman, Cox & Brenner 1967). And Stokes flow is reversible: the
reflection x -> -x about the array's middle, with the flow reversed, maps the wall shear flow,
the array (its domes symmetric fore and aft) and a force-free cell's path onto themselves, so
the path is symmetric about the array's middle: past the array the cell comes back to the
height and the lateral position it started from, whatever the array did to it on the way.

    python examples/free_cell_crossing_array.py           # 3 x 3 domes, k = 4 cell (35 s)

Prints a table (x, y, z in um, U in um/s and over the lone sphere's U at the starting height),
the lift, push and slowing over the array and the path's departure from the symmetry, and writes
the chart free_cell_crossing_array.png (height and lateral position against x) in the working
directory.
"""

import pathlib

import numpy as np

import warpbem as wb
from warpbem import Flow, Model, Simulator, SolverOptions, StepPolicy

DOME = pathlib.Path(__file__).resolve().parents[1] / "scenes" / "adherent_dome.q9"
DOME_CENTRE = 4.5e-6   # m: the dome's reference point above the wall (its base 0.25 um above it)
PITCH = 30e-6          # m: between the domes, along and across the flow
RADIUS = 5e-6          # m: the free cell's
HEIGHT = 6e-6          # m: the free cell's centre above the wall at the start (1 um gap)
GLANCE = 10.5e-6       # m: its lateral offset from the row of domes at y = 0 (thesis fig. 5.14)
SHEAR_RATE = 100.0     # 1/s
VISCOSITY = 1.2e-3     # Pa s
STEP = 5e-3            # s: about 2 um of travel, a fifth of a dome's width
FAR = -2e-3            # m: "far upstream", where the array's disturbance has decayed below the mesh's error


def dome_positions(count):
    """(n, 3) m: an nx x ny array, columns from x = 0 downstream, rows about y = 0."""
    nx, ny = count
    rows = (np.arange(ny) - (ny - 1) // 2) * PITCH
    return np.array([(i * PITCH, y, DOME_CENTRE) for i in range(nx) for y in rows])


def crossing_model(count, subdivisions):
    """The free cell (body 0) and the fixed domes, the domes' flow frozen (the split forced on: by
    default it takes over from 25 adherent cells)."""
    domes = dome_positions(count)
    dome = wb.mesh.load(DOME)
    # the scenes' settings: the free cell's elements split near the wall and the domes (ratio 3, for
    # the time-stepped constant density), the domes' not for their own 0.25 um gap to the wall
    # (the free cell 10.5 um away moves within 0.02 % of the refined U: scenes/README.md)
    solver = SolverOptions(near_far_split="on", contact_refinement=3.0, refine_fixed_at_wall=False)
    model = Model([wb.mesh.sphere(RADIUS, subdivisions)] + [dome] * len(domes), [False] + [True] * len(domes),
                  Flow(SHEAR_RATE, VISCOSITY, wall=True), solver=solver, policy=StepPolicy(STEP), scheme="heun")
    return model, domes


def crossing(count=(3, 3), subdivisions=4, margin=25e-6, device="cpu"):
    """The free cell's path from ``margin`` (m) before the first column of domes to as far past
    the last: an (n, 4) array of rows (x, y, z, U), m and m/s, one per step from the start; and
    U far upstream (``FAR``) at the starting height, a lone sphere's (the same solver: the domes'
    frozen flow and the cell's mesh)."""
    model, domes = crossing_model(count, subdivisions)
    sim = Simulator(model, device)
    state = model.initial_state([[-margin, GLANCE, HEIGHT]] + domes.tolist())
    frame = sim.frame(state)
    rows = [(*state.positions[0], frame.velocity[0, 0])]
    while state.positions[0, 0] < domes[:, 0].max() + margin:
        state, frame = sim.step(state)
        rows.append((*state.positions[0], frame.velocity[0, 0]))
    bodies = model.bodies(state)
    bodies[0] = wb.Body(model.meshes[0], position=(FAR, GLANCE, HEIGHT))
    return np.array(rows), sim.mobility.solve(bodies).velocity[0, 0]


def mirror_offsets(rows, domes):
    """(dy, dz) m: the path's lateral position and height at the mirror image of its start about
    the array's middle (interpolated between the steps around it) less those at its start; zero
    by Stokes reversibility (module docstring), so what is left is the discretisation's."""
    mirror = domes[:, 0].min() + domes[:, 0].max() - rows[0, 0]
    y, z = (np.interp(mirror, rows[:, 0], rows[:, i]) for i in (1, 2))
    return y - rows[0, 1], z - rows[0, 2]


def chart(rows, domes, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (side, top) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    x_um = rows[:, 0] * 1e6
    side.plot(x_um, rows[:, 2] * 1e6, "-", label="free cell's centre")
    side.axhline(HEIGHT * 1e6, color="k", ls=":", lw=0.8, label="a lone cell keeps its height")
    for x in sorted(set(domes[:, 0])):
        side.axvline(x * 1e6, color="0.8", lw=0.8)
    side.set(ylabel="height z [um]", title="free cell crossing an array of adherent domes (shear along x)")
    side.legend(fontsize=8)
    top.plot(x_um, rows[:, 1] * 1e6, "-", label="free cell's centre")
    top.plot(domes[:, 0] * 1e6, domes[:, 1] * 1e6, "o", color="0.6", label="adherent domes (centres)")
    top.set(xlabel="x [um]", ylabel="lateral position y [um]")
    top.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(count=(3, 3), subdivisions=4, margin=25e-6, device="cpu", chart_path="free_cell_crossing_array.png"):
    """The crossing of an ``count`` = (columns, rows) array by a cell of 6 k^2 elements (k =
    ``subdivisions``); prints it and its headline numbers, charts it to ``chart_path`` (None: no
    chart); returns ``crossing``'s path and far-upstream U."""
    rows, far = crossing(count, subdivisions, margin, device)
    domes = dome_positions(count)
    print(" x [um] | y [um] | z [um] | U [um/s] | U / U far")
    for x, y, z, u in rows:
        print(f"{x * 1e6:7.2f} | {y * 1e6:6.3f} | {z * 1e6:6.3f} | {u * 1e6:8.2f} | {u / far:.3f}")
    over = (rows[:, 0] >= domes[:, 0].min()) & (rows[:, 0] <= domes[:, 0].max())
    dy, dz = mirror_offsets(rows, domes)
    print(f"far upstream ({FAR * 1e3:g} mm), {HEIGHT * 1e6:g} um high: U far = {far * 1e6:.2f} um/s (a lone sphere)")
    print(f"over the array: lifted by up to {(rows[:, 2].max() - HEIGHT) * 1e6:.3f} um, pushed aside by up to"
          f" {(rows[:, 1].max() - GLANCE) * 1e6:.3f} um, U down to {rows[over, 3].min() / far:.3f} of U far")
    print(f"past it, at the mirror image of the start: y and z {dy * 1e9:+.1f} and {dz * 1e9:+.1f} nm from the"
          " start's (Stokes reversibility: 0)")
    if chart_path is not None:
        print("chart:", chart(rows, domes, chart_path))
    return rows, far


if __name__ == "__main__":
    main()
