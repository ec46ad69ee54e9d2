"""The mobility problem of many rigid bodies in linear shear flow above a no-slip wall (SI at the
API): ``MobilitySolver`` for a scene solved again and again, ``solve_mobility`` for one solve.
Each solve builds the Completed Double Layer system of the bodies of the moment
(``completed_double_layer.py``, thesis eq. 2.5-2.17), with the operator's discrete form decided
once (``operators/``), and solves it by deflated, preconditioned GMRES (``deflated.py``).

Scaled units inside: lengths over L = the mean equivalent radius, velocities over a scale U0
from the data (shear, loads, prescribed motions), forces over mu U0 L.
"""

from __future__ import annotations

import copy
import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from .. import runtime
from ..surfaces.body import Body
from ..surfaces.placement import body_label, check_placement
from ..surfaces.gaps import WALL
from . import accuracy
from .block_factors import BlockFactors
from .completed_double_layer import FORCE_UNIT, TORQUE_UNIT, CompletedDoubleLayer, all_completion_poles
from .deflated import deflated_solve
from .geometry import SurfaceGeometry
from .operators import BoundaryOperator, KeptBlocks, QuadratureOptions, choose_mode, discrete_form
from .options import Flow, SolverOptions


class ContactResolutionWarning(UserWarning):
    """Two surfaces closer than the contact refinement resolves: accuracy degrades there."""


@dataclass(frozen=True)
class MobilitySolution:
    """Rigid motion and loads of every body, SI units (rows in the order of the bodies).

    velocity (m/s) and angular_velocity (rad/s) of each body's reference point; prescribed for
    fixed bodies. force (N) and torque (N m, about the reference point): for free bodies the
    given external ones; for fixed bodies the external load that holds them, which is minus the
    hydrodynamic force and torque.

    Examples
    --------
    >>> import warpbem as wb
    >>> cell = wb.Body(wb.mesh.sphere(radius=5e-6, subdivisions=2), position=(0.0, 0.0, 10e-6))
    >>> sol = wb.solve_mobility([cell], shear_rate=100.0)
    >>> sol.velocity.shape, sol.angular_velocity.shape, sol.converged, sol.residual < 1e-8
    ((1, 3), (1, 3), True, True)
    >>> print(f"U = {sol.velocity[0, 0] * 1e6:.0f} um/s")   # the wall holds it below the flow's 1000 um/s
    U = 964 um/s
    """

    velocity: np.ndarray
    angular_velocity: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    iterations: int
    residual: float
    converged: bool
    operator_mode: str
    solution_vector: np.ndarray  # scaled GMRES unknowns, for a warm start of a similar solve
    reused_bodies: np.ndarray  # per body: operator blocks kept from the previous solve
    chosen: accuracy.ChosenSettings | None = None  # with an accuracy target: its settings and estimate

    @property
    def error_estimate(self) -> float | None:
        """The accuracy target's estimate of the largest relative error (None without a target)."""
        return None if self.chosen is None else self.chosen.error_estimate


def checked_bodies(bodies) -> list:
    """``bodies`` as a list, at least one, every item a ``Body``."""
    bodies = list(bodies)
    if not bodies:
        raise ValueError("bodies must contain at least one Body")
    for i, b in enumerate(bodies):
        if not isinstance(b, Body):
            raise TypeError(f"bodies[{i}] must be a warpbem.Body, got {type(b).__name__}")
    return bodies


def checked_loads(name, value, bodies, fixed_allowed: bool = False):
    """(n, 3) loads, one row per body, checked; a fixed body's row must be zero unless
    ``fixed_allowed`` (its load is then an input, e.g. the traction problem's)."""
    n = len(bodies)
    if value is None:
        return np.zeros((n, 3))
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n, 3):
        raise ValueError(f"{name} must have shape ({n}, 3), one row per body; got {arr.shape}")
    for i in range(n):
        if not np.all(np.isfinite(arr[i])):
            raise ValueError(f"{name}[{i}] (body {i}) is not finite: {arr[i].tolist()}")
        if bodies[i].fixed and np.any(arr[i]) and not fixed_allowed:
            raise ValueError(
                f"{name}[{i}]: body {i} is fixed, so its {name[:-1]} is an output of the solver;"
                " give external loads for free bodies only"
            )
    return arr


class MobilitySolver:
    """The mobility problem for a scene solved again and again (time stepping, parameter
    sweeps): the flow and the ``options`` (``SolverOptions``, context defaults resolved as for
    a solve) are fixed here; ``solve`` takes the bodies of the moment.

    With ``keep_systems`` it keeps, between calls, the operator blocks (in a ``KeptBlocks``
    store) and the fixed-body completion columns of bodies whose elements did not change (fixed
    adherent cells), and starts GMRES from the previous solution.

    The operator's discrete form (``mode``) is decided once by ``choose_mode``: when the solver is
    built if ``unknowns`` (3 per collocation point of the scenes it will solve) is given, else at
    its first solve, from that solve's unknowns; every later solve keeps it, whatever the memory
    does; ``operator_description`` reports it.

    With ``options.accuracy`` each solve first chooses its settings (``accuracy.py``) and hands
    the bodies, rebuilt on the chosen library meshes, to a solver of those settings, one kept
    per setting; its solutions carry ``chosen``.

    Examples
    --------
    In unbounded simple shear a torque-free sphere moves with the fluid at its centre and
    spins at half the vorticity (shear_rate / 2 about y); one solver for several positions:

    >>> import warpbem as wb
    >>> solver = wb.MobilitySolver(shear_rate=100.0, viscosity=1e-3, wall=False)
    >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> for height in (10e-6, 20e-6):
    ...     sol = solver.solve([wb.Body(cell, position=(0.0, 0.0, height))])
    ...     print(f"{sol.velocity[0, 0] / (100.0 * height):.4f} {sol.angular_velocity[0, 1] / 50.0:.4f}")
    1.0000 1.0000
    1.0000 1.0000
    >>> solver.operator_description
    'dense'
    """

    def __init__(self, shear_rate: float = 0.0, viscosity: float = Flow.viscosity, wall: bool = True, device="cpu",
                 options: SolverOptions | None = None, *, keep_systems: bool = True, unknowns: int | None = None):
        self.flow = Flow(shear_rate, viscosity, wall)
        self.device = device
        runtime.resolve_device(device)  # a device this machine lacks: DeviceError before any work
        self.options = (options or SolverOptions()).resolved()
        self.quadrature = QuadratureOptions(order=self.options.element_quadrature,
                                            adaptive=self.options.adaptive_quadrature,
                                            near_factor=self.options.near_factor)
        self.keep_systems = bool(keep_systems)
        self._mode = None if self.options.operator == "auto" else self.options.operator
        if self._mode is None and unknowns is not None:
            self._mode = choose_mode(int(unknowns), self.options.dtype, self.device)
        self._kept = KeptBlocks() if self.keep_systems else None
        self._factors = BlockFactors() if self.keep_systems else None
        self._last = None  # (CompletedDoubleLayer, solution vector, speed, bodies key) of the previous solve
        self._warned = set()  # contacts already reported by this solver
        self._targeted = {}  # accuracy target: (k, p, ratio) -> the solver of that setting
        self._active = self  # the solver of the last solve (another one's under an accuracy target)
        self.last_chosen = None  # accuracy target: the ChosenSettings of the last solve

    @property
    def mode(self) -> str | None:
        """The operator's discrete form ("dense", "matrix_free", "treecode"), None while "auto"
        waits for the first solve (of the last solve's setting under an accuracy target)."""
        return self._active._mode

    @property
    def operator_description(self) -> str:
        """The operator's mode as decided ("auto (not yet decided)" before the first solve)."""
        return self._active._mode or "auto (not yet decided)"

    def _setting_for(self, bodies, unloaded: bool = False):
        """Under an accuracy target: (the solver of the setting chosen for ``bodies``, the bodies on
        its meshes, the ChosenSettings). ``unloaded``: a solve of the shear flow's motion alone
        (``accuracy.wall_model``)."""
        options = self.options
        chosen = accuracy.choose_for(bodies, self.flow.wall, options.accuracy, options.density_order,
                                     options.refine_fixed_at_wall, unloaded)
        key = (chosen.subdivisions, chosen.density_order, chosen.contact_refinement)
        if key not in self._targeted:
            settings = dataclasses.replace(options, accuracy=None, density_order=chosen.density_order,
                                           contact_refinement=chosen.contact_refinement)
            self._targeted[key] = MobilitySolver(*dataclasses.astuple(self.flow), self.device, settings,
                                                 keep_systems=self.keep_systems)
        self._active, self.last_chosen = self._targeted[key], chosen
        return self._active, accuracy.rebuilt(bodies, chosen), chosen

    def solve(self, bodies, forces=None, torques=None, initial_guess=None,
              check_placement_first: bool = True, background: bool = True, ambient_flow=None,
              factor_every_body: bool = False) -> MobilitySolution:
        """Solve for the bodies of the moment. ``check_placement_first=False`` skips the overlap
        and wall checks, for callers that have just checked these very bodies (time stepping).

        ``background=False`` gives the response to the loads alone (no shear flow, fixed bodies
        at rest), e.g. the mobility of a contact for an implicit contact force; such a solve
        reuses the whole system of a preceding solve of the same bodies and leaves the warm
        start of the next ordinary solve alone.

        ``ambient_flow``: the undisturbed flow in place of the shear flow, a function of the
        collocation points (m, (n, 3)) and the index of each point's body (n,) giving the
        velocity there (m/s, (n, 3)); the flow of frozen adherent cells that are not among the
        bodies (``frozen.py``). Ignored with ``background=False``.

        ``factor_every_body``: the block-Jacobi preconditioner factors every body's block, however
        large (``CompletedDoubleLayer.preconditioner``), for bodies about to be solved for many
        loads."""
        bodies = checked_bodies(bodies)
        forces = checked_loads("forces", forces, bodies)
        torques = checked_loads("torques", torques, bodies)
        if check_placement_first:
            check_placement(bodies, self.flow.wall)
        if self.options.accuracy is not None:
            unloaded = background and ambient_flow is None and not np.any(forces) and not np.any(torques)
            solver, bodies, chosen = self._setting_for(bodies, unloaded)
            return dataclasses.replace(solver.solve(bodies, forces, torques, initial_guess, False, background,
                                                    ambient_flow, factor_every_body), chosen=chosen)
        system, key, previous, length = self._system(bodies)
        rhs, speed, force_scale = self._right_side(system, bodies, forces, torques, length, background, ambient_flow)
        if initial_guess is not None and np.shape(initial_guess) != (system.size,):
            raise ValueError(f"initial_guess must have shape ({system.size},) for this scene, got"
                             f" {np.shape(initial_guess)} (the mesh or the bodies changed)")
        if initial_guess is None and previous is not None and background:
            initial_guess = self._warm_start(system, previous, speed)
        result = deflated_solve(system.linear_operator(), rhs, self.options, initial_guess=initial_guess,
                                **self._preconditioning(system, previous, factor_every_body))
        x = result.solution
        if background or self._last is None or system is not self._last[0]:
            self._last = (system, x, speed, key)
        return self._solution(bodies, system, result, forces, torques, speed, length, force_scale)

    def solve_loads(self, bodies, forces, torques, factor_every_body: bool = False,
                    with_background: bool = False) -> list[MobilitySolution]:
        """The motion under each load (k, n, 3) of ``forces`` and ``torques`` alone, as ``solve``
        with ``background=False`` gives it for each, all solved at once (``deflated.py``: one
        GMRES per load whose products take the k columns together, so the dense matrix is read
        once per iteration for all of them): the responses to a basis of loads (the grand
        mobility, dynamics/hydrodynamics.py). ``with_background``: the first solution is the
        background's (the flow, no load; ``solve(bodies)``), solved with them and started from the
        previous solve's solution as ``solve`` starts. The bodies' placement is not checked."""
        bodies = checked_bodies(bodies)
        if self.options.accuracy is not None:
            solver, bodies, chosen = self._setting_for(bodies)
            return [dataclasses.replace(solution, chosen=chosen)
                    for solution in solver.solve_loads(bodies, forces, torques, factor_every_body, with_background)]
        loads = [(checked_loads("forces", f, bodies), checked_loads("torques", t, bodies))
                 for f, t in zip(forces, torques)]
        if with_background:
            loads.insert(0, (np.zeros((len(bodies), 3)), np.zeros((len(bodies), 3))))
        if not loads:
            return []
        system, key, previous, length = self._system(bodies)
        parts = [self._right_side(system, bodies, f, t, length, with_background and c == 0, None)
                 for c, (f, t) in enumerate(loads)]
        guesses = np.zeros((system.size, len(loads)))
        if with_background and previous is not None:
            guesses[:, 0] = self._warm_start(system, previous, parts[0][1])
        results = deflated_solve(system.linear_operator(), np.column_stack([rhs for rhs, _, _ in parts]),
                                 self.options, initial_guess=guesses,
                                 **self._preconditioning(system, previous, factor_every_body))
        if with_background:
            self._last = (system, results[0].solution, parts[0][1], key)
        elif self._last is None or system is not self._last[0]:
            self._last = (system, results[-1].solution, parts[-1][1], key)
        return [self._solution(bodies, system, result, f, t, speed, length, force_scale)
                for result, (f, t), (_, speed, force_scale) in zip(results, loads, parts)]

    def _warm_start(self, system, previous, speed: float) -> np.ndarray:
        """The background's GMRES start from the previous solve's solution, which is in the previous
        scaling: its loads part is rescaled by the two speed scales."""
        return system.initial_guess(previous, self._last[1] * (self._last[2] / speed))

    def _system(self, bodies):
        """(the CompletedDoubleLayer system of ``bodies``, their key, the previous system or None,
        the length scale L (m)): the previous one itself when the bodies are the very same."""
        length = float(np.mean([b.mesh.equivalent_radius() for b in bodies]))
        fixed = np.array([b.fixed for b in bodies])
        options = self.options
        previous = self._last[0] if self.keep_systems and self._last else None
        # the meshes themselves, not their ids: the key keeps them alive, so a new mesh can never
        # come back at a garbage-collected one's address and be taken for it
        key = [(b.mesh, b.position.tobytes(), b.orientation.tobytes(), b.fixed) for b in bodies]
        if previous is not None and key == self._last[3]:  # the very same bodies: keep the system
            return previous, key, previous, length
        geometry = SurfaceGeometry.from_bodies(bodies, options.quadrature_order, length, self.flow.wall,
                                               options.contact_refinement, options.refine_fixed_at_wall,
                                               options.density_order)
        self._warn_unresolved(geometry, length, bodies)
        description = BoundaryOperator(geometry, self.flow.wall, self.quadrature, "double_layer", options.dtype)
        if self._mode is None:  # "auto" of a solver built without its unknowns: decided once, here
            self._mode = choose_mode(description.size, options.dtype, self.device)
        double_layer = discrete_form(description, self._mode, self.device, kept=self._kept, treecode=options.treecode,
                                     point_sources=all_completion_poles(geometry))
        return CompletedDoubleLayer(geometry, double_layer, fixed, previous), key, previous, length

    def _right_side(self, system, bodies, forces, torques, length: float, background: bool, ambient_flow):
        """(the scaled right-hand side, the velocity scale U0 (m/s), the force scale (N)) of one
        solve of ``system`` (``solve``'s arguments)."""
        fixed = system.fixed
        prescribed = np.array([np.concatenate([b.velocity, b.angular_velocity * length]) for b in bodies])
        slip = [b.surface_velocity for b in bodies] if background else [None] * len(bodies)
        options, flow = self.options, self.flow
        if options.density_order != 1 and any(v is not None for v in slip):
            raise ValueError("a surface_velocity is given per element, for the constant density: solve it with"
                             " density_order=1 (the deformation model's traction is constant per element too)")
        speed = max(abs(flow.shear_rate) * length, np.abs(forces).max() / (flow.viscosity * length),
                    np.abs(torques).max() / (flow.viscosity * length**2), np.abs(prescribed).max(),
                    max((np.abs(v).max() for v in slip if v is not None), default=0.0))
        speed = speed if speed > 0 else 1.0
        force_scale = flow.viscosity * speed * length  # N per scaled force unit
        if not background:
            prescribed[:] = 0.0
        geometry = system.geometry
        xi = geometry.collocation
        ambient = np.zeros_like(xi)
        if background and ambient_flow is not None:
            ambient = ambient_flow(xi * length, geometry.body_of_point) / speed
        elif background:
            ambient[:, 0] = flow.shear_rate * length / speed * xi[:, 2]
        free_loads = {p: np.concatenate([forces[p] / force_scale, torques[p] / (force_scale * length)])
                      for p in np.flatnonzero(~fixed)}
        rhs = system.right_side(ambient, {p: loads for p, loads in free_loads.items() if np.any(loads)},
                                prescribed, slip, speed)
        return rhs, speed, force_scale

    def _preconditioning(self, system, previous, factor_every_body: bool) -> dict:
        """``deflated_solve``'s preconditioner arguments for ``system`` (block Jacobi)."""
        if not self.options.precondition:
            return dict(preconditioner=None, exact_preconditioner=False)
        return dict(preconditioner=system.preconditioner(previous, self.keep_systems, factor_every_body, self._factors),
                    exact_preconditioner=system.preconditioner_is_exact())

    def _solution(self, bodies, system, result, forces, torques, speed, length, force_scale) -> MobilitySolution:
        """The MobilitySolution of one GMRES ``result`` of ``system``."""
        return MobilitySolution(*self._motion_and_loads(bodies, system, result.solution, forces, torques, speed,
                                                        length, force_scale),
                                result.iterations, result.residual, result.converged, system.double_layer.mode,
                                result.solution, system.double_layer.reused_bodies)

    @staticmethod
    def _motion_and_loads(bodies, system, x, forces, torques, speed: float, length: float, force_scale: float):
        """(velocity, angular velocity, force, torque) of every body, SI, from the solution x in
        the scales ``speed`` (m/s), ``length`` (m) and ``force_scale`` (N): free bodies' rigid
        motion -P q and given loads, fixed ones' prescribed motion and the loads their
        densities' rigid parts carry."""
        velocity = np.zeros((len(bodies), 3))
        angular_velocity = np.zeros((len(bodies), 3))
        force, torque = forces.copy(), torques.copy()
        for p, body in enumerate(bodies):
            if body.fixed:
                loads = system.fixed_loads(p, x)
                force[p] = loads[:3] * FORCE_UNIT * force_scale
                torque[p] = loads[3:] * TORQUE_UNIT * force_scale * length
                velocity[p], angular_velocity[p] = body.velocity, body.angular_velocity
            else:
                motion = system.rigid_velocity(p, x)
                velocity[p] = motion[:3] * speed
                angular_velocity[p] = motion[3:] * speed / length
        return velocity, angular_velocity, force, torque

    def fresh(self) -> "MobilitySolver":
        """A solver with these settings and nothing of this one's solves, for other scenes (no
        kept system, no warnings given, "auto" operator decided again at its first solve)."""
        other = copy.copy(self)
        other._mode = None if self.options.operator == "auto" else self.options.operator
        other._kept = KeptBlocks() if self.keep_systems else None
        other._factors = BlockFactors() if self.keep_systems else None
        other._last, other._warned = None, set()
        other._targeted, other._active, other.last_chosen = {}, other, None
        return other

    @property
    def last_system(self):
        """(CompletedDoubleLayer, scaled solution, velocity scale in m/s) of the last ordinary
        solve (``keep_systems``), or None: the density a caller evaluates elsewhere (``frozen.py``)."""
        last = self._active._last
        return None if last is None else last[:3]

    def _warn_unresolved(self, geometry, length, bodies):
        """Warn once per contact (for the life of this solver) that is closer than the contact
        refinement resolves (see refinement.refine_near_contact and the docs/benchmarks.md, stability map)."""
        for (p, q), gap in sorted(geometry.unresolved_contacts.items()):
            if (p, q) in self._warned or (q, p) in self._warned:
                continue
            self._warned.add((p, q))
            what = "the wall" if q == WALL else f"body {body_label(bodies[q].name, q)}"
            warnings.warn(
                f"body {body_label(bodies[p].name, p)} and {what} are {gap * length:.3g} m apart ({gap:.3g} mean"
                " radii), closer than"
                f" the mesh resolves (contact_refinement={self.options.contact_refinement:g}): the gap to the wall, or"
                " the gap to another body (half of it with density_order 2), is under 2 % of the body's"
                " element radius, or under three"
                " element radii without refinement, or the refinement stopped at its deepest level."
                " Squeeze-flow forces lose accuracy first, past about 1 % (docs/benchmarks.md: stability map); a finer"
                " mesh helps."
                + (" In float32, GMRES stalls from about here: use dtype='float64'." if self.options.dtype == "float32" else ""),
                ContactResolutionWarning, stacklevel=4)  # _warn_unresolved, _system, solve, the caller


def solve_mobility(bodies, shear_rate: float = 0.0, viscosity: float = Flow.viscosity, wall: bool = True,
                   forces=None, torques=None, device="cpu", *, options: SolverOptions | None = None,
                   initial_guess=None) -> MobilitySolution:
    """Rigid velocities of free bodies and holding loads of fixed ones (SI units), one solve.

    bodies: list of ``Body``; shear_rate (1/s) of u = shear_rate * z e_x; viscosity (Pa s);
    wall: no-slip plane z = 0 (else unbounded); forces, torques: (n_bodies, 3) external loads
    on free bodies (N, N m), zero rows for fixed ones; options: ``SolverOptions`` (quadrature,
    density order, contact refinement, GMRES tolerance, precision, operator mode; each field
    documented there, defaults resolved for a solve); initial_guess: a previous solution's
    ``solution_vector``. For repeated solves use ``MobilitySolver``.

    Examples
    --------
    Stokes's law: a sphere pulled by 1 pN in unbounded fluid moves at F / (6 pi mu a), here
    within 0.2 % on the k = 2 mesh of 24 elements:

    >>> import math
    >>> import warpbem as wb
    >>> cell = wb.Body(wb.mesh.sphere(radius=5e-6, subdivisions=2))
    >>> sol = wb.solve_mobility([cell], viscosity=1e-3, wall=False, forces=[[1e-12, 0.0, 0.0]])
    >>> print(f"{sol.velocity[0, 0] / (1e-12 / (6 * math.pi * 1e-3 * 5e-6)):.3f}")
    1.001

    A free cell in wall shear beside a held one (thesis ch. 5.3): the free cell's motion, and
    the force holding the adherent cell against the flow:

    >>> sphere = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> free = wb.Body(sphere, position=(-20e-6, 10.5e-6, 7.75e-6))
    >>> adherent = wb.Body(sphere, position=(0.0, 0.0, 7.5e-6), fixed=True)
    >>> sol = wb.solve_mobility([free, adherent], shear_rate=100.0)
    >>> sol.velocity.shape, sol.converged
    ((2, 3), True)
    >>> bool(sol.velocity[0, 0] > 0 and sol.force[1, 0] < 0)   # carried downstream; held upstream
    True
    """
    solver = MobilitySolver(shear_rate, viscosity, wall, device, options, keep_systems=False)
    return solver.solve(bodies, forces, torques, initial_guess)
