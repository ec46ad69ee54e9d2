"""Time stepping of a ``Model`` (DESIGN.md §3): the one place that fixes the order of a step.

    geometry  : the bodies of the state, placement checked
    contacts  : exact gaps, once per state, shared (surfaces.gaps.Contacts)
    loads     : explicit interactions (gravity, given loads) -> mobility solve -> the implicit
                interaction's coordinates (repulsion: contacts within reach) and the motion of
                a unit force along each (one more solve each, same system, no background flow)
    integrate : Euler or Heun; the implicit forces are those at the end of the step (backward
                Euler, ``forces/interaction.py``); the step is dt_max far from contact and
                shrinks with the gap, lands on the next frame time or the end, and is retried
                at half the size when it would make bodies touch

Everything solved at a state is an ``Evaluation``; the end state's evaluation gives its frame
and is also the first stage of the next step, so writing a frame costs no extra solve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..forces.interaction import ImplicitCoordinates, Loads
from ..hydro.mobility import MobilitySolution
from ..surfaces.gaps import Contacts, GapFinder
from ..surfaces.placement import PlacementError, check_placement
from . import integrate
from .frame import Frame
from .model import Model
from .state import State

PROBE_FORCE = 1e-12  # N: the unit load of an implicit coordinate's solve (the response is linear)


@dataclass(frozen=True)
class Implicit:
    """The implicit interaction at a state: its coordinates, the solves of a probe force along
    each, the coordinates' rates without it (m/s) and their response to 1 N along each (m/(N s))."""

    coordinates: ImplicitCoordinates
    responses: list  # MobilitySolution per coordinate, for PROBE_FORCE along it
    rates: np.ndarray
    response: np.ndarray


@dataclass(frozen=True)
class Evaluation:
    """What is known at one state: bodies, contacts, loads and the solves."""

    model: Model
    state: State
    contacts: Contacts
    planned_dt: float  # s: the step the policy allows from here (an upper bound for retries)
    explicit: dict  # {interaction name: Loads}
    background: MobilitySolution  # flow and explicit loads
    implicit: Implicit | None

    def motion(self, dt: float):
        """(U, Omega) over a step of dt from here: the implicit forces of the step's end."""
        if self.implicit is None:
            return self.background.velocity, self.background.angular_velocity
        x = self.implicit
        magnitudes = self.model.implicit.implicit_magnitudes(x.coordinates, x.rates, x.response, dt)
        return self._with(magnitudes)[:2]

    def _with(self, magnitudes):
        """Velocities and loads with the implicit forces ``magnitudes`` (N) added (linearity)."""
        b = self.background
        velocity, angular_velocity = b.velocity.copy(), b.angular_velocity.copy()
        force, torque = b.force.copy(), b.torque.copy()
        for f, r in zip(magnitudes, self.implicit.responses):
            scale = f / PROBE_FORCE
            velocity += scale * r.velocity
            angular_velocity += scale * r.angular_velocity
            force += scale * r.force
            torque += scale * r.torque
        # a held body is also held against the implicit force it receives itself
        received = self.implicit.coordinates.loads(magnitudes, self.model.fixed_mask)
        return velocity, angular_velocity, force - received.force, torque - received.torque

    def frame(self, dt: float) -> Frame:
        """The record of this state; ``dt`` (s): the step that led here."""
        b = self.background
        velocity, angular_velocity, force, torque = b.velocity, b.angular_velocity, b.force, b.torque
        zero = Loads.zero(self.model.n_bodies)
        loads = {x.name: self.explicit.get(x.name, zero) for x in self.model.interactions}
        iterations, residual = b.iterations, b.residual
        implicit = self.model.implicit
        if self.implicit is not None:
            at_state = implicit.magnitudes_at(self.implicit.coordinates)
            velocity, angular_velocity, force, torque = self._with(at_state)
            loads[implicit.name] = self.implicit.coordinates.loads(at_state)
            iterations += sum(r.iterations for r in self.implicit.responses)
            residual = max([residual] + [r.residual for r in self.implicit.responses])
        s = self.state
        return Frame(s.time, dt, s.steps, s.positions, s.orientations, velocity, angular_velocity, force, torque,
                     iterations, residual, self.contacts.closest(), loads, s.parts)


class Simulator:
    """Steps a ``Model`` on a Warp device. ``step(state)`` returns the next state and its frame.

    The simulator keeps the mobility solver (its kept blocks of fixed bodies and warm start) and
    the evaluation of the state it returned last, which the next step starts from: a cache of
    a pure function of that state, never a way to pass results.
    """

    def __init__(self, model: Model, device="cpu"):
        self.model = model
        self.solver = model.solver.build(model.flow, device)
        self.gaps = GapFinder(device)
        self._latest: Evaluation | None = None

    def evaluate(self, state: State, dt_plan: float | None = None) -> Evaluation:
        """Geometry, contacts, loads and mobility at ``state``; ``dt_plan``: the step about to be
        taken from it (default: what the policy allows at its gaps)."""
        if self._latest is not None and self._latest.state is state and dt_plan is None:
            return self._latest
        model = self.model
        bodies = model.bodies(state)  # geometry
        check_placement(bodies, model.flow.wall)
        contacts = Contacts(bodies, model.outer_radii, model.flow.wall, self.gaps)  # gaps, once per state
        if dt_plan is None:
            dt_plan = model.policy.dt(contacts.smallest(model.policy.contact_gap))
        explicit = {x.name: loads for x in model.interactions
                    if (loads := x.explicit_loads(bodies, contacts)) is not None}
        total = sum(explicit.values(), Loads.zero(model.n_bodies))
        background = self.solver.solve(bodies, forces=total.force, torques=total.torque, check_placement_first=False)
        implicit = self._implicit(bodies, contacts, background, dt_plan)
        self._latest = Evaluation(model, state, contacts, dt_plan, explicit, background, implicit)
        return self._latest

    def _implicit(self, bodies, contacts, background, dt_plan) -> Implicit | None:
        """The implicit interaction's coordinates at this state and the solves of a probe force
        along each (the same system as ``background``, no background flow)."""
        model = self.model
        coordinates = None if model.implicit is None else model.implicit.implicit_coordinates(
            bodies, contacts, background.velocity, background.angular_velocity, dt_plan)
        if coordinates is None:
            return None
        free = ~model.fixed_mask[:, None]
        responses = [self.solver.solve(bodies, forces=PROBE_FORCE * f * free, torques=PROBE_FORCE * t * free,
                                       check_placement_first=False, background=False)
                     for f, t in zip(coordinates.unit_force, coordinates.unit_torque)]
        matrix = np.array([coordinates.rates(r.velocity, r.angular_velocity) for r in responses]).T / PROBE_FORCE
        rates = coordinates.rates(background.velocity, background.angular_velocity)
        # symmetric by reciprocity: averaging removes the GMRES noise
        return Implicit(coordinates, responses, rates, 0.5 * (matrix + matrix.T))

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
                return end.state, end.frame(dt)
            except PlacementError as err:
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
        parts = {}
        if state.parts:  # interactions that own state advance it over the accepted motion
            end_bodies = self.model.bodies(moved)
            parts = {x.name: x.advance_state(state.parts[x.name], start.contacts.bodies, end_bodies, dt)
                     for x in self.model.interactions if x.name in state.parts}
        moved = replace(moved, time=moved.time if landing is None else landing, steps=state.steps + 1, parts=parts)
        return self.evaluate(moved)

    def run(self, state: State, t_end: float, callback=None) -> State:
        """Step until t_end (landing on it); ``callback(state, frame)`` after each step."""
        while state.time < t_end:
            state, frame = self.step(state, t_end)
            if callback is not None:
                callback(state, frame)
        return state
