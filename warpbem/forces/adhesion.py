"""Receptor-ligand adhesion as an interaction of the time step (thesis ch. 4): Hookean bonds
with Bell kinetics by Monte Carlo and the Hertz contact patch (eq. 4.8, 4.9), between adhesive
free cells and the wall or ligand-bearing fixed cells. The model and its parameters are written
down in ``bond_model.py``; this module holds the configuration (``Adhesion``) and its binding to
a model's bodies (``BoundAdhesion``: the receptors, the bond table, the protocol); the device
code and its launchers are ``kernels/bonds.py``.
"""

from __future__ import annotations

from dataclasses import KW_ONLY, dataclass

import numpy as np

from .. import runtime
from ..options import declared
from ..surfaces.gaps import bounding_spheres
from . import hertz
from .bond_model import BondLaws, BondOptions, sample_receptors
from .interaction import BoundInteraction, ImplicitCoordinates, Interaction
from .repulsion import Repulsion

APPROACH_MARGIN = 100e-9  # m: a cell approaches the wall far less than this in one step
KINETICS_BOUND_TOLERANCE = 1e-9  # relative: a dt_min given as the kinetics' bound is inside it


@dataclass(frozen=True)
class Adhesion(BondLaws, Interaction):
    """Bonds between the adhesive free cells and the wall, or the fixed cells marked in
    ``ligand_bodies`` (module docstring), with the parameters of ``options`` (``BondOptions``;
    layers not given: the default repulsion's roughness); per body of the model
    ``shear_modulus`` (Pa, None or 0: rigid, no contact patch) and ``poisson_ratio``;
    ``adhesive`` (default: every free body). The parameters are also attributes of the same
    names, with the layers ``options`` leaves out taken from ``repulsion``'s roughness (a
    ``Model`` sets it to its own ``Repulsion``; default: the repulsion's defaults). The receptors
    are sampled on the model's meshes when it is bound (``BoundAdhesion``).

    Examples
    --------
    >>> import warpbem as wb
    >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> bonds = wb.Adhesion(wb.BondOptions(spring_constant=5e-4, on_rate=365.0, off_rate=2.4),
    ...                     shear_modulus=[4e3])        # Pa: the Hertz patch of the cell
    >>> model = wb.Model([cell], [False], wb.Flow(shear_rate=100.0), interactions=[wb.Repulsion(), bonds])
    >>> model.interaction("bond").roughness    # m: the receptors' tips, from the repulsion's cell roughness
    1.75e-07
    """

    name = "bond"
    implicit = True

    options: BondOptions
    _: KW_ONLY
    shear_modulus: tuple | None = None
    poisson_ratio: tuple | None = None
    adhesive: tuple | None = None
    ligand_bodies: tuple | None = None
    repulsion: Repulsion = Repulsion()

    def __post_init__(self):
        for name in ("shear_modulus", "poisson_ratio", "adhesive", "ligand_bodies"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, tuple(getattr(self, name)))
        resolved = self.options.resolved(self.repulsion.cell_roughness, self.repulsion.wall_roughness)
        for name, _, _ in declared(BondOptions):  # read as attributes throughout the bond model
            object.__setattr__(self, name, getattr(resolved, name))

    def per_body(self, model):
        """(the adhesive free bodies, the ligand-bearing fixed bodies (indices, in body order),
        each body's shear modulus (Pa; 0: rigid) and Poisson ratio) on ``model``'s bodies;
        ValueError where they do not fit them."""
        n = model.n_bodies
        fixed = model.fixed_mask
        adhesive = ~fixed if self.adhesive is None else np.asarray(self.adhesive, dtype=bool) & ~fixed
        cells = np.flatnonzero(adhesive)
        if not len(cells):
            raise ValueError("adhesion needs at least one adhesive free body")
        carriers = np.zeros(n, dtype=bool) if self.ligand_bodies is None else np.asarray(self.ligand_bodies, dtype=bool)
        if carriers.shape != (n,) or np.any(carriers & ~fixed):
            raise ValueError("ligand_bodies must mark fixed bodies only (one flag per body): ligands on a moving"
                             " cell are not modelled")
        modulus = np.zeros(n) if self.shear_modulus is None else np.array(
            [0.0 if g is None else g for g in self.shear_modulus], dtype=float)
        ratio = np.full(n, 0.33) if self.poisson_ratio is None else np.array(
            [0.33 if v is None else v for v in self.poisson_ratio], dtype=float)
        if modulus.shape != (n,) or np.any(~np.isfinite(modulus)) or np.any(modulus < 0):
            raise ValueError(f"shear_modulus must be >= 0 (Pa) for each of the {n} bodies, got {modulus.tolist()}")
        if ratio.shape != (n,) or np.any(ratio <= -1) or np.any(ratio >= 0.5):
            raise ValueError(f"poisson_ratio must be in (-1, 0.5) for each of the {n} bodies, got {ratio.tolist()}")
        return cells, np.flatnonzero(carriers), modulus, ratio

    def check(self, model):
        """The bodies fit (``per_body``), and the step allows the kinetics: k dt <=
        kinetics_fraction must hold at the shortest step, ``model.policy.dt_min``. The bound is
        compared, and printed, to 1e-9 of itself, so that a dt_min written as the bound (on_rate
        = 1e5 /s, dt_min = 1e-6 s) is not refused by the round-off of kinetics_fraction / rate."""
        self.per_body(model)
        if not model.flow.wall:
            raise ValueError("adhesion: bonds form with ligands on the wall; it needs Flow(wall=True)")
        dt_min = model.policy.dt_min
        for name, rate in (("on_rate", self.fastest_formation), ("off_rate", self.off_rate)):
            longest = self.kinetics_fraction / rate if rate > 0 else float("inf")
            if dt_min > longest * (1 + KINETICS_BOUND_TOLERANCE):
                raise ValueError(f"dt_min: {dt_min:.10g} s is too long for the bond kinetics ({name}: k dt ="
                                 f" {rate * dt_min:.10g} > kinetics_fraction {self.kinetics_fraction:g}); the"
                                 f" allowed range is dt_min <= {longest:.10g} s")

    def bound(self, model, device=None) -> "BoundAdhesion":
        return BoundAdhesion(self, model, device)


class BoundAdhesion(BondLaws, BoundInteraction):
    """The bonds of an ``Adhesion`` on a model's bodies: the receptors sampled on its meshes
    (``tips``, body frame, the cells' in body order from the seed's stream), the bond table's
    layout, and on a device the kernels and static arrays (``kernels/bonds.py``). The
    parameters are attributes of the same names, as on the configuration."""

    def __init__(self, interaction: Adhesion, model, device=None):
        super().__init__(interaction, model, None if device is None else runtime.resolve_device(device))
        for name, _, _ in declared(BondOptions):
            setattr(self, name, getattr(interaction, name))
        self.cells, self.ligand_bodies, self.shear_modulus, self.poisson_ratio = interaction.per_body(model)
        meshes = model.meshes
        self.radius = np.array([m.equivalent_radius() for m in meshes])
        rng = np.random.default_rng(self.seed)
        sampled = [sample_receptors(meshes[b], self.receptor_density, self.roughness, rng) for b in self.cells]
        tips = [t for t, _, _ in sampled]
        self.tips = np.concatenate(tips)
        # the mesh nodes under each tip and their weights: a deformed cell carries its tips
        self.tip_nodes = np.concatenate([meshes[b].elements[e] for b, (_, e, _) in zip(self.cells, sampled)])
        self.tip_weights = np.concatenate([w for _, _, w in sampled])
        self.receptor_body = np.concatenate([np.full(len(t), b) for t, b in zip(tips, self.cells)]).astype(np.int32)
        self.receptor_start = np.concatenate([[0], np.cumsum([len(t) for t in tips])]).astype(np.int32)
        self.receptor_cell = np.repeat(np.arange(len(tips)), [len(t) for t in tips]).astype(np.int32)
        self.n_bodies = model.n_bodies
        self.capacity = self.max_bonds * len(self.cells)
        self._last_state = None  # (contacts, part, vector, moment): _bonds_at
        if self.device is None:
            return  # the model's host view: no device data (forces/interaction.py)
        wp = runtime.init()
        from ..kernels.bonds import build_bond_kernels

        self.wp, self.k = wp, build_bond_kernels(wp.float64)
        wp.load_module(self.k.bond_geometry.module, device=self.device)
        self._tips = wp.array(self.tips, dtype=self.k.vec3, device=self.device)
        self._receptor_body = wp.array(self.receptor_body, dtype=int, device=self.device)
        self._receptor_start = wp.array(self.receptor_start, dtype=int, device=self.device)
        self._receptor_cell = wp.array(self.receptor_cell, dtype=int, device=self.device)
        self._curvature = wp.array(self.radius + self.roughness, dtype=wp.float64, device=self.device)
        # the step's work arrays, kept: allocating and zeroing them at every step took a third of
        # the bond kinetics' time on the 8 x 8 patch (400 000 receptors). The kernels write every
        # entry they read (rupture each row's ``broken``, formation each receptor's ``candidate``,
        # the ligand's columns where it is set), except ``bound``, zeroed at each step.
        n_receptors = len(self.tips)
        self._broken = wp.empty(self.capacity, dtype=int, device=self.device)
        self._bound = wp.empty(n_receptors, dtype=int, device=self.device)
        self._candidate = wp.empty(n_receptors, dtype=int, device=self.device)
        self._ligand = (wp.empty(n_receptors, dtype=self.k.vec3, device=self.device),
                        wp.empty(n_receptors, dtype=wp.float64, device=self.device),
                        wp.empty(n_receptors, dtype=int, device=self.device))
        # without ligand-bearing cells their ligands are the same "none" at every step
        self._no_cell_ligands = None if len(self.ligand_bodies) else self._device_cell_ligands(*self.cell_ligands([]))
        if len(self.ligand_bodies):
            from ..kernels.contact import build_contact_kernels

            self.contact = build_contact_kernels(wp.float64)

    # -- device -----------------------------------------------------------------------------
    def tips_at(self, bodies) -> np.ndarray:
        """The tips (R, 3, body frame) on the bodies' surfaces of a state: the reference tips
        moved by the displacement of the surface under them, for cells whose mesh at the state
        is a deformed one (``Deformation``; the microvillus keeps its reference direction). The
        adhesion passes the shapes the gaps are measured on (``Contacts.shapes``: without the
        cell's response to its own loads, the fluid's answer included, which the bond's spring
        and the Hertz patch carry; elastic/deformable.py, "Contacts")."""
        tips, meshes = self.tips, self.model.meshes
        for c, b in enumerate(self.cells):
            if bodies[b].mesh is not meshes[b]:
                rows = slice(self.receptor_start[c], self.receptor_start[c + 1])
                shift = bodies[b].mesh.nodes - meshes[b].nodes
                tips = tips.copy() if tips is self.tips else tips
                tips[rows] += np.einsum("ra,rai->ri", self.tip_weights[rows], shift[self.tip_nodes[rows]])
        return tips

    def _frame(self, bodies, contacts, part):
        """Device arrays of the configuration: positions, rotations, patch centres and radii."""
        self._stepping()
        wp, k = self.wp, self.k
        centre = np.array([b.position for b in bodies])
        for b, gap in zip(self.cells, contacts.to_wall(self.cells)):
            centre[b] = gap.point  # the foot of the closest point (x, y are used)
        tips = self.tips_at(contacts.shapes)
        return dict(tips=self._tips if tips is self.tips else wp.array(tips, dtype=k.vec3, device=self.device),
                    positions=wp.array(np.array([b.position for b in bodies]), dtype=k.vec3, device=self.device),
                    rotations=wp.array(np.array([b.rotation() for b in bodies]), dtype=k.mat33, device=self.device),
                    patch_centre=wp.array(centre, dtype=k.vec3, device=self.device),
                    patch_radius=wp.array(part["contact_radius"], dtype=wp.float64, device=self.device),
                    curvature=self._curvature)

    def _table(self, part):
        self._stepping()
        wp, k = self.wp, self.k
        return (wp.array(part["receptor"].astype(np.int32), dtype=int, device=self.device),
                wp.array(part["anchor"], dtype=k.vec3, device=self.device),
                wp.array(part["offset"], dtype=wp.float64, device=self.device))

    def geometry(self, table, frame):
        """(vector, moment) device arrays of every table row (``kernels/bonds.py``)."""
        from ..kernels import bonds  # here, not at the top: `import warpbem` must not load Warp

        wp, k = self.wp, self.k
        vector = wp.zeros(self.capacity, dtype=k.vec3, device=self.device)
        moment = wp.zeros(self.capacity, dtype=k.mat33, device=self.device)
        bonds.bond_geometry(k, self.device, self.capacity, *table, frame["tips"], self._receptor_body,
                            frame["positions"], frame["rotations"], vector, moment)
        return vector, moment

    def _bonds_at(self, bodies, contacts, part, rows):
        """(vector, moment) of the bonds ``rows`` at a state, computed once for the step bound
        and the implicit coordinates, which both ask for them (keyed by the state's own Contacts
        and part, which it holds, so the key cannot be a stale object's)."""
        if self._last_state is None or self._last_state[0] is not contacts or self._last_state[1] is not part:
            vector, moment = self.geometry(self._table(part), self._frame(bodies, contacts, part))
            self._last_state = (contacts, part, vector.numpy()[rows], moment.numpy()[rows])
        return self._last_state[2:]

    def tip_forces(self, vector):
        """The force of each bond on its tip (N, (rows, 3)): -sigma (L - lambda) x_b / L (eq. 4.3)."""
        length = np.linalg.norm(vector, axis=1)
        unit = np.divide(vector, length[:, None], out=np.zeros_like(vector), where=length[:, None] > 0)
        return -self.tension(length)[:, None] * unit

    def reduce(self, receptor, moment, bond_force):
        """Per adhesive cell: force (N), torque (N m) and number of bonds (one thread per cell)."""
        from ..kernels import bonds

        wp, k = self.wp, self.k
        cells = len(self.cells)
        force = wp.zeros(cells, dtype=k.vec3, device=self.device)
        torque = wp.zeros(cells, dtype=k.vec3, device=self.device)
        count = wp.zeros(cells, dtype=int, device=self.device)
        forces = wp.array(bond_force, dtype=k.vec3, device=self.device)
        bonds.reduce_per_cell(k, self.device, cells, receptor, moment, forces, self.max_bonds, force, torque, count)
        return force.numpy(), torque.numpy(), count.numpy()

    # -- protocol ---------------------------------------------------------------------------
    def state_columns(self):
        c, n = self.capacity, self.n_bodies
        return {"receptor": ("1 (receptor index, -1: free row)", (c,)), "anchor": ("m", (c, 3)),
                "offset": ("m", (c,)), "partner": ("1 (-1: the wall, else the body carrying the ligand)", (c,)),
                "birth": ("s", (c,)), "count": ("1", (n,)), "contact_radius": ("m", (n,)),
                "contact_force": ("N", (n,)), "draws": ("1", ())}

    def derived_columns(self):
        n = self.n_bodies
        return {"contact_area": ("m^2", (n,), "Hertz contact area pi a_s^2 of each cell (thesis eq. 4.9)"),
                "contact_force": ("N", (n,), "normal component of each cell's bond forces towards the wall, the"
                                  " Hertz load (thesis eq. 4.6)")}

    def derived_values(self, part):
        return {"contact_area": np.pi * part["contact_radius"] ** 2, "contact_force": part["contact_force"]}

    def initial_state(self, bodies):
        c, n = self.capacity, self.n_bodies
        return {"receptor": np.full(c, -1.0), "anchor": np.zeros((c, 3)), "offset": np.zeros(c),
                "partner": np.full(c, -1.0), "birth": np.zeros(c),
                "count": np.zeros(n), "contact_radius": np.zeros(n), "contact_force": np.zeros(n),
                "draws": np.array(0.0)}

    def implicit_coordinates(self, bodies, contacts, part, velocity, angular_velocity, dt):
        """Three coordinates per bond, the components of its vector x_m - x_o: their rates are
        linear in the cell's motion (dx/dt = U + Omega x arm), and the law of the length is exact
        however far the tip moves in a step (a rolling cell's tips move further than a bond is
        long). Their points are the tip on the cell and the anchor on a ligand-bearing cell,
        where the bond's force deforms a deformable one."""
        rows = np.flatnonzero(part["receptor"] >= 0)
        if not len(rows):
            return None
        vector, moment = self._bonds_at(bodies, contacts, part, rows)
        g = len(rows)
        # coordinate 3 g + i: component i of bond g; on its cell (slot 0) and the ligand's (slot 1)
        carriers = np.full((g, 3, 2), -1)
        carriers[:, :, 0] = self.receptor_body[part["receptor"][rows].astype(int)][:, None]
        unit_force, unit_torque = np.zeros((g, 3, 2, 3)), np.zeros((g, 3, 2, 3))
        points = np.full((g, 3, 2, 3), np.nan)
        unit_force[:, :, 0] = np.eye(3)
        unit_torque[:, :, 0] = moment.transpose(0, 2, 1)  # arm x e_i, the columns of [arm]_x
        points[:, :, 0] = (part["anchor"][rows] + vector)[:, None]
        partner = part["partner"][rows].astype(int)
        on_cell = np.flatnonzero(partner >= 0)
        if len(on_cell):  # the reaction on the cell that carries the ligand, at the anchor
            anchors = part["anchor"][rows[on_cell]]
            arm = anchors - np.array([bodies[p].position for p in partner[on_cell]])
            carriers[on_cell, :, 1] = partner[on_cell, None]
            unit_force[on_cell, :, 1] = -np.eye(3)
            unit_torque[on_cell, :, 1] = -np.cross(arm[:, None], np.eye(3))
            points[on_cell, :, 1] = anchors[:, None]
        m = 3 * g
        return ImplicitCoordinates(vector.ravel(), carriers.reshape(m, 2), unit_force.reshape(m, 2, 3),
                                   unit_torque.reshape(m, 2, 3), self.n_bodies, points.reshape(m, 2, 3))

    def cell_ligands(self, bodies):
        """Per receptor, the ligand on a ligand-bearing fixed cell nearest to its rest length:
        (anchor (R, 3), deviation (R,) m, partner (R,) body or -1), from the exact closest point
        of each candidate element (bounding spheres within ``cell_reach``) to the tip."""
        from ..kernels import contact

        n = len(self.tips)
        anchor, deviation, partner = np.zeros((n, 3)), np.full(n, 1.0), np.full(n, -1, dtype=np.int32)
        if len(self.ligand_bodies):
            rotations = np.array([b.rotation() for b in bodies])[self.receptor_body]
            tips = np.array([b.position for b in bodies])[self.receptor_body] + np.einsum("rij,rj->ri", rotations,
                                                                                          self.tips_at(bodies))
        for b in self.ligand_bodies:
            elements = bodies[b].world_nodes()[bodies[b].mesh.elements]
            centres, radii = bounding_spheres(elements)
            near = np.flatnonzero(np.linalg.norm(tips - bodies[b].position, axis=1)
                                  < np.linalg.norm(elements.reshape(-1, 3) - bodies[b].position, axis=1).max()
                                  + self.cell_reach)
            if not len(near):
                continue
            reach = np.linalg.norm(tips[near, None] - centres[None], axis=-1) - radii[None] < self.cell_reach
            receptor, element = np.nonzero(reach)
            if not len(receptor):
                continue
            wp = self.wp
            points = wp.zeros(len(receptor), dtype=self.k.vec3, device=self.device)
            contact.closest_to_points(
                self.contact, self.device, len(receptor),
                wp.array(elements.reshape(-1, 3), dtype=self.k.vec3, device=self.device),
                wp.array(element.astype(np.int32), dtype=int, device=self.device),
                wp.array(tips[near[receptor]], dtype=self.k.vec3, device=self.device), points)
            # per candidate: distance r of the tip from the surface, the ligand at r - lambda
            # (clamped to the layer) along the line to the closest point
            points = points.numpy()
            offset = tips[near[receptor]] - points
            distance = np.linalg.norm(offset, axis=1)
            height = np.clip(distance - self.equilibrium_length, 0.0, self.cell_ligand_layer)
            dev = distance - height - self.equilibrium_length
            for r, p, h, d, o, dist in zip(near[receptor], points, height, dev, offset, distance):
                if abs(d) < abs(deviation[r]):
                    deviation[r], partner[r] = d, b
                    anchor[r] = p + h * o / dist
        return anchor, deviation, partner

    def _device_cell_ligands(self, anchor, deviation, partner):
        """``cell_ligands``'s arrays on the device."""
        wp = self.wp
        return (wp.array(anchor, dtype=self.k.vec3, device=self.device),
                wp.array(deviation, dtype=wp.float64, device=self.device),
                wp.array(partner, dtype=int, device=self.device))

    def reuses_mobility(self, part) -> bool:
        return bool(np.any(part["receptor"] >= 0))

    def longest_step(self, bodies, contacts, part):
        """k dt <= kinetics_fraction for the fastest formation and the fastest rupture at this
        state; no limit while no cell has a bond or a tip within reach (with a margin of
        APPROACH_MARGIN for the approach over one step)."""
        rows = np.flatnonzero(part["receptor"] >= 0)
        if not len(rows):
            lowest = min(gap.distance for gap in contacts.to_wall(self.cells)) - self.roughness
            nearest = min([g.distance for g in contacts.within(self.cell_reach + self.roughness + APPROACH_MARGIN)
                           if g.body in self.cells and g.other in self.ligand_bodies], default=np.inf) - self.roughness
            if lowest > self.reach + APPROACH_MARGIN and nearest > self.cell_reach + APPROACH_MARGIN:
                return np.inf
        rates = [self.fastest_formation, self.off_rate]
        if len(rows):
            vector = self._bonds_at(bodies, contacts, part, rows)[0]
            rates.append(self.rupture_rate(self.tension(np.linalg.norm(vector, axis=1))).max())
        fastest = max(rates)
        return np.inf if fastest == 0 else self.kinetics_fraction / fastest

    def advance_state(self, part, start_bodies, end_bodies, end_contacts, dt, end_time):
        """Rupture, then formation, at the end of the step (counter-based draws 2n and 2n + 1 of
        the seed's stream), then the new contact radius from the bonds' normal force there."""
        from ..kernels import bonds

        self._stepping()
        wp, k = self.wp, self.k
        draw = int(part["draws"])
        receptor, anchor, offset = table = self._table(part)
        birth = wp.array(part["birth"], dtype=wp.float64, device=self.device)
        frame = self._frame(end_bodies, end_contacts, part)
        vector, _ = self.geometry(table, frame)
        broken = self._broken
        bonds.rupture(k, self.device, self.capacity, receptor, vector, self.spring_constant, self.equilibrium_length,
                      int(self.compression), self.off_rate, self.reactive_compliance / self.thermal_energy, dt,
                      self.seed, 2 * draw, broken)
        bound, candidate, (ligand, lowering, chosen) = self._bound, self._candidate, self._ligand
        bound.zero_()
        bonds.mark_bound(k, self.device, self.capacity, receptor, bound)
        cell_ligands = self._no_cell_ligands or self._device_cell_ligands(*self.cell_ligands(end_contacts.shapes))
        partner = wp.array(part["partner"].astype(np.int32), dtype=int, device=self.device)
        bonds.formation(
            k, self.device, len(self.tips),
            bound, frame["tips"], self._receptor_body, frame["positions"], frame["rotations"], frame["patch_centre"],
            frame["patch_radius"], frame["curvature"], self.equilibrium_length, *self.ligand_span,
            self.spring_constant / self.thermal_energy, self.reactive_compliance, self.on_rate, dt,
            self.seed, 2 * draw + 1, *cell_ligands, self.ligand_sites, self._receptor_cell,
            self.max_bonds, receptor, anchor, partner, candidate, ligand, lowering, chosen)
        bonds.insert(k, self.device, len(self.cells), candidate, ligand, lowering, chosen, self._receptor_start,
                     self.max_bonds, end_time, self.cap_rule == "replace", self.seed, 2 * draw + 1,
                     self.ligand_sites is not None, receptor, anchor, offset, partner, birth, bound)
        vector, moment = self.geometry(table, frame)
        on_wall = (partner.numpy() < 0)[:, None]
        force, _, count = self.reduce(receptor, moment, self.tip_forces(vector.numpy()) * on_wall)
        normal, counts = np.zeros(self.n_bodies), np.zeros(self.n_bodies)
        normal[self.cells] = np.maximum(-force[:, 2], 0.0)  # the Hertz load: the wall's bonds only
        counts[self.cells] = count
        compliant = self.shear_modulus > 0
        modulus = np.where(compliant, self.shear_modulus, 1.0)
        # on the rigid, flat wall: R* = the cell's radius, 1 / E* the cell's compliance
        patch = hertz.contact_radius(normal, self.radius, hertz.compliance(modulus, self.poisson_ratio))
        radius = np.where(compliant, patch, 0.0)
        return {"receptor": receptor.numpy().astype(float), "anchor": anchor.numpy().astype(float),
                "offset": offset.numpy(), "partner": partner.numpy().astype(float), "birth": birth.numpy(),
                "count": counts, "contact_radius": radius,
                "contact_force": normal, "draws": np.array(float(draw + 1))}
