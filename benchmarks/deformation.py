"""Traction and interior elasticity (issue 10 items 1-2): error against exact solutions and cost,
over the mesh refinement k (6 k^2 elements per sphere), on the machine it runs on:

1. traction: a free sphere in unbounded shear (t = 5 mu E . n exact) and a sphere held at h/a =
   1.1 above the wall (the surface velocity of eq. 2.18, zero exactly), time per solve;
2. elasticity: a sphere under a uniform stress (Hooke's linear displacement exact), time to
   assemble the cell's operators (once per reference shape) and per solve.

    python benchmarks/deformation.py [--quick] [--device cuda:0]

Writes results/bench/deformation.csv and deformation.png (error against time).
"""

import warnings

import numpy as np

import warpbem as wb
from common import arguments, best_time, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.elastic.interior import InteriorElasticity
from warpbem.surfaces.body import Body

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A, MU, SHEAR, G, NU = 5e-6, 1e-3, 100.0, 1e3, 0.33
RATE = 0.5 * SHEAR * np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
STRESS = np.array([[0.0, 0.0, 5.0], [0.0, 2.0, 0.0], [5.0, 0.0, -1.0]])


def traction_row(k, device):
    body = Body(wb.mesh.sphere(A, k))
    s = wb.solve_traction([body], SHEAR, MU, wall=False, device=device)
    exact = 5 * MU * s.normals @ RATE
    free_time = best_time(lambda: wb.solve_traction([body], SHEAR, MU, wall=False, device=device))
    held = Body(wb.mesh.sphere(A, k), position=(0.0, 0.0, 1.1 * A), fixed=True)
    loads = wb.solve_mobility([held], SHEAR, MU, device=device, options=wb.SolverOptions(density_order=1))  # the traction's scheme
    h = wb.solve_traction([held], SHEAR, MU, forces=loads.force, torques=loads.torque, device=device)
    held_time = best_time(lambda: wb.solve_traction([held], SHEAR, MU, forces=loads.force, torques=loads.torque,
                                                    device=device))
    return dict(k=k, elements=6 * k * k, free_error=np.abs(s.traction - exact).max() / np.abs(exact).max(),
                free_s=free_time, held_elements=len(h.traction),
                held_slip=np.abs(h.surface_velocity()).max() / (SHEAR * 1.1 * A), held_s=held_time,
                iterations=h.iterations)


def elastic_row(k, device):
    body = Body(wb.mesh.sphere(A, k))
    assemble = best_time(lambda: InteriorElasticity(body.mesh, G, NU, device), repeats=1)
    elastic = InteriorElasticity(body.mesh, G, NU, device)
    u = elastic.solve(lambda x, n: n @ STRESS)
    strain = STRESS / (2 * G) - NU / (2 * G * (1 + NU)) * np.trace(STRESS) * np.eye(3)
    exact = u.points @ strain.T
    return dict(k=k, elements=6 * k * k, error=np.abs(u.displacement - exact).max() / np.abs(exact).max(),
                assemble_s=assemble, solve_s=best_time(lambda: elastic.solve(lambda x, n: n @ STRESS)),
                iterations=u.iterations)


def chart(traction_rows, elastic_rows, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for rows, err, t, label in ((traction_rows, "free_error", "free_s", "traction, free sphere in shear"),
                                (traction_rows, "held_slip", "held_s", "traction, held at h/a = 1.1: slip"),
                                (elastic_rows, "error", "solve_s", "elastic displacement, uniform stress")):
        ax.loglog([r[t] for r in rows], [r[err] for r in rows], "o-", label=label)
        for r in rows:
            ax.annotate(f"k={r['k']}", (r[t], r[err]), fontsize=7)
    ax.set(xlabel="time per solve [s]", ylabel="largest error / largest exact value",
           title="deformation operators: error against cost")
    return save_chart(fig, path, (ax,), legend_size=8)


def main():
    parser = arguments(__doc__)
    args = parser.parse_args()
    ks = [2, 4] if args.quick else [2, 4, 8, 12]
    progress = Progress(2 * len(ks))  # each k, traction then elasticity
    print("1. traction (completed adjoint double layer)")
    traction_rows = []
    for k in ks:
        traction_rows.append(traction_row(k, args.device))
        progress.done(f"traction, k = {k}")
    print_table(traction_rows)
    write_csv("deformation_traction.csv", traction_rows)
    print("\n2. interior elasticity (Kelvinlet BEM)")
    elastic_rows = []
    for k in ks:
        elastic_rows.append(elastic_row(k, args.device))
        progress.done(f"interior elasticity, k = {k}")
    print_table(elastic_rows)
    write_csv("deformation_elastic.csv", elastic_rows)
    print("chart:", chart(traction_rows, elastic_rows, output("deformation.png")))


if __name__ == "__main__":
    main()
