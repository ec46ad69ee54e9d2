"""Accuracy table of the mobility solver against the exact sphere-wall solutions.

Relative errors of the free sphere in shear (U, Omega; GCB 1967b), the held sphere (f*, t*),
parallel resistances (Ft, Tr; O'Neill 1964 / GCB 1967a) and normal motion (lambda; Brenner
1961) at several heights, for the seed's scheme on its mesh (k = 4, density constant per
element, p = 1, no contact refinement), p = 1 with contact refinement 3, the default (p = 2,
bilinear density, refinement 1.1) on the seed mesh and on k = 6, with collocation point counts
and times; solver defaults otherwise (2x2 Gauss, adaptive near-field quadrature).

    python benchmarks/accuracy.py [--heights 3 1.5 1.2 1.1 1.05]
"""

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from warpbem.app.progress import Progress

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402  (the reference implementation of the tests)

CONFIGS = {"seed: k=4, p=1, no contact refinement": (4, 1, 0.0), "k=4, p=1, refinement 3": (4, 1, 3.0),
           "default: k=4, p=2, refinement 1.1": (4, 2, 1.1), "k=6, p=2, refinement 1.1": (6, 2, 1.1)}


def solve(mesh, h, ratio, p, fixed=False, motion=None, shear=0.0):
    kwargs = {}
    if motion is not None:
        kwargs = dict(velocity=motion[:3], angular_velocity=motion[3:])
    body = wb.Body(mesh, position=(0, 0, h), fixed=fixed or motion is not None, **kwargs)
    return wb.solve_mobility([body], shear_rate=shear, viscosity=1.0, options=wb.SolverOptions(contact_refinement=ratio, density_order=p))


def errors_at(mesh, h, ratio, p):
    free_ref, held_ref = series.free_sphere_in_shear(h), series.fixed_sphere_in_shear(h)
    par = series.parallel_resistance(h)
    t = time.perf_counter()
    free = solve(mesh, h, ratio, p, shear=1.0)
    elapsed = time.perf_counter() - t
    held = solve(mesh, h, ratio, p, fixed=True, shear=1.0)
    trans = solve(mesh, h, ratio, p, motion=np.array([1.0, 0, 0, 0, 0, 0]))
    rot = solve(mesh, h, ratio, p, motion=np.array([0, 0, 0, 0, 1.0, 0]))
    normal = solve(mesh, h, ratio, p, motion=np.array([0, 0, 1.0, 0, 0, 0]))
    return dict(
        elements=len(free.solution_vector) // 3,
        U=free.velocity[0, 0] / h / free_ref["U_over_gdot_h"] - 1,
        Omega=free.angular_velocity[0, 1] / free_ref["Omega_over_gdot"] - 1,
        f_star=-held.force[0, 0] / (6 * np.pi * h * held_ref["f_star"]) - 1,
        t_star=-held.torque[0, 1] / (4 * np.pi * held_ref["t_star"]) - 1,
        Ft=trans.force[0, 0] / (6 * np.pi * par["Ft"]) - 1,
        Tr=rot.torque[0, 1] / (8 * np.pi * par["Tr"]) - 1,
        lam=normal.force[0, 2] / (6 * np.pi * series.brenner_lambda(h)) - 1,
        time=elapsed, iterations=free.iterations,
    )


def main():
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)  # near contact on purpose
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heights", type=float, nargs="+", default=[3.0, 1.5, 1.2, 1.1, 1.05])
    args = parser.parse_args()
    keys = ["U", "Omega", "f_star", "t_star", "Ft", "Tr", "lam"]
    header = "| config | h/a | points | " + " | ".join(keys) + " | GMRES its | s/solve |"
    print(header)
    print("|" + "---|" * (len(keys) + 5))
    # progress on stderr: the table on stdout stays one markdown table
    progress = Progress(len(CONFIGS) * len(args.heights), lambda line: print(line, file=sys.stderr, flush=True))
    for name, (k, p, ratio) in CONFIGS.items():
        mesh = wb.mesh.sphere(1.0, k)
        for h in args.heights:
            e = errors_at(mesh, h, ratio, p)
            cells = " | ".join(f"{e[key]:+.1e}" for key in keys)
            print(f"| {name} | {h} | {e['elements']} | {cells} | {e['iterations']} | {e['time']:.2f} |", flush=True)
            progress.done(f"{name}, h/a = {h}")


if __name__ == "__main__":
    main()
