"""What an interaction is to the time step (DESIGN.md §3, step 3 "loads"): a configuration
that, bound to a model, answers a small protocol, so that a new force (bonds, Hertz contact,
lubrication) plugs in without touching the step.

Configuration and binding. An ``Interaction`` is a configuration: its parameters only (a
spring constant, densities per body), frozen when made. The ``Model`` holds it beside the
meshes, fixed flags and flow, and is the one source of all of them: when made it calls
``check(model)`` on each interaction, which raises ``ValueError`` where the configuration does
not fit the bodies (one density per body, ligands on fixed bodies only). ``bound(model,
device)`` returns a ``BoundInteraction``: what the configuration derives from the model
(receptor tips sampled on the meshes, the weight of each free body, the size of the bond table)
and, with a device, the device data (compiled kernels, static arrays, assembled elastic
operators). The bound object carries the protocol below; it reads the meshes, fixed flags,
flow and solver options from its ``model``, never from copies of its own.

Two bindings serve a run. The ``Simulator`` binds each interaction on its device and steps
with those (several simulators, on several devices, can share one model). The model keeps its
own binding without a device (``Model.bound_interactions``, made when first asked for), the
host view its own methods read: the bodies' shapes at a state (``Model.bodies``: a deformable
cell's displaced mesh), each interaction's start (``Model.initial_state``) and the state's
layout, which frames write and resumed runs read back (``frame_columns``, ``derived_values``).
Those need the meshes but no device, and the model can then answer without a simulator (a
scene builds its start state before any device is chosen). Both bindings derive from the same
model by the same code (tips from the same seeded stream), so they agree; the host view's
stepping methods (bond kinetics, the elastic solves) are not for use: they raise
``RuntimeError``.

The protocol. A bound interaction is given the bodies of a state (``surfaces.Body``, SI) and
that state's ``Contacts`` (exact gaps, computed once per state and shared), and answers in one
of two ways:

* **explicit**: ``explicit_loads`` returns the force and torque it puts on each body (gravity,
  given loads); the step adds them to the loads of the mobility solve;
* **implicit** (stiff laws: repulsion, bond springs): ``implicit_coordinates`` returns scalar
  coordinates s_c (a separation, a bond length; m) and the loads of a unit force along each;
  ``law(s)`` (the configuration's: it depends on parameters only) gives each coordinate's
  convex energy U (J), its force f = -dU/ds (N, along the unit load) and stiffness dU^2/ds^2
  (N/m). The step takes the forces of every implicit interaction together at the end of the
  step (backward Euler, ``dynamics/implicit.py``):

      s_c' = s_c + dt (r_c + sum_d B_cd f_d),   f_c = f(s_c'),

  with r the rates of the coordinates without the stiff laws and B the response of the rates to
  unit forces (symmetric by reciprocity). By virtual work the rate of a coordinate under rigid
  motions (U_b, Omega_b) is sum_b unit_force_cb . U_b + unit_torque_cb . Omega_b (over the one or
  two bodies b the coordinate acts on), so the same unit loads give both. The frame records the
  law at the state itself, f(s_c).

An interaction that carries state of its own (a bond table, a counter) declares it in
``state_columns`` ({name: (unit, per-frame shape)}), gives its start in ``initial_state`` and
its value after an accepted step in ``advance_state``; the step keeps it in
``State.parts[interaction.name]``, passes it back to the interaction's other methods as
``part``, frames write it as columns ``<name>_<column>`` and a resumed run reads it back.
Columns derived from it (``derived_columns``/``derived_values``) are written under their own
names. ``longest_step`` bounds the step from a state (the bond kinetics: k dt << 1). An
interaction that shapes bodies (deformable cells) gives their meshes from its part in
``body_meshes``, the velocity of their surfaces on top of the rigid motion in
``surface_velocities``, and the part of the step's end in ``advance_shape``, from the start
state. Implicit interactions whose forces act at points of the surfaces (contacts) give those
points with their coordinates (``ImplicitCoordinates.points``), so that a deforming cell feels
them where they act. What a bound interaction keeps between calls is its own (a warning given
once, the bond geometry of the last state): the model and the configuration are never written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..surfaces.gaps import WALL


@dataclass(frozen=True)
class Loads:
    """Force (n, 3) N and torque (n, 3) N m about each body's reference point."""

    force: np.ndarray
    torque: np.ndarray

    @classmethod
    def zero(cls, n_bodies: int) -> "Loads":
        return cls(np.zeros((n_bodies, 3)), np.zeros((n_bodies, 3)))

    def __add__(self, other: "Loads") -> "Loads":
        return Loads(self.force + other.force, self.torque + other.torque)


@dataclass(frozen=True)
class ImplicitCoordinates:
    """Coordinates s_c (m) of an implicit interaction at one state, and the loads of a unit (1 N)
    force along each on the one or two bodies it acts on (a bond: its cell, and the fixed cell
    that carries its ligand; a contact: its two bodies, or one and the wall): ``bodies`` (m, 2)
    their indices, -1 (``WALL``) for none; ``unit_force``, ``unit_torque`` (m, 2, 3) on each
    (zero where there is none); ``points`` (m, 2, 3; NaN where a body takes no load) where the
    unit force acts on each body's surface, for the contact loads that deform cells, or None where
    that does not apply; ``n_bodies`` the model's bodies. Held per coordinate, not per coordinate
    and body, so that thousands of bonds on hundreds of cells cost O(m), not O(m n), per step
    (the rate geometry, the loads and the rates alike)."""

    values: np.ndarray
    bodies: np.ndarray
    unit_force: np.ndarray
    unit_torque: np.ndarray
    n_bodies: int
    points: np.ndarray | None = None

    def _on(self, per_body: np.ndarray) -> np.ndarray:
        """(m, 2, 3) each coordinate's bodies' rows of ``per_body`` (n, 3), zero where it has none."""
        return np.where((self.bodies >= 0)[:, :, None], per_body[np.maximum(self.bodies, 0)], 0.0)

    def rates(self, velocity: np.ndarray, angular_velocity: np.ndarray) -> np.ndarray:
        """ds_c/dt (m/s) for the rigid motions of the bodies (virtual work)."""
        return (np.einsum("cki,cki->c", self.unit_force, self._on(velocity))
                + np.einsum("cki,cki->c", self.unit_torque, self._on(angular_velocity)))

    def part(self, where: slice) -> "ImplicitCoordinates":
        return ImplicitCoordinates(self.values[where], self.bodies[where], self.unit_force[where],
                                   self.unit_torque[where], self.n_bodies,
                                   None if self.points is None else self.points[where])

    @classmethod
    def join(cls, items) -> "ImplicitCoordinates":
        items = list(items)
        points = None
        if any(x.points is not None for x in items):
            points = np.concatenate([np.full(x.unit_force.shape, np.nan) if x.points is None else x.points
                                     for x in items])
        return cls(*(np.concatenate([getattr(x, name) for x in items])
                     for name in ("values", "bodies", "unit_force", "unit_torque")), items[0].n_bodies, points)

    def dense_loads(self) -> tuple[np.ndarray, np.ndarray]:
        """(unit_force, unit_torque) on every body, (m, n_bodies, 3) each: for a few coordinates."""
        force, torque = (np.zeros((len(self.values), self.n_bodies, 3)) for _ in range(2))
        rows, slots = np.nonzero(self.bodies >= 0)
        np.add.at(force, (rows, self.bodies[rows, slots]), self.unit_force[rows, slots])
        np.add.at(torque, (rows, self.bodies[rows, slots]), self.unit_torque[rows, slots])
        return force, torque

    def rate_geometry(self):
        """G (m, 6 n, scipy.sparse CSR): the rate of each coordinate per unit rigid motion
        (velocity, angular velocity) of each body, from its unit loads (virtual work)."""
        import scipy.sparse

        rows, slots = np.nonzero(self.bodies >= 0)
        entries = np.concatenate([self.unit_force[rows, slots], self.unit_torque[rows, slots]], axis=1)  # (k, 6)
        columns = 6 * self.bodies[rows, slots][:, None] + np.arange(6)
        geometry = scipy.sparse.csr_matrix((entries.ravel(), (np.repeat(rows, 6), columns.ravel())),
                                           shape=(len(self.values), 6 * self.n_bodies))
        geometry.eliminate_zeros()
        return geometry

    def loads(self, magnitudes: np.ndarray, bodies_mask: np.ndarray | None = None) -> Loads:
        """Loads of the forces ``magnitudes`` (N) along the coordinates, on the bodies of
        ``bodies_mask`` only (all if None)."""
        rows, slots = np.nonzero(self.bodies >= 0)
        on = self.bodies[rows, slots]
        force, torque = (np.stack([np.bincount(on, weights=magnitudes[rows] * unit[rows, slots, i],
                                               minlength=self.n_bodies) for i in range(3)], axis=1).astype(float)
                         for unit in (self.unit_force, self.unit_torque))  # (integers where there is none)
        if bodies_mask is not None:
            force[~bodies_mask] = 0.0
            torque[~bodies_mask] = 0.0
        return Loads(force, torque)

    def point_loads(self, magnitudes: np.ndarray) -> list:
        """(body, other (the body across the contact, or ``WALL``), point (m), force (N)) of the
        forces ``magnitudes`` (N) along the coordinates that have points, in the order of the
        coordinates and, within one, of the bodies."""
        out = []
        if self.points is None:
            return out
        for c in np.flatnonzero(np.asarray(magnitudes) != 0):
            loaded = [k for k in np.argsort(self.bodies[c], kind="stable")
                      if self.bodies[c, k] >= 0 and np.all(np.isfinite(self.points[c, k]))]
            for k in loaded:
                other = next((int(self.bodies[c, o]) for o in loaded if o != k), WALL)
                out.append((int(self.bodies[c, k]), other, self.points[c, k], magnitudes[c] * self.unit_force[c, k]))
        return out


class Interaction:
    """Base of every interaction's configuration (module docstring): parameters only, frozen.
    ``name`` keys its frame columns and its part of the state; ``implicit``: its forces are a
    stiff law (``law``); ``shapes_bodies``: it sets the bodies' meshes (deformable cells)."""

    name = "interaction"
    shapes_bodies = False  # True: body_meshes / advance_shape apply (deformable cells)
    implicit = False  # True: implicit_coordinates / law apply

    def check(self, model) -> None:
        """Raise ValueError where this configuration does not fit ``model``'s bodies (called by
        the model when it is made); by default anything fits."""

    def bound(self, model, device=None) -> "BoundInteraction":
        """This interaction bound to ``model``: what it derives from the model's meshes, fixed
        flags and flow, with its device data on ``device`` (None: none, the model's host view;
        module docstring); by default a binding that contributes nothing."""
        return BoundInteraction(self, model, device)

    def law(self, s: np.ndarray):
        """(energy J, force N, stiffness N/m) of coordinates at values s (m); energy +inf where
        the law is not defined (layers that touch)."""
        raise NotImplementedError(f"{type(self).__name__} is not an implicit interaction")


class BoundInteraction:
    """An ``interaction`` bound to a ``model`` (and a ``device``, or None: the host view): the
    protocol of the step (module docstring). By default it contributes nothing and owns no
    state; each interaction's binding overrides the methods of its kind."""

    def __init__(self, interaction: Interaction, model, device=None):
        self.interaction, self.model, self.device = interaction, model, device

    @property
    def name(self) -> str:
        return self.interaction.name

    @property
    def implicit(self) -> bool:
        return self.interaction.implicit

    @property
    def shapes_bodies(self) -> bool:
        return self.interaction.shapes_bodies

    def _stepping(self) -> None:
        """Raise where the host view (bound without a device) is asked to step."""
        if self.device is None:
            raise RuntimeError(f"the {self.name} interaction is bound without a device (the model's host view,"
                               " Model.bound_interactions): step with a Simulator, which binds its own")

    def explicit_loads(self, bodies, contacts) -> Loads | None:
        return None

    def implicit_coordinates(self, bodies, contacts, part, velocity, angular_velocity,
                             dt) -> ImplicitCoordinates | None:
        """Coordinates that can matter over a step of at most ``dt`` (s) from this state, given the
        bodies' motion without the stiff laws (m/s, rad/s); None if there are none."""
        return None

    def law(self, s: np.ndarray):
        """The configuration's law (``Interaction.law``)."""
        return self.interaction.law(s)

    def longest_step(self, bodies, contacts, part) -> float:
        """The longest step (s) this interaction allows from this state."""
        return np.inf

    def reuses_mobility(self, part) -> bool:
        """Whether this state holds stiff forces that make mobility snapshots worth their cost
        (``dynamics/hydrodynamics.py``): the bonds of a rolling cell, not a free-stream pass."""
        return False

    def keeps_shape(self, part: dict, tolerance: float) -> bool:
        """Whether the bodies this interaction shapes are within ``tolerance`` (m) of their
        reference shapes at the state of ``part``, so that mobility snapshots serve it."""
        return True

    def state_columns(self) -> dict:
        return {}

    def initial_state(self, bodies) -> dict:
        return {}

    def advance_state(self, part: dict, start_bodies, end_bodies, end_contacts, dt: float, end_time: float) -> dict:
        return part

    def advance_shape(self, part: dict, start_bodies, start_loads: Loads, end_orientations, dt: float,
                      point_loads: list) -> dict:
        """The part of a step's end where it sets the bodies' shapes (deformable cells): from
        the start state's bodies and the external loads over the step (the implicit forces of
        the step's end, ``Evaluation.step_loads``), the end's orientations, the step dt (s) and
        those loads' part at points of the surfaces (``ImplicitCoordinates.point_loads``);
        called before the end's bodies are built, so they take the new shapes."""
        return part

    def body_meshes(self, part: dict, meshes: list, contact: bool = False) -> list:
        """The meshes of the bodies at a state with this part (body frame); ``contact``: the
        shapes the gaps are measured on (a deformable cell's without the flattening of its own
        contact loads); default unchanged."""
        return meshes

    def surface_velocities(self, part: dict, velocities: list) -> list:
        """Per body, the velocity (elements, 3; m/s, body frame) of its surface on top of its
        rigid motion at a state with this part (a deforming cell's), or None; default unchanged."""
        return velocities

    def derived_columns(self) -> dict:
        """{column name: (unit, per-frame shape, description)} computed from ``part``."""
        return {}

    def derived_values(self, part: dict) -> dict:
        return {}
