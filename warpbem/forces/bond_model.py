"""The bond model of receptor-ligand adhesion (thesis ch. 4): its parameters (``BondOptions``),
the receptors on a cell (``sample_receptors``) and the rates and law of the bonds
(``BondLaws``: Bell kinetics eq. 4.1, 4.2; Hookean springs eq. 4.3, 4.4). The interaction that
puts them in the time step is ``adhesion.py``; the device code, ``kernels/bonds.py``.

Model, written down (SI):

* Receptors sit at microvillus tips, ``roughness`` (175 nm, Table 4.1) out along the outward
  normal from the surface of each adhesive free cell, placed uniformly by area with density
  ``receptor_density`` (1/m^2) from the seed (a 5 um cell at 20 /um^2 has 6283).
* Ligands are in excess in the substrate layer 0 <= z <= ``ligand_layer`` (its roughness, 50 nm)
  and, as an option, on fixed (adherent) cells (``ligand_bodies``), in the layer of their
  microvilli (``cell_ligand_layer``, 175 nm) above their surface, so a free cell can bind to an
  adherent one: a tip at distance r from that surface (exact closest point, Newton's method on
  the QUAD9 element) binds to one at r - lambda along the line to it, clamped to the layer; a
  bond to a cell pulls that cell back (its holding load carries the reaction).
  On the wall, ``ligand_geometry`` says where the ligands are. The thesis speaks only of a
  "surface attachment point" and gives no ligand density, so each is a completion of its model:
  "layer" (ligands through the layer): a free receptor whose tip is at height z binds to one
  straight below at z - lambda, clamped to the layer, so the bond forms at its rest length lambda
  wherever the tip is within lambda .. lambda + layer of the wall, and stretched or compressed by
  the distance beyond: the most binding-friendly rule, under which eq. 4.2's dependence on the
  stretch acts only outside that band. "plane" (ligands on the plane z = ``ligand_height``): the
  tip binds to the point straight below on the plane, its deviation d = z - h - lambda, eq. 4.2
  as written, for every tip. "layer" is the default: on the plane stiff bonds (100 dyn/cm) at
  Table 4.1's parameters form one or two bonds in 10 ms and the cell passes, against the
  thesis's capture (scenes/README.md, "Where the wall's ligands are": the runs side by side).
  "sites" (ligands of density ``ligand_density`` n_l, the points of a Poisson process on the
  plane z = ``ligand_height``, each binding one receptor): a tip binds a free site within reach,
  its deviation d = |tip - site| - lambda, at the rate of eq. 4.2 summed over the free sites (so
  k_f0 is the rate per site at the rest length and the tip's rate grows as n_l: the
  pseudo-first-order rate of 2D kinetics, k_on n_l), the site drawn in proportion to its rate.
  A tip closer to the plane than lambda binds at its rest length to the sites on a ring of radius
  sqrt(lambda^2 - dz^2) around it (tilted bonds), one farther than lambda only straight below.
  The sites come from a hash of the seed and the squares of a lattice of spacing n_l^(-1/2)
  (``kernels/bonds.py``): the same wall for every step and every cell, unbounded, never stored.
  Layer and plane hold ligands in excess, so ``ligand_density`` goes with "sites" only.
* Formation: k_f = k_f0 exp(sigma |d| (r0 - |d|/2) / kT) (eq. 4.2; d the deviation from lambda);
  rupture: k_r = k_r0 exp(r0 |F| / kT) (eq. 4.1), F = sigma (L - lambda) (only tension when
  ``compression`` is false: a compressed bond is slack); each with probability 1 - exp(-k dt),
  drawn after each accepted step at its end configuration. Note k_f / k_r = (k_f0 / k_r0)
  exp(-sigma d^2 / 2kT): the rates obey detailed balance, so a stiff bond forms only within
  sqrt(2 kT / sigma) of its rest length (0.3 nm at 100 dyn/cm, 4 nm at 0.5 dyn/cm).
* Forces: the bond springs are an implicit interaction (coordinates: bond lengths, energy
  sigma (L - lambda)^2 / 2), solved with the repulsion at the end of each step
  (``dynamics/implicit.py``), so the step is set by the kinetics, k dt <= ``kinetics_fraction``
  (``longest_step``), not by the spring stiffness.
* Contact (ch. 4.2): after each step the normal component of the cell's bond forces,
  F = max(0, -sum F_z), gives the Hertz contact radius a_s = (3 F a / (4 E*))^(1/3) on the
  rigid wall, E* = E / (1 - nu^2), E = 2 G (1 + nu) (eq. 4.9, ``hertz.py``; a the cell's
  equivalent radius); tips within the patch are flattened onto it (``kernels/bonds.py``), so the
  receptors inside the contact area are those within reach. Before any bond has formed a_s = 0
  and the receptors within reach are those of the cap that comes within lambda + layer of the
  wall (the thesis's first-step anchoring). Rigid cells (no shear modulus) keep a_s = 0.
* Cap: at most ``max_bonds`` per cell, which is also the size of each cell's bond table. The
  thesis's cap (figs. 4.12-4.14, L910) "broke any additional bonds that attempted to form" and
  calls the result "artificially induced bond rupture" that makes the rolling noisy; refusing
  a bond breaks none, so ``cap_rule`` offers both readings: "refuse" (the default: a bond that
  would form on a full cell does not) and "replace" (it forms in the place of one of the cell's
  bonds, drawn uniformly, which breaks: the table turns over at the formation rate).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..options import OptionError, option, validate
from ..surfaces import quad9

BOLTZMANN = 1.380649e-23  # J/K
LIGAND_GEOMETRIES = ("layer", "plane", "sites")  # BondOptions.ligand_geometry
CAP_RULES = ("refuse", "replace")  # BondOptions.cap_rule
SITE_SEED_OFFSET = 1_000_003  # the ligand sites' hash seed, seed + this: a wall apart from the seed's other streams


@dataclass(frozen=True)
class BondOptions:
    """The bond model's parameters (module docstring; defaults: thesis Table 4.1).

    Examples
    --------
    >>> import warpbem as wb
    >>> options = wb.BondOptions(spring_constant=5e-4)     # N/m: Table 4.1's soft bonds, 0.5 dyn/cm
    >>> options.spring_constant, options.roughness is None  # layers left to the model's repulsion
    (0.0005, True)
    """

    spring_constant: float | None = option(None, "bond spring constant sigma (eq. 4.3; Table 4.1: 0.5-100 dyn/cm ="
                                           " 5e-4-0.1 N/m). Required", "N/m", kind=float, low=0.0, high=1e3,
                                           low_open=True)
    receptor_density: float = option(20e12, "receptors per area of an adhesive cell's surface, at its microvillus"
                                     " tips", "1/m^2", low=0.0, high=1e18, low_open=True)
    ligand_density: float | None = option(None, "ligands per area of the wall, for ligand_geometry = sites (required"
                                          " there; layer and plane hold ligands in excess)", "1/m^2", kind=float,
                                          low=0.0, high=1e18, low_open=True)
    equilibrium_length: float = option(30e-9, "bond rest length lambda (eq. 4.3)", "m", low=0.0, high=1e-6)
    off_rate: float = option(2.4, "unstressed rupture rate k_r0 (eq. 4.1)", "1/s", low=0.0, high=1e9)
    on_rate: float = option(365.0, "formation rate k_f0 at the rest length (eq. 4.2)", "1/s", low=0.0, high=1e9)
    reactive_compliance: float = option(0.39e-10, "Bell's reactive compliance r0 (eq. 4.1-4.2)", "m", low=0.0,
                                        high=1e-8)
    temperature: float = option(310.0, "absolute temperature T (k T in eq. 4.1-4.2)", "K", low=0.0, high=1e4,
                                low_open=True)
    max_bonds: int = option(100, "cap of bonds per cell (the size of its bond table)", low=1, high=1e5)
    cap_rule: str = option("refuse", "what a bond that forms on a cell at its cap does: refuse (it does not form) or"
                           " replace (it takes the place of one of the cell's bonds drawn at random, which breaks)",
                           choices=CAP_RULES)
    compression: bool = option(False, "bonds resist compression too (false: a compressed bond is slack)")
    seed: int = option(0, "seed of the receptors' placement and the bond Monte Carlo", low=0, high=2**31 - 1)
    roughness: float | None = option(None, "tip height of the receptors above the surface. Default: the repulsion's"
                                     " cell_roughness", "m", kind=float, low=0.0, high=1e-5)
    ligand_layer: float | None = option(None, "thickness of the wall's ligand layer. Default: the repulsion's"
                                        " wall_roughness", "m", kind=float, low=0.0, high=1e-5)
    ligand_geometry: str = option("layer", "where the wall's ligands are: layer (spread through 0 <= z <="
                                  " ligand_layer: a tip at height z binds the one at z - lambda, clamped to the layer,"
                                  " so inside it every bond forms at its rest length), plane (on the plane z ="
                                  " ligand_height: eq. 4.2's deviation measured to it) or sites (ligand_density"
                                  " sites on that plane, one bond each)", choices=LIGAND_GEOMETRIES)
    ligand_height: float | None = option(None, "height of the ligand plane (ligand_geometry = plane or sites)."
                                         " Default: the top of the ligand layer, ligand_layer", "m", kind=float,
                                         low=0.0, high=1e-5)
    kinetics_fraction: float = option(0.1, "the step keeps k dt below this for every bond rate", low=0.0, high=1.0,
                                      low_open=True)
    cell_ligand_layer: float | None = option(None, "thickness of the ligand layer on adherent cells. Default: the"
                                             " repulsion's cell_roughness", "m", kind=float, low=0.0, high=1e-5)

    def __post_init__(self):
        validate(self)
        if self.spring_constant is None:
            raise OptionError("spring_constant: missing (N/m; thesis Table 4.1: 0.5-100 dyn/cm = 5e-4-0.1 N/m)")
        if (self.ligand_geometry == "sites") != (self.ligand_density is not None):
            raise OptionError("ligand_density: give it with ligand_geometry = \"sites\" and only then (1/m^2; layer"
                              " and plane hold ligands in excess)")

    def resolved(self, cell_roughness: float, wall_roughness: float) -> "BondOptions":
        """The layers not given taken from the repulsion's roughness (m), the ligand plane at the
        top of the wall's layer."""
        layer = wall_roughness if self.ligand_layer is None else self.ligand_layer
        return dataclasses.replace(
            self, roughness=cell_roughness if self.roughness is None else self.roughness,
            ligand_layer=layer,
            ligand_height=layer if self.ligand_height is None else self.ligand_height,
            cell_ligand_layer=cell_roughness if self.cell_ligand_layer is None else self.cell_ligand_layer)


def sample_receptors(mesh, density: float, roughness: float, rng):
    """Tips (n, 3), body frame: points uniform by area on the QUAD9 surface (element by area,
    then (s, t) by rejection on the surface Jacobian), moved ``roughness`` out along the normal;
    and where each sits, (element (n,), shape function values (n, 9)) of its surface point, so
    that a deforming surface carries it."""
    nodes = mesh.element_nodes()
    areas = mesh.element_areas()
    count = int(round(density * areas.sum()))
    tips, sites, weights = np.empty((0, 3)), np.empty(0, dtype=int), np.empty((0, 9))
    while len(tips) < count:
        n = 2 * (count - len(tips)) + 16
        element = rng.choice(len(areas), size=n, p=areas / areas.sum())
        s, t = rng.uniform(-1, 1, size=(2, n))
        values, ds, dt = quad9.shape_functions(s, t)
        x = np.einsum("na,nai->ni", values, nodes[element])
        normal = np.cross(np.einsum("na,nai->ni", ds, nodes[element]), np.einsum("na,nai->ni", dt, nodes[element]))
        jacobian = np.linalg.norm(normal, axis=1)
        bound = 1.25 * areas[element] / 4.0  # above the element's largest Jacobian on these meshes
        keep = rng.uniform(0, 1, size=n) * bound < jacobian
        tips = np.concatenate([tips, (x + roughness * normal / jacobian[:, None])[keep]])
        sites, weights = np.concatenate([sites, element[keep]]), np.concatenate([weights, values[keep]])
    return tips[:count], sites[:count], weights[:count]


class BondLaws:
    """The bond model's rates and law (module docstring) from its parameters, the attributes of
    ``BondOptions``'s names (its layers resolved), which the configuration (``Adhesion``) and
    its binding (``BoundAdhesion``) both carry."""

    @property
    def thermal_energy(self) -> float:
        return BOLTZMANN * self.temperature

    @property
    def sites_in_reach(self) -> float:
        """With ligand sites, twice the expected number that a tip closer to the plane than lambda
        finds near its rest length, n_l 2 pi lambda sqrt(2 pi kT / sigma) (the ring of radius
        sqrt(lambda^2 - dz^2) and width |d| ~ sqrt(kT / sigma) around it; the factor 2 for its
        fluctuation), at least 1; 1 for ligands in excess."""
        if self.ligand_geometry != "sites":
            return 1.0
        ring = 2.0 * np.pi * self.equilibrium_length * np.sqrt(2.0 * np.pi * self.thermal_energy / self.spring_constant)
        return max(1.0, 2.0 * self.ligand_density * ring)

    @property
    def fastest_formation(self) -> float:
        """The largest k_f of eq. 4.2 (1/s), at d = r0, for the sites within reach of a tip."""
        return self.on_rate * self.sites_in_reach * np.exp(self.spring_constant * self.reactive_compliance**2
                                                           / (2.0 * self.thermal_energy))

    @property
    def reach_deviation(self) -> float:
        """The deviation |d| (m) past which eq. 4.2 falls below 1e-6 of k_f0 (sigma d^2 / 2 kT ~
        ln 1e6)."""
        return np.sqrt(2.0 * self.thermal_energy * np.log(1e6) / self.spring_constant) + self.reactive_compliance

    @property
    def ligand_sites(self) -> tuple | None:
        """(density 1/m^2, lattice spacing m, seed, deviation m) of the wall's ligand sites for the
        formation kernel, None for ligands in excess (module docstring)."""
        if self.ligand_geometry != "sites":
            return None
        return (self.ligand_density, self.ligand_density**-0.5, (self.seed + SITE_SEED_OFFSET) % 2**31,
                self.reach_deviation)

    def rupture_rate(self, force):
        """k_r of eq. 4.1 for bond forces (N; tension positive)."""
        return self.off_rate * np.exp(self.reactive_compliance * np.abs(force) / self.thermal_energy)

    def tension(self, length):
        """Bond force sigma (L - lambda) (N, tension positive; slack bonds carry none unless
        ``compression``)."""
        f = self.spring_constant * (np.asarray(length, dtype=float) - self.equilibrium_length)
        return f if self.compression else np.maximum(f, 0.0)

    def law(self, s):
        """U = sigma (|x| - lambda)^2 / 2 of each bond vector x (only |x| > lambda when bonds
        resist tension only), f = -dU/dx, and the 3 x 3 Hessian sigma [x^ x^ + (stretch / |x|)
        (I - x^ x^)] (its transverse part left out where a compressed bond makes it negative)."""
        x = s.reshape(-1, 3)
        length = np.linalg.norm(x, axis=1)
        unit = np.divide(x, length[:, None], out=np.zeros_like(x), where=length[:, None] > 0)
        stretch = length - self.equilibrium_length
        if not self.compression:
            stretch = np.maximum(stretch, 0.0)
        sigma = self.spring_constant
        outer = unit[:, :, None] * unit[:, None, :]
        radial = np.where(self.compression | (stretch > 0), sigma, 0.0)[:, None, None] * outer
        transverse = sigma * np.divide(np.maximum(stretch, 0.0), length, out=np.zeros_like(length), where=length > 0)
        stiffness = radial + transverse[:, None, None] * (np.eye(3) - outer)
        energy = np.repeat(0.5 * sigma * stretch**2 / 3.0, 3)
        return energy, (-sigma * stretch[:, None] * unit).ravel(), stiffness

    @property
    def ligand_span(self) -> tuple:
        """(lowest, highest) height (m) of the wall's ligands: the layer (0, ligand_layer), or the
        plane, with or without sites (ligand_height, ligand_height) (module docstring)."""
        if self.ligand_geometry != "layer":
            return self.ligand_height, self.ligand_height
        return 0.0, self.ligand_layer

    @property
    def reach(self) -> float:
        """Height (m) of a tip above the wall beyond which formation is below 1e-6 of k_f0:
        lambda + the highest ligand + the deviation where eq. 4.2 falls to that (sigma d^2 / 2 kT
        ~ ln 1e6)."""
        return self.equilibrium_length + self.ligand_span[1] + self.reach_deviation

    @property
    def cell_reach(self) -> float:
        """As ``reach``, from the surface of a ligand-bearing cell (its layer: its microvilli)."""
        return self.reach - self.ligand_span[1] + self.cell_ligand_layer
