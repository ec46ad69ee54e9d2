"""Adherent cell shapes from physics (issue 10 item 8; thesis ch. 5.2-5.3, fig. 5.1), set beside
the geometric dome and box the recruitment scenes use (scenes/adherent_dome.q9, adherent_box.q9).

The thesis made its adherent cells by "applying known fluid and chemistry induced external
stresses and holding the resulting deformed cell shape". Here a sphere (a = 5 um, G = 0.5 kPa,
the most compliant cell of Table 4.1, nu = 0.33), held 0.25 um above the wall in shear (100 1/s,
1.2 mPa s), takes through the interior elastic solve (warpbem/elastic/interior.py):

* the fluid's traction on the held cell (``solve_traction``), whose load the bonds carry: a
  traction over the contact, linear across it, with the opposite force and torque;
* the chemistry: adhesion spreads the cell on the wall as an elastic sphere with surface energy W
  (Johnson, Kendall & Roberts 1971; Johnson 1985 ch. 5.5): over the contact radius a the
  pressure is Hertz's compression less the tension of the bonds pulling at its rim,
      p(r) = (2 E* a / (pi R)) sqrt(1 - r^2 / a^2) - sqrt(2 W E* / (pi a)) / sqrt(1 - r^2 / a^2),
  which carries no net force (no external load) when a^3 = 9 pi W R^2 / (2 E*). Bonds are the
  thesis's chemistry: W = n_b e_b, the bond density times the energy of each.

The contact radius is swept; the mesh is graded towards the contact (k = 8, pole_grading 4: 0.25
um elements there) so that the patch is resolved (a Hertz patch flattens as Hertz says to 1.8 %,
tests/verification/test_elastic.py). For each a: the adhesion energy W and the bond density it
takes at 25 kT per bond, the deformed cell's height, its width along the flow, the approach
delta (JKR: a^2 / R - sqrt(2 pi W a / E*)), and the largest displacement; beside them the
geometric dome and box (same volume as the sphere). Writes results/adherent_shapes.csv and
docs/figures/adherent_shapes.png (the x-z profiles).

    python scenes/adherent_shapes.py
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

import warpbem as wb
from warpbem.app.plotting import _pyplot
from warpbem.elastic.deformable import balanced
from warpbem.elastic.interior import InteriorElasticity
from warpbem.elastic.shape import nodal_displacement
from warpbem.surfaces import quad9
from warpbem.surfaces.body import Body
from warpbem.surfaces.mesh import Mesh

ROOT = Path(__file__).resolve().parent.parent
RADIUS, MODULUS, RATIO, GAP = 5e-6, 500.0, 0.33, 0.25e-6
SHEAR, VISCOSITY = 100.0, 1.2e-3
BOND_ENERGY = 25 * 1.380649e-23 * 310.0  # J: 25 kT, a receptor-ligand bond's (Bell 1978 range)
ESTAR = 2 * MODULUS * (1 + RATIO) / (1 - RATIO**2)
GEOMETRIC = {"dome": ("adherent_dome.q9", 4.5e-6), "box": ("adherent_box.q9", 3.25e-6)}


def jkr_energy(a):
    """W (J/m^2) that spreads the sphere to contact radius a with no load: a^3 = 9 pi W R^2 / 2E*."""
    return 2 * ESTAR * a**3 / (9 * np.pi * RADIUS**2)


def jkr_pressure(r, a, energy):
    """Compressive pressure (Pa) of the JKR contact at radius r < a (module docstring)."""
    root = np.sqrt(np.clip(1 - (r / a) ** 2, 1e-12, None))
    return 2 * ESTAR * a / (np.pi * RADIUS) * root - np.sqrt(2 * energy * ESTAR / (np.pi * a)) / root


def adherent_shape(mesh, elastic, fluid, a):
    """The deformed mesh (body frame) and its displacement (nodes) for contact radius a."""
    energy = jkr_energy(a)
    # each element's mean of the JKR pressure, by a 12 x 12 Gauss rule (the rim's singularity is
    # integrable; the rule resolves the patch on elements that straddle its edge)
    points, weights = quad9.surface_quadrature(mesh.element_nodes(), 12)
    rho = np.hypot(points[..., 0], points[..., 1])
    inside = (points[..., 2] < 0) & (rho < a)
    pressure = np.where(inside, jkr_pressure(np.where(inside, rho, 0.0), a, energy), 0.0)
    jacobian = np.linalg.norm(weights, axis=-1)
    patch = inside.any(axis=1)
    traction = fluid.copy()
    traction[:, 2] += (pressure * jacobian).sum(axis=1) / jacobian.sum(axis=1)  # pushes up, into the cell
    # the fluid's load and the discretised JKR pressure's small residual: carried by the bonds, a
    # traction linear across the patch
    traction = balanced(mesh, traction, patch)
    u = nodal_displacement(mesh, elastic.solve(traction).displacement)
    return Mesh(mesh.nodes + u, mesh.elements), u, energy


def measures(nodes, bottom, contact_radius=0.0):
    """(height above the wall, width along the flow) of a surface resting on the wall at
    ``bottom`` (m): its lowest point, or for a contact of radius a the mean height of the nodes
    inside a / 2 (the flattened patch: the displacement of a piecewise-constant traction
    overshoots at the rim's singularity, on the elements there)."""
    z = nodes[:, 2]
    inner = (np.hypot(nodes[:, 0], nodes[:, 1]) < 0.5 * contact_radius) & (z < 0)
    base = z[inner].mean() if inner.any() else z.min()
    return z.max() - base + bottom, nodes[:, 0].max() - nodes[:, 0].min()


def section(mesh, centre_z):
    """(x, z) of the nodes within 0.2 um of the plane y = 0, ordered around the section, the
    reference point at height ``centre_z``."""
    near = np.abs(mesh.nodes[:, 1]) < 0.2e-6
    x, z = mesh.nodes[near, 0], mesh.nodes[near, 2] + centre_z
    order = np.argsort(np.arctan2(z - centre_z, x))
    return np.append(x[order], x[order][0]), np.append(z[order], z[order][0])


def main():
    mesh = wb.mesh.sphere(RADIUS, 8, pole_grading=4.0)
    centre = RADIUS + GAP
    held = Body(mesh, position=(0.0, 0.0, centre), fixed=True)
    holding = wb.solve_mobility([held], SHEAR, VISCOSITY)
    fluid = wb.solve_traction([held], SHEAR, VISCOSITY, True, holding.force, holding.torque).on_mesh(0)
    elastic = InteriorElasticity(mesh, MODULUS, RATIO)
    rows, shapes = [], {}
    for name, (path, height) in GEOMETRIC.items():
        geometric = wb.mesh.load(ROOT / "scenes" / path)
        z = geometric.nodes[:, 2] + height
        base = np.abs(z - z.min()) < 0.05e-6
        top, width = measures(geometric.nodes, GAP)
        rows.append(dict(shape=f"geometric {name}", contact_radius_um=np.hypot(*geometric.nodes[base, :2].T).max() * 1e6,
                         adhesion_energy_uJ_m2=float("nan"), bonds_per_um2=float("nan"), height_um=top * 1e6,
                         width_um=width * 1e6, approach_um=(2 * RADIUS + GAP - top) * 1e6, jkr_approach_um=float("nan"),
                         largest_displacement_over_a=float("nan")))
        shapes[f"geometric {name}"] = (geometric, 0.0)
    for a in (1.0e-6, 1.5e-6, 1.94e-6, 2.79e-6):
        shaped, u, energy = adherent_shape(mesh, elastic, fluid, a)
        top, width = measures(shaped.nodes, GAP, a)
        approach = a**2 / RADIUS - np.sqrt(2 * np.pi * energy * a / ESTAR)
        rows.append(dict(shape=f"elastic JKR, a = {a * 1e6:.2f} um", contact_radius_um=a * 1e6,
                         adhesion_energy_uJ_m2=energy * 1e6, bonds_per_um2=energy / BOND_ENERGY * 1e-12,
                         height_um=top * 1e6, width_um=width * 1e6, approach_um=(2 * RADIUS + GAP - top) * 1e6,
                         jkr_approach_um=approach * 1e6,
                         largest_displacement_over_a=np.linalg.norm(u, axis=1).max() / RADIUS))
        shapes[rows[-1]["shape"]] = (shaped, a)
        print(rows[-1], flush=True)
    out = ROOT / "results" / "adherent_shapes.csv"
    out.parent.mkdir(exist_ok=True)
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print("table:", out)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for label, (shape, contact_radius) in shapes.items():
        top, _ = measures(shape.nodes, GAP, contact_radius)
        x, z = section(shape, top - shape.nodes[:, 2].max())  # resting on its flattened base
        ax.plot(x * 1e6, z * 1e6, "--" if label.startswith("geometric") else "-", lw=1.5, label=label)
    ax.axhline(0.0, color="k", lw=1)
    ax.set(xlabel="x (flow) [um]", ylabel="z [um]", aspect="equal",
           title="adherent cells: geometric (thesis fig. 5.1) and elastic with adhesion (G = 0.5 kPa)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    path = ROOT / "docs" / "figures" / "adherent_shapes.png"
    fig.savefig(path, dpi=120)
    print("chart:", path)


if __name__ == "__main__":
    main()
