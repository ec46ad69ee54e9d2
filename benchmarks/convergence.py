"""Observed order of convergence under mesh refinement near contact, before and after issue 11.

A sphere at h/a = 1.5, 1.1, 1.05, 1.02 against the exact series of
``tests/verification/sphere_wall_series.py``: U and Omega of the free sphere in wall shear (GCB
1967b), the parallel translational drag F^t* (O'Neill 1964) and the normal drag lambda
(Brenner 1961), on cube-sphere meshes k (6 k^2 elements), for three schemes:

* before: constant density (p = 1), contact refinement at a fixed ratio 3 whatever the mesh
  (reproduced by passing the ratio that the mesh scaling turns back into 3);
* p = 1, the contact refinement scaled with the mesh (surfaces/refinement.py);
* p = 2 (bilinear density), the scaled refinement at its default ratio: the default.

The order between meshes k1 < k2 is log(e1 / e2) / log(k2 / k1) (the element size goes as 1/k).

    python benchmarks/convergence.py [--heights 1.5 1.1 1.05 1.02]
"""

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from common import print_table, write_csv
from warpbem.app.progress import Progress
from warpbem.surfaces.refinement import REFERENCE_ELEMENT_SIZE, relative_element_size

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

SCHEMES = {"before (p=1, fixed ratio 3)": (1, "fixed", (3, 4, 6)),
           "p=1, scaled refinement": (1, None, (3, 4, 6)),
           "p=2, scaled refinement (default)": (2, None, (2, 3, 4, 6))}
QUANTITIES = ("U", "Omega", "Ft", "lambda")


def errors(mesh, h, **options):
    """The four errors at h/a = h with the solver ``options`` (``SolverOptions`` fields)."""
    options = wb.SolverOptions(**options)
    ref = series.free_sphere_in_shear(h)
    t = time.perf_counter()
    free = wb.solve_mobility([wb.Body(mesh, position=(0, 0, h))], shear_rate=1.0, viscosity=1.0, options=options)
    elapsed = time.perf_counter() - t
    par = wb.solve_mobility([wb.Body(mesh, position=(0, 0, h), fixed=True, velocity=(1.0, 0, 0))], viscosity=1.0,
                            options=options)
    nor = wb.solve_mobility([wb.Body(mesh, position=(0, 0, h), fixed=True, velocity=(0, 0, 1.0))], viscosity=1.0,
                            options=options)
    return dict(points=len(free.solution_vector) // 3, time_s=elapsed,
                U=free.velocity[0, 0] / h / ref["U_over_gdot_h"] - 1,
                Omega=free.angular_velocity[0, 1] / ref["Omega_over_gdot"] - 1,
                Ft=par.force[0, 0] / (6 * np.pi * series.parallel_resistance(h)["Ft"]) - 1,
                **{"lambda": nor.force[0, 2] / (6 * np.pi * series.brenner_lambda(h)) - 1})


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heights", type=float, nargs="+", default=[1.5, 1.1, 1.05, 1.02])
    args = parser.parse_args()
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)
    rows, orders = [], []
    progress = Progress(len(args.heights) * sum(len(ks) for _, _, ks in SCHEMES.values()))
    for h in args.heights:
        for scheme, (p, ratio, ks) in SCHEMES.items():
            previous = None
            for k in ks:
                mesh = wb.mesh.sphere(1.0, k)
                # "fixed": the ratio the mesh scaling (refinement.py: meshes finer than k = 4 only)
                # turns back into 3 on this mesh
                scaling = max(1.0, REFERENCE_ELEMENT_SIZE / relative_element_size(mesh.element_nodes()))
                contact = 3.0 / scaling if ratio == "fixed" else ratio
                e = errors(mesh, h, density_order=p, contact_refinement=contact)
                rows.append(dict(h=h, scheme=scheme, k=k, **e))
                progress.done(f"h/a = {h}, {scheme}, k = {k}: {e['points']} points, "
                              + ", ".join(f"{q} {e[q]:+.2e}" for q in QUANTITIES) + f", {e['time_s']:.2f} s")
                if previous is not None:
                    k0, e0 = previous
                    orders.append(dict(h=h, scheme=scheme, ks=f"{k0}->{k}",
                                       **{q: np.log(abs(e0[q]) / abs(e[q])) / np.log(k / k0) for q in QUANTITIES}))
                previous = (k, e)
    print_table(rows)
    print(f"csv: {write_csv('convergence.csv', rows)}")
    print("\nObserved order of convergence (error ~ k^-order):")
    print_table(orders, {q: "{:.1f}" for q in QUANTITIES})
    print(f"csv: {write_csv('convergence_orders.csv', orders)}")


if __name__ == "__main__":
    main()
