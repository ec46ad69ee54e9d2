"""Deformable cells in time: linear elasticity relaxing through the fluid (thesis ch. 2.2 C,
ch. 2.3; Roscoe 1967 J. Fluid Mech. 28:273).

Kinematics. A deformable cell's surface is its reference mesh displaced in its body frame and
placed rigidly, x = x_c + R (X + u(X)), u the node displacement (``nodal_displacement`` of the
element values, ``shape.py``). The body frame is the material's: R turns with the cell's rigid
rotation, so material points X circulate around a steady shape (tank-treading, thesis fig. 2.12).

Target. The traction on every body at the step's start state (``solve_traction``, closed by
each body's total load over the step, ``Evaluation.step_loads``), turned into the body frame,
gives through the interior elastic problem on the reference mesh (eq. 2.26-2.31,
``interior.py``) the displacement u* = E[R_n^T t_n] that balances it. A body load (gravity, an
applied force) has no surface traction; it is balanced by the smooth traction a + b x (x - c)
with its force and moment (``balanced``). ``update_interval`` = m > 1 re-solves u* every m-th
step only and relaxes towards the kept one (body frame) in between.

Relaxation (``relaxation = True``). The fluid resists the surface's motion: for a sphere in a
linear flow (Roscoe 1967, after Taylor 1932) the fluid traction on a surface moving with strain
rate e is 5 mu E.n - 3 mu e.n and the elastic one 2 G eps.n, so d eps / dt = (eps* - eps) / tau,
tau = 3 mu / (2 G). The model moves every cell's displacement by that law, exactly over a step
for a target held over it: u_(n+1) = u* + (u_n - u*) exp(-dt / tau). In unbounded shear this is
Roscoe's steady state, D = 5 Ca / (2 sqrt(4 + 9 Ca^2)) at (1/2) atan(2 / (3 Ca)) = pi/4 - 3 Ca /
4 + O(Ca^3) from the flow (Ca = mu gdot / G); ``relaxation = False`` takes u_(n+1) = u*, the
quasi-static limit tau -> 0 (D = 5 Ca / 4 at pi/4). The target's traction is the rigid
shape's: the surface motion's own traction is what tau models.

Surface motion (``surface_velocity = True``). The mobility problem is solved on the deformed
surface with the slip w = R du/dt on top of the rigid motion (``Body.surface_velocity``), du/dt
the displacement's mean rate over the last step, (u_(n+1) - u_n) / dt, which keeps the
tank-treading slip of stiff cells (tau << dt). A tank-treading cell's surface then slides along
its steady shape instead of turning with it, which lifts it off the wall (Smart & Leighton
1991; Abkarian, Lartigue & Viallat 2002); solved as rigid at the instant (``surface_velocity =
False``) it drifts towards the wall (scenes/README.md). A target that jumps (a cell released
undeformed, a bond formed) puts its jump into one step's slip.

Contacts. The shape the contact laws see (the gaps of the repulsion, eq. 3.1, the adhesion's
reach and receptor tips) and the slip leave out the cell's response to its own loads,
``contact_displacement``: the elastic response to all its contact, bond and body loads with the
fluid's answer to them (``solve_traction`` ``load_response``, one more solve on the same
operator). Counted in the gaps, that response would act a step late and close a loop of gain ~
(the law's stiffness) x (the cell's compliance under the load); the contact's own compliance is
the law's instead (the steric spring of the roughness layers, the bond's spring, the Hertz patch
below the elements). All loads are left out together: the body loads' fluid answer alone would
open the gap of a cell they press on the wall. The flow sees the whole displacement. Contact
and bond loads act at their points (``ImplicitCoordinates.point_loads``), spread over their
Hertz patch (eq. 4.8-4.9, ``forces/hertz.py``); receptors ride on the surface point under them,
and the Hertz patch of the bonds' normal force still flattens the tips inside it, as on rigid
cells. Mobility snapshots serve a state while max |u| is within their tolerance (``keeps_shape``).
``own_loads_in_gaps = True`` counts that response in the gaps and the slip as well (one shape
for the flow and the contacts, and no extra solve).

The thesis's step (ch. 2.2 C, eq. 2.25-2.31) is each step's traction on the shape at the
instant, solved as a rigid body, turned into the displacement by the interior problem and
taken as the new shape, one shape for everything: ``relaxation = False``, ``surface_velocity =
False``, ``own_loads_in_gaps = True``. Each of the three switches undoes one of this model's
additions to it (scenes/README.md, "The deformable model's additions, one at a time").

Assumptions and limits. Linear elasticity (small strains: D << 1). tau is the sphere's for its
l = 2 mode in unbounded fluid (other modes and shapes, and the wall, change the resistance); the
cell's internal viscosity is not modelled. The target lags the traction by one step (first
order in dt: a cell spinning at Omega shows its inclination Omega dt behind). The film between
close surfaces is in the fluid traction as far as the mesh resolves the gap, with no
lubrication formula on top; a Hertz patch narrower than the elements lands on the nearest one,
so the mesh, not Hertz, sets the contact's resolution. The solver warns (``DeformationWarning``,
once per body) past max |u| / a = ``LINEAR_RANGE`` (0.2, a the equivalent radius: D ~ 0.2,
where a neo-Hookean stress departs from Hooke's by ~D / 2 = 10 %), for a turn per step over
``ROTATION_PER_STEP`` (the target then lags by about half of it) and for an unresolved patch
whose Hertz approach a^2 / R passes 1 nm; it stops (``DeformationError``, naming the body and the
way out) past ``LINEAR_LIMIT`` (0.5) or where the surface folds (a node normal turned over 90
degrees from the reference one; a sphere in unbounded shear folds at Ca ~ 1; docs/deformation.md
(the step's guards).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..forces import hertz
from ..forces.interaction import BoundInteraction, Interaction
from ..options import option, validate
from ..hydro.traction import solve_traction
from ..surfaces.body import rotation_matrix
from ..surfaces.gaps import WALL
from ..surfaces import quad9
from ..surfaces.mesh import Mesh
from ..surfaces.placement import body_label
from .interior import InteriorElasticity, check_material
from .shape import nodal_displacement, nodal_weights, shear_plane_deformation

LINEAR_RANGE = 0.2  # max |u| / a past which the linear material is inaccurate (module docstring)
LINEAR_LIMIT = 0.5  # max |u| / a past which a run stops
UNRESOLVED_APPROACH = 1e-9  # m: a contact patch narrower than the elements warns past this Hertz approach
ROTATION_PER_STEP = 0.1  # rad: a larger turn in one step lags the target by about half of it


def balanced(mesh: Mesh, traction: np.ndarray, where=None) -> np.ndarray:
    """``traction`` (E, 3, Pa) less the traction a + b x (x - c) over the elements ``where``
    (default: the whole surface; c their centroid) with its force and moment, so that it is in
    equilibrium (an elastic solution exists): the smooth balance of a concentrated load."""
    centres, areas, size = mesh.element_nodes()[:, quad9.CENTRE_NODE], mesh.element_areas(), mesh.size()
    where = np.ones(len(areas), bool) if where is None else np.asarray(where, bool)
    arm = (centres - centres[where].T @ areas[where] / areas[where].sum()) / size  # one scale for the least squares
    columns = []
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1.0
        columns += [np.where(where[:, None], e, 0.0), np.where(where[:, None], np.cross(e, arm), 0.0)]

    def resultant(t):  # force, and moment / size
        return np.concatenate([areas @ t, areas @ np.cross(centres, t) / size])

    coefficients = np.linalg.lstsq(np.array([resultant(c) for c in columns]).T, resultant(traction), rcond=None)[0]
    return traction - sum(c * column for c, column in zip(coefficients, columns))


@dataclass(frozen=True)
class DeformationOptions:
    """How deformable cells are modelled (module docstring).

    Examples
    --------
    >>> import warpbem as wb
    >>> wb.DeformationOptions(update_interval=5).relaxation
    True
    """

    relaxation: bool = option(True, "the fluid's resistance to the deformation: relaxation time tau = 3 mu / 2G"
                              " (Roscoe 1967); false: quasi-static, u = u*")
    surface_velocity: bool = option(True, "the flow sees the surface move with the material (false: the deformed"
                                    " shape moves rigidly at the instant)")
    update_interval: int = option(1, "steps between traction and elastic solves (relaxing towards the kept target"
                                  " in between)", low=1, high=1e6)
    own_loads_in_gaps: bool = option(False, "the contact laws' gaps and the surface's slip include the cell's response"
                                     " to its own contact, bond and body loads (true: one shape for all, as the"
                                     " thesis's; false: left out, a step-late loop otherwise)")

    def __post_init__(self):
        validate(self)


class DeformationWarning(UserWarning):
    """A deformable cell outside the range where its model is accurate (it still runs)."""


class DeformationError(RuntimeError):
    """A deformable cell's displacement outside what linear elasticity on its mesh can mean."""


@dataclass(frozen=True)
class Deformation(Interaction):
    """Linear elastic deformation of the ``deformable`` bodies (module docstring; one flag per
    body of the model): per body ``shear_modulus`` (Pa) and ``poisson_ratio``; ``options`` the
    ``DeformationOptions``. The relaxation time takes the model's flow, the traction and the
    interior elastic problem its ``SolverOptions`` (quadrature, contact refinement, GMRES,
    operator mode).

    Examples
    --------
    >>> import warpbem as wb
    >>> soft = wb.Deformation(deformable=[True], shear_modulus=[4e3], poisson_ratio=[0.33])
    >>> model = wb.Model([wb.mesh.sphere(radius=5e-6, subdivisions=2)], [False], interactions=[soft])
    >>> model.interaction("deformation").options.update_interval
    1
    """

    name = "deformation"
    shapes_bodies = True

    deformable: tuple
    shear_modulus: tuple
    poisson_ratio: tuple
    options: DeformationOptions = DeformationOptions()

    def __post_init__(self):
        object.__setattr__(self, "deformable", tuple(bool(d) for d in self.deformable))
        object.__setattr__(self, "shear_modulus", tuple(self.shear_modulus))
        object.__setattr__(self, "poisson_ratio", tuple(self.poisson_ratio))

    def check(self, model):
        if len(self.deformable) != model.n_bodies or not any(self.deformable):
            raise ValueError("deformable must flag each body, at least one of them")
        for i in np.flatnonzero(self.deformable):
            check_material(self.shear_modulus[i], self.poisson_ratio[i])

    def bound(self, model, device=None) -> "BoundDeformation":
        return BoundDeformation(self, model, device)


class BoundDeformation(BoundInteraction):
    """A ``Deformation`` on a model's bodies (``meshes``: the model's reference meshes, body
    frame) and, on a device, what each deformable cell's steps need, assembled once in its body
    frame (it depends on the reference shape only): its interior elastic problem, nodal weights,
    reference node normals and element size."""

    def __init__(self, interaction: Deformation, model, device=None):
        super().__init__(interaction, model, device)
        self.meshes = model.meshes
        self.deformable = np.array(interaction.deformable, dtype=bool)
        self.shear_modulus, self.poisson_ratio = list(interaction.shear_modulus), list(interaction.poisson_ratio)
        options = interaction.options
        self.relaxation, self.update_interval = options.relaxation, options.update_interval
        self.surface_velocity, self.own_loads_in_gaps = options.surface_velocity, options.own_loads_in_gaps
        self.max_nodes = max(len(m.nodes) for m in self.meshes)
        self.radii = [m.equivalent_radius() for m in self.meshes]  # m: the Hertz curvatures, the amplitude scale
        self._warned = set()  # (body, kind) already reported, once per binding
        self.elastic, self.weights, self.normals, self.element_size = {}, {}, {}, {}
        if device is None:
            return  # the model's host view: no elastic problems (forces/interaction.py)
        self.elastic = {i: InteriorElasticity(self.meshes[i], self.shear_modulus[i], self.poisson_ratio[i], device,
                                              options=model.solver)
                        for i in np.flatnonzero(self.deformable)}
        self.weights = {i: nodal_weights(self.meshes[i]) for i in self.elastic}
        self.normals = {i: self._node_normals(self.meshes[i].nodes, i) for i in self.elastic}
        self.element_size = {i: float(np.sqrt(self.meshes[i].element_areas().mean())) for i in self.elastic}

    def relaxation_time(self, i: int) -> float:
        """tau = 3 mu / (2 G) (s) of body i (module docstring); 0 for the quasi-static model."""
        return 1.5 * self.model.flow.viscosity / self.shear_modulus[i] if self.relaxation else 0.0

    def state_columns(self):
        n = len(self.meshes)
        return {"node_displacement": ("m (body frame; rows past a mesh's nodes are zero)", (n, self.max_nodes, 3)),
                "target_displacement": ("m (body frame: the elastic balance of the last traction solved)",
                                        (n, self.max_nodes, 3)),
                "node_velocity": ("m/s (body frame: the displacement's rate over the last step)",
                                  (n, self.max_nodes, 3)),
                "contact_displacement": ("m (body frame: the part of node_displacement from the cell's own loads"
                                         " with the fluid's answer to them, which the gaps leave out)",
                                         (n, self.max_nodes, 3)),
                "contact_target": ("m (body frame: that part of target_displacement)", (n, self.max_nodes, 3)),
                "steps_since_solve": ("1 (steps since the target was solved; per body, all alike)", (n,)),
                "orientation": ("1 (quaternion w, x, y, z of the shape measured)", (n, 4))}

    def initial_state(self, bodies):
        zeros = np.zeros((len(self.meshes), self.max_nodes, 3))
        # the first step solves its target
        return {"node_displacement": zeros, "target_displacement": zeros.copy(), "node_velocity": zeros.copy(),
                "contact_displacement": zeros.copy(), "contact_target": zeros.copy(),
                "steps_since_solve": np.full(len(self.meshes), float(self.update_interval)),
                "orientation": np.array([b.orientation for b in bodies])}

    def keeps_shape(self, part, tolerance):
        """max |u| <= tolerance: the snapshots of the reference shapes then serve the state, the
        surface's slip over a step moving it by no more than that (module docstring)."""
        return bool(np.abs(part["node_displacement"]).max() <= tolerance)

    def body_meshes(self, part, meshes, contact=False):
        out = list(meshes)
        for i in np.flatnonzero(self.deformable):
            nodes = self.meshes[i].nodes
            u = part["node_displacement"][i, :len(nodes)]
            if contact:  # the gaps: without the contact loads' own flattening (module docstring)
                u = u - part["contact_displacement"][i, :len(nodes)]
            out[i] = Mesh(nodes + u, self.meshes[i].elements)
        return out

    def surface_velocities(self, part, velocities):
        if not self.surface_velocity:
            return velocities
        out = list(velocities)
        for i in np.flatnonzero(self.deformable):
            # at the collocation points
            out[i] = part["node_velocity"][i, self.meshes[i].elements[:, quad9.CENTRE_NODE]]
        return out

    def advance_shape(self, part, start_bodies, start_loads, end_orientations, dt, point_loads):
        self._stepping()
        target, contact_target = part["target_displacement"], part["contact_target"]
        age = part["steps_since_solve"]
        if age[0] >= self.update_interval:
            (target, contact_target), age = self._target(start_bodies, start_loads, point_loads), np.zeros_like(age)
        displacement, rate = np.zeros_like(part["node_displacement"]), np.zeros_like(part["node_displacement"])
        contact = np.zeros_like(displacement)
        for i in self.elastic:
            tau = self.relaxation_time(i)
            keep = np.exp(-dt / tau) if tau > 0 else 0.0
            displacement[i] = target[i] + (part["node_displacement"][i] - target[i]) * keep
            contact[i] = contact_target[i] + (part["contact_displacement"][i] - contact_target[i]) * keep
            # over the step, without the contact loads' flattening (module docstring)
            rate[i] = (displacement[i] - contact[i] - part["node_displacement"][i] + part["contact_displacement"][i]) / dt
            self._check(i, displacement[i], start_bodies[i].orientation, end_orientations[i], dt)
        return {"node_displacement": displacement, "target_displacement": target, "steps_since_solve": age + 1.0,
                "node_velocity": rate, "contact_displacement": contact, "contact_target": contact_target,
                "orientation": np.array(end_orientations, dtype=float)}

    def _node_normals(self, nodes, i):
        """Unit normals (E, 9, 3) at the nine nodes of every element of body i's surface through
        ``nodes`` (body frame)."""
        return quad9.unit_normals(nodes[self.meshes[i].elements], *quad9.REFERENCE_NODES.T)

    def _warn_once(self, i, kind, message):
        if (i, kind) not in self._warned:
            self._warned.add((i, kind))
            warnings.warn(message, DeformationWarning, stacklevel=4)

    def _check(self, i, displacement, start_orientation, end_orientation, dt):
        """Stop or warn where the model fails (module docstring: assumptions and limits)."""
        nodes = self.meshes[i].nodes
        amplitude = np.linalg.norm(displacement[:len(nodes)], axis=1).max() / self.radii[i]
        turn = np.einsum("eqi,eqi->eq", self._node_normals(nodes + displacement[:len(nodes)], i), self.normals[i])
        advice = (f"lower the viscous number mu gdot / G (G = {self.shear_modulus[i]:g} Pa) or the loads on the"
                  " cell, or model it as rigid")
        who = f"body {body_label(self.model.names[i], i)}"
        if turn.min() <= 0.0:
            raise DeformationError(f"{who}: the deformed surface folds (an element's normal turned"
                                   f" {np.degrees(np.arccos(max(turn.min(), -1.0))):.0f} degrees from the reference"
                                   f" one, max |u| / a = {amplitude:.2f}): {advice}")
        if amplitude > LINEAR_LIMIT:
            raise DeformationError(f"{who}: its displacement reached {amplitude:.2f} of its radius, beyond"
                                   f" {LINEAR_LIMIT} where linear elasticity means nothing: {advice}")
        if amplitude > LINEAR_RANGE:
            self._warn_once(i, "range", f"{who}: displacement {amplitude:.2f} of its radius, past {LINEAR_RANGE}:"
                            " the linear material departs from a neo-Hookean one by ~10 % and more here")
        q = np.asarray(start_orientation, dtype=float) @ np.asarray(end_orientation, dtype=float)
        angle = 2.0 * np.arccos(min(abs(q), 1.0))
        if angle > ROTATION_PER_STEP:
            self._warn_once(i, "turn", f"{who} turned {angle:.2g} rad in a step of {dt:.3g} s: its shape lags"
                            f" the material by about half that; a step below {ROTATION_PER_STEP} rad of turn"
                            " (time.dt_max) keeps the inclination accurate")

    def contact_radius(self, body: int, other: int, force: float) -> float:
        """Hertz radius a (m; thesis eq. 4.9, ``forces/hertz.py``) of a contact load F (N) between
        ``body`` and ``other`` (a body or the wall), 1/R* = sum 1/R and 1/E* = sum (1 - nu^2) / E
        over the two (the wall and rigid bodies do not yield); 0 if neither yields."""
        pair = (body,) if other == WALL else (body, other)
        total = sum(hertz.compliance(self.shear_modulus[i], self.poisson_ratio[i]) for i in pair if self.deformable[i])
        curvature = sum(1.0 / self.radii[i] for i in pair)
        return float(hertz.contact_radius(abs(force), 1.0 / curvature, total))

    def _target(self, start_bodies, start_loads, point_loads):
        """(u*, its contact part) of every deformable body: the elastic balance of the start
        state's traction, the fluid's and the contact loads' (each spread over its Hertz patch,
        ``solve_traction``); the contact part that of the loads acting without the flow, with
        the fluid's answer to them (module docstring: contacts)."""
        force, torque = start_loads.force.copy(), start_loads.torque.copy()
        spread = []
        for body, other, point, load in point_loads:  # these act on the surface, not as body loads
            force[body] -= load
            torque[body] -= np.cross(point - start_bodies[body].position, load)
            radius = self.contact_radius(body, other, np.linalg.norm(load))
            spread.append((body, point, load, radius))
            # a patch the elements miss, whose Hertz approach a^2 / R (thesis eq. 4.9) matters
            if (self.deformable[body] and radius < self.element_size[body]
                    and radius**2 / self.radii[body] > UNRESOLVED_APPROACH):
                self._warn_once(body, "patch", f"body {body_label(self.model.names[body], body)}: its contact patch"
                                f" (Hertz radius {radius:.2g} m) is"
                                " narrower than its elements: the mesh, not Hertz, sets the contact's flattening")
        # the cells whose own loads' response the gaps leave out (module docstring: contacts)
        loaded = set() if self.own_loads_in_gaps else {body for body, _, _, _ in spread}
        flow = self.model.flow
        traction = solve_traction(start_bodies, flow.shear_rate, flow.viscosity, flow.wall,
                                  force, torque, self.device, point_loads=spread,
                                  load_response=bool(loaded & set(self.elastic)), options=self.model.solver)
        target = np.zeros((len(self.meshes), self.max_nodes, 3))
        contact = np.zeros_like(target)
        for i, elastic in self.elastic.items():
            # each element's traction, in the body frame of the state it was solved at
            rotation = start_bodies[i].rotation()
            total = traction.on_mesh(i) @ rotation
            nodes = slice(0, len(self.meshes[i].nodes))
            # a body load (gravity, an applied force) has no surface traction: its smooth balance
            target[i, nodes] = nodal_displacement(self.meshes[i], elastic.solve(balanced(self.meshes[i], total)).displacement,
                                                  self.weights[i])
            if i in loaded:  # all its loads with the fluid's answer to them (module docstring: contacts)
                loads = balanced(self.meshes[i], traction.on_mesh(i, "loads") @ rotation)
                contact[i, nodes] = nodal_displacement(self.meshes[i], elastic.solve(loads).displacement,
                                                       self.weights[i])
        return target, contact

    def derived_columns(self):
        n = len(self.meshes)
        return {"taylor_deformation": ("1", (n,), "D = (L - B) / (L + B) of each body's best-fit ellipsoid cut by"
                                       " the shear plane (x flow, z gradient)"),
                "inclination_angle": ("rad", (n,), "angle of that section's long axis from the flow direction")}

    def derived_values(self, part):
        d, angle = np.zeros(len(self.meshes)), np.zeros(len(self.meshes))
        for i, mesh in enumerate(self.meshes):
            nodes = (mesh.nodes + part["node_displacement"][i, :len(mesh.nodes)]) @ rotation_matrix(part["orientation"][i]).T
            d[i], angle[i] = shear_plane_deformation(nodes)
        return {"taylor_deformation": d, "inclination_angle": angle}
