"""Where a single solve's time goes at the low-budget end (issue 27 item 2): a free sphere in
wall shear at h/a = 1.5 and 1.1, built from an existing mesh and solved from scratch, at the
settings of the low end of the accuracy front. Each setting: the median of 5 solves after a
warm-up (no profiler), its error against Goldman, Cox & Brenner's exact series
(``tests/verification/sphere_wall_series.py``), and the share of each phase of the solve in a
profiled run of 20 solves (cProfile's cumulative times of the functions named in PHASES; the
phases overlap where one calls another: the refinement lies inside the geometry, and the
assembly inside GMRES where the matrix is built at its first product).

    python benchmarks/setup_cost.py [--heights 1.5 1.1]

Then the same through the accuracy target at each of ACCURACIES (``SolverOptions(accuracy=...)``
alone, the k = 4 library sphere given and rebuilt at the chosen k; the median of 15 solves): the
settings it chose, its estimate and its bound (the estimate times its margin, which the target
keeps within the accuracy).

Targets of issue 27: h/a = 1.5 within 1e-3 in under 5 ms, h/a = 1.1 within 1e-2 in under 10 ms.
"""

import argparse
import cProfile
import pstats
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from common import print_table, write_csv
from warpbem.app.progress import Progress

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
from sphere_wall_series import free_sphere_in_shear  # noqa: E402

# (mesh k, density order p, contact refinement ratio or None for p's default)
SETTINGS = [(2, 1, 0.0), (3, 1, 0.0), (2, 2, 0.0), (2, 2, 0.3), (2, 2, None), (3, 2, None)]
ACCURACIES = (1e-2, 1e-3)
LIBRARY_SPHERE = wb.mesh.sphere(1.0, 4)
# phase: (a file's name ending, a function name) whose cumulative time is the phase's
PHASES = {"geometry": ("hydro/geometry.py", "from_bodies"),
          "refinement": ("surfaces/refinement.py", "refine_near_contact"),
          "assembly": ("kernels/integrals.py", "assemble_entries"),
          "to device": ("hydro/geometry.py", "to_device"),
          "LU factors": ("scipy/linalg/_decomp_lu.py", "lu_factor"),
          "GMRES": ("hydro/deflated.py", "deflated_solve")}


def solver(h, mesh, options):
    return lambda: wb.solve_mobility([wb.Body(mesh, position=(0.0, 0.0, h))], shear_rate=1.0, viscosity=1.0,
                                     options=options)


def phase_shares(solve, repeats=20) -> dict:
    profile = cProfile.Profile()
    profile.enable()
    for _ in range(repeats):
        solve()
    profile.disable()
    stats = pstats.Stats(profile).stats
    total = sum(v[2] for v in stats.values())  # every function's own time: the run's
    shares = {}
    for phase, (ending, name) in PHASES.items():
        shares[phase] = sum(v[3] for (path, _, func), v in stats.items()
                            if path.endswith(ending) and func == name) / total
    return shares


def measured(h: float, mesh, options, repeats: int) -> dict:
    """The row of one setting: its unknowns, the larger error of U and Omega against GCB 1967b,
    the median time of ``repeats`` solves after a warm-up (and, under an accuracy target, what it
    chose, its estimate and its bound)."""
    exact = free_sphere_in_shear(h)
    solve = solver(h, mesh, options)
    solution = solve()  # compile and warm up
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        solution = solve()
        times.append(time.perf_counter() - t)
    u = solution.velocity[0, 0] / h
    omega = solution.angular_velocity[0, 1]
    chosen = solution.chosen
    settings = options.resolved() if chosen is None else options
    return {"h/a": h, "accuracy": "-" if chosen is None else f"{options.accuracy:g}",
            "k": mesh.subdivisions if chosen is None else chosen.subdivisions,
            "p": settings.density_order if chosen is None else chosen.density_order,
            "refinement": ("default" if options.contact_refinement is None else options.contact_refinement)
            if chosen is None else chosen.contact_refinement,
            "unknowns": solution.solution_vector.size,
            "estimate": np.nan if chosen is None else chosen.error_estimate,
            "bound": np.nan if chosen is None else chosen.error_bound,
            "error": max(abs(u / exact["U_over_gdot_h"] - 1), abs(omega / exact["Omega_over_gdot"] - 1)),
            "median_ms": 1e3 * np.median(times)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heights", type=float, nargs="+", default=[1.5, 1.1])
    args = parser.parse_args()
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)  # the settings without refinement, on purpose
    rows, progress = [], Progress(len(args.heights) * (len(SETTINGS) + len(ACCURACIES)))
    for h in args.heights:
        for k, p, ratio in SETTINGS:
            mesh, options = wb.mesh.sphere(1.0, k), wb.SolverOptions(density_order=p, contact_refinement=ratio)
            row = measured(h, mesh, options, 5)
            row.update({f"{phase}_%": 100 * share for phase, share in phase_shares(solver(h, mesh, options)).items()})
            rows.append(row)
            progress.done(f"h/a = {h}, k = {k}, p = {p}, refinement {row['refinement']}: {row['median_ms']:.1f} ms")
        for accuracy in ACCURACIES:
            rows.append(measured(h, LIBRARY_SPHERE, wb.SolverOptions(accuracy=accuracy), 15)
                        | {f"{phase}_%": np.nan for phase in PHASES})
            progress.done(f"h/a = {h}, accuracy {accuracy:g}: {rows[-1]['median_ms']:.1f} ms")
    print_table(rows, {"estimate": "{:.1e}", "bound": "{:.1e}", "error": "{:.1e}", "median_ms": "{:.1f}",
                       **{f"{p}_%": "{:.0f}" for p in PHASES}})
    print(f"table: {write_csv('setup_cost.csv', rows)}")


if __name__ == "__main__":
    main()
