"""Lubrication between two cells (issue 10 item 6; thesis ch. 3.2-3.3, fig. 3.3): the squeeze
and shear components of eq. 3.7-3.8 against the surface separation, beside what the boundary
element solution itself gives for the same motions, and the exact squeeze (Maude 1961, Brenner
1961) it is checked against.

Two spheres (a = 5 um, mu = 1.2 mPa s, k = 4 and 8, default contact refinement) held at
separations eps from 2 um down to 20 nm, moved (a) towards each other along their line of
centres at +-U and (b) past each other, normal to it, at +-U without turning (the relative
velocity is 2U either way); the force on one of them against the lubrication formulas and, for
(a), the exact series. The BEM force contains the film's pressure and stress as far as the mesh
resolves the gap: where it matches the exact squeeze, eq. 3.7-3.8 added on top would count the
film twice.

    python benchmarks/lubrication.py [--quick] [--device cuda:0]

Writes results/bench/lubrication.csv and lubrication.png.
"""

import sys
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from common import arguments, output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.forces.lubrication import shear_force, squeeze_force

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

A, MU, U = 5e-6, 1.2e-3, 100e-6


def pair_force(k, eps, velocity, device):
    """Force (N) on sphere A, held with ``velocity``, B with minus it, centres along x."""
    mesh = wb.mesh.sphere(A, k)
    bodies = [wb.Body(mesh, position=(0, 0, 0), fixed=True, velocity=velocity),
              wb.Body(mesh, position=(2 * A + eps, 0, 0), fixed=True, velocity=-np.asarray(velocity))]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", wb.ContactResolutionWarning)
        s = wb.solve_mobility(bodies, viscosity=MU, wall=False, device=device, options=wb.SolverOptions(density_order=1))  # the scenes' scheme
    unresolved = any(issubclass(w.category, wb.ContactResolutionWarning) for w in caught)
    return -s.force[0], len(s.solution_vector) // 3, unresolved  # the fluid's force on A


def rows_for(ks, gaps, device):
    rows, progress = [], Progress(len(gaps))
    for eps in gaps:
        line = np.array([1.0, 0.0, 0.0])
        exact = -6 * np.pi * MU * A * U * series.approaching_spheres_lambda(1 + eps / (2 * A))
        row = dict(eps_nm=eps * 1e9, eps_over_a=eps / A, squeeze_exact_pN=exact * 1e12,
                   squeeze_eq37_pN=squeeze_force(A, MU, eps, [2 * U, 0, 0], line)[0] * 1e12,
                   shear_eq38_pN=shear_force(A, MU, eps, [0, 0, 2 * U], line)[2] * 1e12)
        for k in ks:
            squeeze, elements, unresolved = pair_force(k, eps, (U, 0.0, 0.0), device)
            sliding, _, _ = pair_force(k, eps, (0.0, 0.0, U), device)
            row.update({f"k{k}_squeeze_pN": squeeze[0] * 1e12, f"k{k}_squeeze_error": squeeze[0] / exact - 1,
                        f"k{k}_shear_pN": sliding[2] * 1e12, f"k{k}_elements": elements,
                        f"k{k}_unresolved": unresolved})
        rows.append(row)
        print_table([row])
        progress.done(f"gap {eps * 1e9:g} nm")
    return rows


def chart(rows, ks, path):
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    eps = np.array([r["eps_nm"] for r in rows])
    left.loglog(eps, [-r["squeeze_exact_pN"] for r in rows], "k-", label="exact squeeze (Maude 1961)")
    left.loglog(eps, [-r["squeeze_eq37_pN"] for r in rows], "k--", label="squeeze, eq. 3.7")
    left.loglog(eps, [-r["shear_eq38_pN"] for r in rows], "k:", label="shear, eq. 3.8")
    for k, marker in zip(ks, "os"):
        left.loglog(eps, [-r[f"k{k}_squeeze_pN"] for r in rows], marker, mfc="none", label=f"BEM squeeze, k = {k}")
        left.loglog(eps, [-r[f"k{k}_shear_pN"] for r in rows], marker, label=f"BEM shear, k = {k}")
        right.semilogx(eps, [100 * r[f"k{k}_squeeze_error"] for r in rows], marker + "-", label=f"BEM squeeze, k = {k}")
    right.semilogx(eps, [100 * (r["squeeze_eq37_pN"] / r["squeeze_exact_pN"] - 1) for r in rows], "k--",
                   label="eq. 3.7 alone")
    left.set(xlabel="surface separation eps [nm]", ylabel="force on one cell [pN]",
             title=f"two 5 um cells, relative speed {2 * U * 1e6:.0f} um/s")
    right.set(xlabel="surface separation eps [nm]", ylabel="error against the exact squeeze [%]",
              title="what the BEM resolves")
    right.axhline(0, color="gray", lw=0.5)
    return save_chart(fig, path, (left, right), legend_size=7)


def main():
    parser = arguments(__doc__)
    args = parser.parse_args()
    ks = [4] if args.quick else [4, 8]
    gaps = [1e-6, 1e-7] if args.quick else [2e-6, 1e-6, 5e-7, 3.5e-7, 2.5e-7, 1e-7, 5e-8, 2e-8]
    rows = rows_for(ks, gaps, args.device)
    print_table(rows)
    write_csv("lubrication.csv", rows)
    print("chart:", chart(rows, ks, output("lubrication.png")))


if __name__ == "__main__":
    main()
