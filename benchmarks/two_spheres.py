"""Two spheres near contact: the boundary-element grand mobility of two equal 5 um cells in
unbounded fluid against the exact one, the inverse of the resistance of Jeffrey & Onishi (1984)
(warpbem/hydro/two_spheres.py: twin multipole series and lubrication form, checked against the
exact bispherical solutions and Lamb's-method values in tests/verification/test_two_spheres.py).

The pair at surface gaps of 2 down to 0.02 radii along x, library spheres of k = 2, 3, 4
subdivisions with the default contact refinement, the solver's default bilinear density (p = 2)
and the constant one the scenes run with (p = 1); the 12 x 12 mobility from the 12 unit loads
(forces, and torques of 1 N times a) solved together (``MobilitySolver.solve_loads``, from
scratch). Error: the largest change over the largest entry of the mobility with torques and
angular velocities scaled by a (the norm of benchmarks/many_cells.py). Time: the wall time of
the 12 loads' solve. Then the accuracy target (``SolverOptions(accuracy=1e-3)``) from the k = 4
sphere at 0.05 and 0.02 radii: the setting it chooses, its estimate and the error it reaches, on
the mobility and on the pair pushed together (``target_rows``), with that solve's time.

    python benchmarks/two_spheres.py [--quick] [--k 2 3 4] [--density 2 1] [--device cuda:0] [--target-only]

Writes results/bench/two_spheres.csv (and two_spheres_target.csv) and two_spheres.png.
"""

import time
import warnings

import numpy as np

import warpbem as wb
from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.hydro.two_spheres import resistance_matrix

A, MU = 5e-6, 1.2e-3
GAPS = (2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.02)  # surface gap / a
TARGET_GAPS = (0.05, 0.02)
SCALE = np.diag([1.0, 1.0, 1.0, A, A, A] * 2)  # torques and angular velocities times a


def pair(mesh, gap):
    return [wb.Body(mesh, position=(0.0, 0.0, 0.0)), wb.Body(mesh, position=((2 + gap) * A, 0.0, 0.0))]


def exact_mobility(gap):
    return SCALE @ np.linalg.inv(resistance_matrix(MU, A, [(2 + gap) * A, 0.0, 0.0])) @ SCALE


def grand_mobility(solver, bodies):
    """(the scaled 12 x 12 mobility, seconds, GMRES iterations, unknowns, contact unresolved,
    the solutions) of the pair's 12 unit loads solved together."""
    loads = np.eye(12).reshape(12, 2, 2, 3) * np.array([1.0, A])[None, None, :, None]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", wb.ContactResolutionWarning)
        start = time.perf_counter()
        solutions = solver.solve_loads(bodies, loads[:, :, 0], loads[:, :, 1])
        seconds = time.perf_counter() - start
    motion = np.array([np.concatenate([s.velocity[0], s.angular_velocity[0] * A, s.velocity[1],
                                       s.angular_velocity[1] * A]) for s in solutions]).T
    unresolved = any(issubclass(w.category, wb.ContactResolutionWarning) for w in caught)
    return (motion, seconds, max(s.iterations for s in solutions), len(solutions[0].solution_vector),
            unresolved, solutions)


def error(motion, gap):
    exact = exact_mobility(gap)
    return float(np.abs(motion - exact).max() / np.abs(exact).max())


def rows_for(settings, gaps, device):
    rows, progress = [], Progress(len(gaps) * len(settings))
    for p in {p for _, p in settings}:  # an untimed solve first: it compiles the kernels
        options = wb.SolverOptions(density_order=p)
        grand_mobility(wb.MobilitySolver(viscosity=MU, wall=False, device=device, options=options, keep_systems=False),
                       pair(wb.mesh.sphere(A, 2), GAPS[0]))
    for gap in gaps:
        row = dict(gap_over_a=gap, gap_nm=gap * A * 1e9)
        for k, p in settings:
            options = wb.SolverOptions(density_order=p)
            solver = wb.MobilitySolver(viscosity=MU, wall=False, device=device, options=options, keep_systems=False)
            motion, seconds, iterations, unknowns, unresolved, _ = grand_mobility(solver, pair(wb.mesh.sphere(A, k), gap))
            key = f"k{k}p{p}"
            row.update({f"{key}_error": error(motion, gap), f"{key}_seconds": seconds, f"{key}_unknowns": unknowns,
                        f"{key}_iterations": iterations, f"{key}_unresolved": unresolved})
            progress.done(f"gap {gap:g} a, k = {k}, p = {p}")
        rows.append(row)
        print_table([row])
    return rows


def target_rows(gaps, device, accuracy=1e-3):
    """The accuracy target on the pair from the library's k = 4 sphere: its chosen setting and
    estimate; the error it reaches on the 12 x 12 mobility (the 12 loads together) and on the
    pair pushed together along its line of centres (``solve_mobility`` with forces +-1 pN: the
    relative error of the spheres' approach speed against the exact, Jeffrey & Onishi's X11A and
    X12A; the error model's pair quantity) and that solve's wall time, the target's choice and
    assembly included."""
    rows = []
    for gap in gaps:
        options = wb.SolverOptions(accuracy=accuracy)
        solver = wb.MobilitySolver(viscosity=MU, wall=False, device=device, options=options, keep_systems=False)
        bodies = pair(wb.mesh.sphere(A, 4), gap)
        motion, seconds, iterations, unknowns, unresolved, solutions = grand_mobility(solver, bodies)
        chosen = solutions[0].chosen
        start = time.perf_counter()
        squeeze = wb.solve_mobility(bodies, viscosity=MU, wall=False, device=device, options=options,
                                    forces=[[1e-12, 0.0, 0.0], [-1e-12, 0.0, 0.0]])
        squeeze_seconds = time.perf_counter() - start
        exact = exact_mobility(gap)
        approach = squeeze.velocity[0, 0] - squeeze.velocity[1, 0]
        exact_approach = 1e-12 * (exact[0, 0] - exact[0, 6] - exact[6, 0] + exact[6, 6])
        rows.append(dict(gap_over_a=gap, accuracy=accuracy, k=chosen.subdivisions, density_order=chosen.density_order,
                         contact_refinement=chosen.contact_refinement, estimate=chosen.error_estimate,
                         bound=chosen.error_bound, error=error(motion, gap), seconds=seconds, unknowns=unknowns,
                         unresolved=unresolved, approach_error=float(abs(approach / exact_approach - 1)),
                         approach_seconds=squeeze_seconds))
        print_table([rows[-1]])
    return rows


def chart(rows, settings, targets, path):
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    gaps = [r["gap_over_a"] for r in rows]
    for k, p in settings:
        style = dict(marker="osd"[(k - 2) % 3], linestyle="-" if p == 2 else "--")
        left.loglog(gaps, [r[f"k{k}p{p}_error"] for r in rows], label=f"k = {k}, p = {p}", **style)
        right.loglog(gaps, [r[f"k{k}p{p}_seconds"] for r in rows], label=f"k = {k}, p = {p}", **style)
    if targets:
        left.loglog([r["gap_over_a"] for r in targets], [r["error"] for r in targets], "k*", ms=10,
                    label=f"accuracy = {targets[0]['accuracy']:g}")
    left.set(xlabel="surface gap / a", ylabel="largest change / largest entry",
             title="12 x 12 mobility of two spheres against the exact")
    right.set(xlabel="surface gap / a", ylabel="seconds (12 loads, from scratch)", title="cost")
    return save_chart(fig, path, (left, right), legend_size=8)


def main():
    parser = arguments(__doc__)
    parser.add_argument("--k", type=int, nargs="+", default=None, help="sphere subdivisions (default 2 3 4)")
    parser.add_argument("--density", type=int, nargs="+", default=[2, 1], help="density orders p (default 2 1)")
    parser.add_argument("--no-target", action="store_true", help="leave out the accuracy target's part")
    parser.add_argument("--target-only", action="store_true", help="only the accuracy target's part (no chart)")
    args = parser.parse_args()
    targets = []
    if not args.no_target:
        targets = target_rows((0.1,) if args.quick else TARGET_GAPS, args.device)
        write_csv("two_spheres_target.csv", targets)
    if args.target_only:
        return
    ks = args.k or ([2, 3] if args.quick else [2, 3, 4])
    settings = [(k, p) for k in ks for p in args.density]
    gaps = (1.0, 0.1) if args.quick else GAPS
    rows = rows_for(settings, gaps, args.device)
    print_table(rows)
    write_csv("two_spheres.csv", rows)
    print("chart:", chart(rows, settings, targets, output("two_spheres.png")))


if __name__ == "__main__":
    main()
