"""Time stepping of a ``Model`` (DESIGN.md §3): the one place that fixes the order of a step.

    geometry  : the bodies of the state, placement checked
    contacts  : exact gaps, once per state, shared (surfaces.gaps.Contacts)
    loads     : explicit interactions (gravity, given loads) -> mobility (``hydrodynamics.py``:
                exact, or from snapshots reused across steps) -> the implicit interactions'
                coordinates (repulsion: contacts within reach; bonds) and the motion of the
                basis their forces are combined from
    integrate : Euler or Heun; the implicit forces are those at the end of the step, all
                stiff laws together (backward Euler, ``implicit.py``); the step is dt_max far
                from contact, shrinks with the gap and as the interactions ask (bond kinetics),
                lands on the next frame time or the end, and is retried at half the size when it
                would make bodies touch
    state     : interactions that own state advance it over the accepted step (bond kinetics)

Everything solved at a state is an ``Evaluation``; the end state's evaluation gives its frame
and is also the first stage of the next step, so writing a frame costs no extra solve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .. import runtime
from ..forces.interaction import ImplicitCoordinates, Loads
from ..surfaces.gaps import Contacts, GapFinder
from ..surfaces.placement import PlacementError, check_placement
from . import integrate
from .frame import ACCURACY_COLUMNS, Frame
from .hydrodynamics import Hydrodynamics, HydrodynamicSolves
from .implicit import DenseResponse, ImplicitSolveError, ImplicitSystem, MobilityResponse
from .model import Model, build_solver
from .state import State


@dataclass(frozen=True)
class Implicit:
    """The implicit interactions at a state: their coordinates (concatenated; ``owners``: which
    interaction each slice belongs to), the forces at the state and the backward-Euler system."""

    coordinates: ImplicitCoordinates
    owners: list  # [(interaction, slice)]
    system: ImplicitSystem
    at_state: np.ndarray  # N: the laws at the state's own coordinates
    at_state_coefficients: np.ndarray  # N: the same forces in the basis of the solves


@dataclass(frozen=True)
class Evaluation:
    """What is known at one state: bodies, contacts, loads and the solves."""

    model: Model
    state: State
    contacts: Contacts
    planned_dt: float  # s: the step the policy allows from here (an upper bound for retries)
    explicit: dict  # {interaction name: Loads}
    hydro: Hydrodynamics
    implicit: Implicit | None
    _steps: dict = field(default_factory=dict, repr=False, compare=False)  # dt -> implicit_step(dt)

    def implicit_step(self, dt: float):
        """(coefficients z, forces f(s')) of the backward-Euler step of dt from here, solved once
        per dt (the motion and the step's loads both need them)."""
        if dt not in self._steps:
            at_state = self.implicit.at_state_coefficients
            self._steps[dt] = self.implicit.system.solve(dt, [at_state * 2.0**k for k in range(48)])
        return self._steps[dt]

    def motion(self, dt: float):
        """(U, Omega) over a step of dt from here: the implicit forces of the step's end."""
        b = self.hydro.background
        if self.implicit is None:
            return b.velocity, b.angular_velocity
        z, _ = self.implicit_step(dt)
        velocity, angular_velocity, _, _ = self.hydro.basis.combine(z)
        return b.velocity + velocity, b.angular_velocity + angular_velocity

    def step_loads(self, dt: float) -> tuple[Loads, list]:
        """The loads on the bodies over a step of dt from here (as the frame's, with the implicit
        forces of the step's end, which move the bodies, in place of those at the state, which
        may be far larger where a contact has closed in), and their part at points of the
        surfaces (``ImplicitCoordinates.point_loads``): what deforms the cells over the step."""
        b = self.hydro.background
        if self.implicit is None:
            return Loads(b.force, b.torque), []
        x = self.implicit
        z, magnitudes = self.implicit_step(dt)
        extra = self.hydro.basis.combine(z)
        received = x.coordinates.loads(magnitudes, self.model.fixed_mask)
        loads = Loads(b.force + extra[2] - received.force, b.torque + extra[3] - received.torque)
        return loads, x.coordinates.point_loads(magnitudes)

    def frame(self, dt: float) -> Frame:
        """The record of this state; ``dt`` (s): the step that led here."""
        b = self.hydro.background
        velocity, angular_velocity, force, torque = b.velocity, b.angular_velocity, b.force, b.torque
        zero = Loads.zero(self.model.n_bodies)
        loads = {x.name: self.explicit.get(x.name, zero) for x in self.model.interactions}
        iterations, residual = b.iterations, b.residual
        if self.implicit is not None:
            x = self.implicit
            extra = self.hydro.basis.combine(x.at_state_coefficients)
            # a held body is also held against the implicit forces it receives itself
            received = x.coordinates.loads(x.at_state, self.model.fixed_mask)
            velocity, angular_velocity = velocity + extra[0], angular_velocity + extra[1]
            force, torque = force + extra[2] - received.force, torque + extra[3] - received.torque
            for interaction, where in x.owners:
                loads[interaction.name] = x.coordinates.part(where).loads(x.at_state[where])
        if self.hydro.basis is not None:
            iterations += self.hydro.basis.iterations
            residual = max(residual, self.hydro.basis.residual)
        s = self.state
        derived = {}
        for interaction in self.model.bound_interactions:
            if interaction.name in s.parts:
                derived.update(interaction.derived_values(s.parts[interaction.name]))
        chosen = self.hydro.chosen
        if chosen is not None:
            derived.update({name: getattr(chosen, name.removeprefix("accuracy_")) or 0 for name in ACCURACY_COLUMNS})
        # the two kinds of gap from the state's kept gaps (min of them: closest_gap, bit for bit)
        body_gap, wall_gap = self.contacts.closest("bodies"), self.contacts.closest("wall")
        return Frame(s.time, dt, s.steps, s.positions, s.orientations, velocity, angular_velocity, force, torque,
                     iterations, residual, min(body_gap, wall_gap), body_gap, wall_gap, loads, s.parts, derived)


class Simulator:
    """Steps a ``Model`` on a Warp device. ``step(state)`` returns the next state and its frame.

    The simulator keeps the model's interactions bound on its device (``Interaction.bound``:
    what they derive from the model, with their kernels and device arrays), the mobility solver
    (its kept blocks of fixed bodies and warm start) and the evaluation of the state it returned
    last, which the next step starts from: a cache of a pure function of that state, never a way
    to pass results.

    Examples
    --------
    A free cell 12 um upstream of an adherent one, both 5 um in radius:

    >>> import warpbem as wb
    >>> sphere = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> pair = wb.Model([sphere, sphere], [False, True], wb.Flow(shear_rate=100.0), names=["free", "adherent"])
    >>> sim = wb.Simulator(pair, device="cpu")
    >>> state, frame = sim.step(pair.initial_state([[-12e-6, 0.0, 6e-6], [0.0, 0.0, 5.25e-6]]))
    >>> state.steps, state.time      # one step: the next state and its frame
    (1, 0.0001)
    >>> round(frame.wall_gap * 1e6, 2), round(frame.closest_body_gap * 1e6, 2)   # um
    (1.0, 2.0)

    ``warpbem.run`` runs a whole scene with progress lines, HDF5 frames and resume.
    """

    def __init__(self, model: Model, device="cpu"):
        self.model = model
        fixed_cells = int(model.fixed_mask.sum())
        self.mobility = build_solver(model.solver, model.flow, device, fixed_cells, model.unknowns)
        self.near_far_split = model.solver.near_far_report(fixed_cells)  # on or off, and why
        self.hydro = HydrodynamicSolves(model, self.mobility)
        self.gaps = GapFinder(device)
        # the interactions bound to the model with their device data on this device
        self.interactions = tuple(x.bound(model, device) for x in model.interactions)
        self.implicit = tuple(x for x in self.interactions if x.implicit)
        self._latest: Evaluation | None = None

    def evaluate(self, state: State, dt_plan: float | None = None, geometry=None) -> Evaluation:
        """Geometry, contacts, loads and mobility at ``state``; ``dt_plan``: the step about to be
        taken from it (default: what the policy and the interactions allow there);
        ``geometry``: its (bodies, contacts) when the caller has them already."""
        if self._latest is not None and self._latest.state is state and dt_plan is None:
            return self._latest
        model = self.model
        bodies, contacts = self.geometry(state) if geometry is None else geometry
        if dt_plan is None:
            dt_plan = model.policy.dt(contacts.smallest(model.policy.contact_gap))
            limits = [x.longest_step(bodies, contacts, state.parts.get(x.name)) for x in self.interactions]
            dt_plan = max(model.policy.dt_min, min([dt_plan] + limits))
        explicit = {x.name: loads for x in self.interactions
                    if (loads := x.explicit_loads(bodies, contacts)) is not None}
        total = sum(explicit.values(), Loads.zero(model.n_bodies))
        stiff = (any(x.reuses_mobility(state.parts[x.name]) for x in self.interactions if x.name in state.parts)
                 and all(x.keeps_shape(state.parts[x.name], self.hydro.tolerance) for x in self.interactions
                         if x.shapes_bodies and x.name in state.parts))
        background, snapshot = self.hydro.background(bodies, total, stiff)
        hydro, implicit = self._implicit(state, bodies, contacts, background, snapshot, dt_plan)
        self._latest = Evaluation(model, state, contacts, dt_plan, explicit, hydro, implicit)
        return self._latest

    def geometry(self, state: State):
        """The bodies of a state, placement checked, and its Contacts (gaps, once per state)."""
        bodies = self.model.bodies(state)
        check_placement(bodies, self.model.flow.wall)
        shapes = self.model.bodies(state, contact=True) if self.model.shapes_bodies else None
        return bodies, Contacts(bodies, self.model.outer_radii, self.model.flow.wall, self.gaps, shapes)

    def _implicit(self, state, bodies, contacts, background, snapshot, dt_plan):
        """The implicit interactions' coordinates at this state, joined, with the solves of the
        basis their forces are combined from and the backward-Euler system of a step."""
        found = []
        for x in self.implicit:
            c = x.implicit_coordinates(bodies, contacts, state.parts.get(x.name), background.velocity,
                                       background.angular_velocity, dt_plan)
            if c is not None and len(c.values):
                found.append((x, c))
        if not found:
            return Hydrodynamics(background, None, "none", self.hydro.mobility.last_chosen), None
        owners, start = [], 0
        for x, c in found:
            owners.append((x, slice(start, start + len(c.values))))
            start += len(c.values)
        coordinates = ImplicitCoordinates.join([c for _, c in found])
        basis, kind = self.hydro.basis(bodies, coordinates, snapshot)
        quadratic = basis.quadratic()
        # rates consistent with the symmetrised dissipation (reciprocity; hydrodynamics.py)
        if kind == "coordinates":
            rate_response = DenseResponse(quadratic)
        elif self.hydro.pairwise is not None:  # many cells: R never formed, H neither (implicit.py)
            rate_response = MobilityResponse.of(coordinates, quadratic, basis.load_force, basis.load_torque)
        else:
            rate_response = DenseResponse(np.array([coordinates.rates(u, w) for u, w in
                                                    zip(basis.velocity, basis.angular_velocity)]).T)
        rates = coordinates.rates(background.velocity, background.angular_velocity)
        system = ImplicitSystem(coordinates.values, rates, rate_response, quadratic,
                                [(where, x.law) for x, where in owners])
        at_state = system.evaluate(coordinates.values)[1]
        if kind == "coordinates":
            coefficients = at_state
        else:
            loads = coordinates.loads(at_state, ~self.model.fixed_mask)
            coefficients = self.hydro.body_coefficients(loads.force, loads.torque)
        return (Hydrodynamics(background, basis, kind, self.hydro.mobility.last_chosen),
                Implicit(coordinates, owners, system, at_state, coefficients))

    def frame(self, state: State) -> Frame:
        """The frame of a state no step led to (the first of a run)."""
        return self.evaluate(state).frame(0.0)

    def step(self, state: State, t_stop: float = math.inf) -> tuple[State, Frame]:
        """One step from ``state``, never past ``t_stop`` (s; landing on it exactly)."""
        if not t_stop > state.time:
            raise ValueError(f"t_stop = {t_stop!r} s is not after the state's time {state.time!r} s")
        start = self.evaluate(state)  # geometry, contacts, loads, mobility (kept from the last step)
        dt = self.model.policy.landing(start.planned_dt, t_stop - state.time)
        while True:
            try:
                end = self._integrate(start, dt, t_stop if dt == t_stop - state.time else None)
                runtime.release_freed_memory()  # what this step freed, back to the system (runtime.py)
                return end.state, end.frame(dt)
            except (PlacementError, ImplicitSolveError) as err:
                if dt <= self.model.policy.dt_min * (1 + 1e-12):
                    raise PlacementError(f"at t = {state.time:.6g} s even the smallest step dt_min ="
                                         f" {self.model.policy.dt_min:g} s makes bodies touch: {err}") from err
                dt = max(0.5 * dt, self.model.policy.dt_min)

    def _integrate(self, start: Evaluation, dt: float, landing: float | None) -> Evaluation:
        """Move from ``start`` over dt (Heun's second stage evaluated at its predictor) and
        evaluate the end; PlacementError if the predictor or the end is not a valid placement."""
        state = start.state

        def motion(s):
            return start.motion(dt) if s is state else self.evaluate(s, dt).motion(dt)

        moved, _ = integrate.step(state, motion, dt, self.model.scheme)
        moved = replace(moved, time=moved.time if landing is None else landing, steps=state.steps + 1)
        owners = [x for x in self.interactions if x.name in state.parts]
        shapers = [x for x in owners if x.shapes_bodies]
        if shapers:  # shapes first (the end's bodies are built with them), from the start state
            loads, contact_loads = start.step_loads(dt)
            moved = replace(moved, parts={**state.parts, **{
                x.name: x.advance_shape(state.parts[x.name], start.contacts.bodies, loads, moved.orientations, dt,
                                        contact_loads)
                for x in shapers}})
        geometry = self.geometry(moved)
        if owners:  # interactions that own state advance it over the accepted motion
            parts = {x.name: x.advance_state(moved.parts[x.name], start.contacts.bodies, *geometry, dt, moved.time)
                     for x in owners}
            moved = replace(moved, parts=parts)
        return self.evaluate(moved, geometry=geometry)

    def run(self, state: State, t_end: float, callback=None) -> State:
        """Step until t_end (landing on it); ``callback(state, frame)`` after each step."""
        while state.time < t_end:
            state, frame = self.step(state, t_end)
            if callback is not None:
                callback(state, frame)
        return state
