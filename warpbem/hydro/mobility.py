"""Mobility of many rigid bodies in linear shear flow above a no-slip wall by the Completed
Double Layer boundary element method (Power & Miranda 1987; Kim & Karrila 1991 ch. 17;
thesis eq. 2.5-2.17).

Scaled units inside (``length_scale`` L = mean equivalent radius, viscosity mu, velocity scale
U0 from the data); SI at the API. The disturbance of the ambient flow u_inf = shear_rate z e_x
is written as

    w = D[q] + sum_p V_p,

D the double layer of ``kernels/greens.py`` (wall images included when ``wall``), q a density
constant per element, and V_p the completion of body p: a Stokeslet of strength F_p at its
reference point x_p and, for its torque T_p, three pairs of Stokeslets +-(T_p x e_l)/(4 d) at
x_p +- d e_l (a force couple whose moment is T_p). The double layer carries no force or torque,
so (F_p, T_p) are the force and torque the body exerts on the fluid, i.e. the external load on
a free body, or the load that holds a fixed one. Any interior singularity with that force and
torque completes the representation; a couple of Stokeslets needs no rotlet-image formula.

Boundary condition on body p (exterior limit of D is D^PV + q/2):

    (1/2 + D^PV) q + sum V = U_p + Omega_p x (xi - x_p) - u_inf(xi).

* Free body: the rigid velocity is unknown and set to -P_p q, where P_p is the projector onto
  the body's six rigid fields, orthonormalised by Gram-Schmidt (a Cholesky factor of their Gram
  matrix) in the discrete inner product <u, v> = sum_b u_b . v_b A_b (element areas A_b); this
  is Wielandt's deflation that maps the rigid null space of (1/2 + D^PV) to eigenvalue 1
  (thesis eq. 2.7-2.17). With this sign and scaling the whole spectrum lies in (0, 1]; the
  thesis's second deflation (of its eigenvalue 2, eq. 2.15-2.16) is not needed for GMRES.
* Fixed body (prescribed U_p, Omega_p, zero by default): (F_p, T_p) are unknown. Since the
  double layer ignores the rigid part of q (below), that part is free to carry them: the six
  coefficients c_p = <phi_p, q> stand for the loads, (F_p, T_p) = s_p * c_p, and the
  completion V_p(s_p c_p) takes the place of P_p q in the equation. With s_p chosen so that
  <phi_p^l, V_p(s_p e_l)> = 1 the rigid block is close to the identity, as for a free body:
  the system stays square with a spectrum like the free bodies', instead of the saddle point
  of six extra constraint rows (which took 137 GMRES iterations instead of 37 among four
  adherent cells near the wall).

Since (1/2 + D^PV) annihilates rigid fields exactly, the discrete operator is applied to the
non-rigid part q - P q only. The identity already makes this exact for translations; for
rotations, whose piecewise-constant representation it does not annihilate exactly, it removes
an O(h^2) error (sphere under torque, 96 elements: 5e-3 -> 1.7e-4).
"""

from __future__ import annotations

import copy
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg as spla

from ..surfaces.body import Body
from ..surfaces.placement import check_placement
from ..surfaces.gaps import WALL
from .deflated import RigidModes, deflated_operator, deflated_solve
from .geometry import SurfaceGeometry
from .operators import DoubleLayerOperator, QuadratureOptions, choose_operator, dof_indices
from .options import Flow, SolverOptions


class ContactResolutionWarning(UserWarning):
    """Two surfaces closer than the contact refinement resolves: accuracy degrades there."""


FACTOR_LIMIT = 1800  # unknowns (600 elements): largest moving body block factored for GMRES
FORCE_UNIT = 6.0 * np.pi  # scaled force of a unit-speed unit sphere; scales the load unknowns
TORQUE_UNIT = 8.0 * np.pi


@dataclass(frozen=True)
class MobilitySolution:
    """Rigid motion and loads of every body, SI units (rows in the order of the bodies).

    velocity (m/s) and angular_velocity (rad/s) of each body's reference point; prescribed for
    fixed bodies. force (N) and torque (N m, about the reference point): for free bodies the
    given external ones; for fixed bodies the external load that holds them, which is minus the
    hydrodynamic force and torque.
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


def non_rigid_part(geometry: SurfaceGeometry, body: int, surface_velocity: np.ndarray) -> np.ndarray:
    """(3 n,) the body's per-element ``surface_velocity`` at its collocation points (refined
    elements take their parent's value) less its rigid part, the least-squares fit of the six
    rigid fields in the area-weighted inner product, so that the rigid motion the solver finds
    is the whole rigid part of the surface's motion."""
    start, stop = geometry.body_ranges[body]
    w = surface_velocity[geometry.parent_element[start:stop]].ravel()
    modes, weights = geometry.rigid_modes(body), np.repeat(geometry.areas[start:stop], 3)
    gram = modes.T @ (weights[:, None] * modes)
    return w - modes @ np.linalg.solve(gram, modes.T @ (weights * w))


def completion_poles(geometry: SurfaceGeometry, body: int):
    """The 7 poles of body p's completion, its reference point and 6 points at +-d along the
    axes (d a quarter of the distance to its nearest collocation point), and d."""
    start, stop = geometry.body_ranges[body]
    centre = geometry.centres[body]
    d = 0.25 * np.linalg.norm(geometry.collocation[start:stop] - centre, axis=1).min()
    e = np.eye(3)
    return np.concatenate([centre[None], centre + d * e, centre - d * e]), d


def all_completion_poles(geometry: SurfaceGeometry) -> np.ndarray:
    """(7 n_bodies, 3) the completion poles of every body, body after body."""
    return np.concatenate([completion_poles(geometry, p)[0] for p in range(len(geometry.body_ranges))])


class CompletedDoubleLayer:
    """The discrete CDL system for the density q (3 E unknowns); for a fixed body the rigid
    part of its density stands for its load (see the module docstring)."""

    def __init__(self, geometry: SurfaceGeometry, double_layer: DoubleLayerOperator, fixed,
                 previous: "CompletedDoubleLayer | None" = None):
        self.geometry = geometry
        self.double_layer = double_layer
        self.fixed = np.asarray(fixed, dtype=bool)
        self.fixed_index = np.cumsum(self.fixed) - 1
        self.size = 3 * geometry.n_points
        self.rigid = RigidModes.of(geometry)  # Gram-Schmidt of each body's rigid fields (deflated.py)
        self.ranges = self.rigid.ranges
        self.unchanged = geometry.unchanged_bodies(previous.geometry if previous else None)
        self.factors = None  # LU of each body's block (None: not factored), see preconditioner
        self._block_jacobi = None
        # the treecode sums the fixed bodies' completions with the double layer; the dense
        # columns of every fixed body at every point would not fit (1024 cells: 14 GB)
        self.treecode = double_layer.mode == "treecode"
        self.fixed_columns = None if self.treecode else self._fixed_body_columns(previous)
        self.own_columns = {p: self._own_columns(p) for p in np.flatnonzero(self.fixed)}
        # load per unit rigid coefficient: makes <phi_l, V(s_l e_l)> = 1 (rigid block ~ identity)
        self.load_per_coefficient = np.zeros(6 * int(self.fixed.sum()))
        for p in np.flatnonzero(self.fixed):
            k = 6 * self.fixed_index[p]
            rows = self.ranges[p]
            response = self.rigid.modes[p].T @ (self.rigid.weights[rows, None] * self.own_columns[p])
            self.load_per_coefficient[k : k + 6] = 1.0 / np.diag(response)

    def _own_columns(self, body: int) -> np.ndarray:
        """(3 n_p, 6) velocity at fixed body p's own points of its six unit loads."""
        if self.fixed_columns is not None:
            k = 6 * self.fixed_index[body]
            return self.fixed_columns[self.ranges[body], k : k + 6]
        units = np.diag([FORCE_UNIT] * 3 + [TORQUE_UNIT] * 3)
        poles, point_forces = self.completion(body, units)
        start, stop = self.geometry.body_ranges[body]
        tensors = self.double_layer.point_force_tensors(self.geometry.collocation[start:stop], poles)
        return np.einsum("tpij,lpj->til", tensors, point_forces).reshape(-1, 6)

    def completion(self, body: int, loads: np.ndarray):
        """Poles (7, 3) and point forces (..., 7, 3) of body p's completion for scaled loads
        (F, T) of shape (..., 6): one load case or several."""
        poles, d = completion_poles(self.geometry, body)
        e = np.eye(3)
        loads = np.asarray(loads, dtype=float)
        couple = np.cross(loads[..., None, 3:], e) / (4.0 * d)  # (T x e_l) / (4 d), row l
        return poles, np.concatenate([loads[..., None, :3], couple, -couple], axis=-2)

    def _fixed_body_columns(self, previous) -> np.ndarray:
        """Velocity at every collocation point of the six unit loads of each fixed body; the
        rows of bodies that did not move are copied from ``previous`` when the fixed body did
        not move either."""
        columns = np.zeros((self.size, 6 * int(self.fixed.sum())))
        all_rows = np.arange(self.geometry.n_points)
        for p in np.flatnonzero(self.fixed):
            k = 6 * self.fixed_index[p]
            targets = all_rows
            if previous is not None and self.unchanged[p] and previous.fixed[p]:
                kept = np.flatnonzero(self.unchanged)
                old_rows = dof_indices(previous.geometry.points_of(kept))
                old_k = 6 * previous.fixed_index[p]
                columns[dof_indices(self.geometry.points_of(kept)), k : k + 6] = \
                    previous.fixed_columns[old_rows, old_k : old_k + 6]
                targets = self.geometry.points_of(np.flatnonzero(~self.unchanged))
            if len(targets) == 0:
                continue
            units = np.diag([FORCE_UNIT] * 3 + [TORQUE_UNIT] * 3)
            poles, point_forces = self.completion(p, units)  # point_forces: (load, pole, 3)
            tensors = self.double_layer.point_force_tensors(self.geometry.collocation[targets], poles)
            velocity = np.einsum("tpij,lpj->til", tensors, point_forces)
            columns[dof_indices(targets), k : k + 6] = velocity.reshape(-1, 6)
        return columns

    def initial_guess(self, previous: "CompletedDoubleLayer", solution: np.ndarray) -> np.ndarray:
        """Start GMRES from the previous solution, body by body where the element count of a
        body is unchanged (its density barely changes between nearby configurations)."""
        x0 = np.zeros(self.size)
        old = previous.geometry
        for p, rows in enumerate(self.ranges):
            if p < len(old.body_ranges) and previous.fixed[p] == self.fixed[p]:
                a0, a1 = old.body_ranges[p]
                if a1 - a0 == rows.stop // 3 - rows.start // 3:
                    x0[rows] = solution[3 * a0 : 3 * a1]
        return x0

    def held_loads(self, coefficients: np.ndarray) -> np.ndarray:
        """Scaled loads of the fixed bodies, in order, from every body's rigid coefficients
        ((n_bodies, 6)): the fixed ones' carry their loads (module docstring)."""
        loads = np.zeros(len(self.load_per_coefficient))
        for p in np.flatnonzero(self.fixed):
            k = 6 * self.fixed_index[p]
            loads[k : k + 6] = coefficients[p] * self.load_per_coefficient[k : k + 6]
        return loads

    def pole_forces(self, loads: np.ndarray, free_loads: dict | None = None) -> np.ndarray:
        """(7 n_bodies, 3) point forces at every body's completion poles (the operator's
        ``point_sources``): of the fixed bodies' scaled ``loads`` (6 each, in order), or of the
        free bodies' given loads {body: (6,)}."""
        forces = np.zeros((7 * len(self.ranges), 3))
        if free_loads is None:  # the load unknowns count in units of FORCE_UNIT, TORQUE_UNIT
            units = np.array([FORCE_UNIT] * 3 + [TORQUE_UNIT] * 3)
            free_loads = {p: loads[6 * self.fixed_index[p] : 6 * self.fixed_index[p] + 6] * units
                          for p in np.flatnonzero(self.fixed)}
        for p, body_loads in free_loads.items():
            forces[7 * p : 7 * p + 7] = self.completion(p, body_loads)[1]
        return forces

    def fixed_loads(self, body: int, q: np.ndarray) -> np.ndarray:
        """Scaled (F, T) of a fixed body, carried by the rigid part of its density."""
        k = 6 * self.fixed_index[body]
        return self.rigid.coefficients(body, q) * self.load_per_coefficient[k : k + 6]

    def linear_operator(self) -> spla.LinearOperator:
        """The deflated CDL system (``deflated.py``): (1/2 + D) annihilates rigid fields exactly,
        so it is applied to the non-rigid part only (the discretisation error of piecewise-
        constant rotations then does not enter the motion); free bodies' rigid parts are shifted
        to themselves, fixed bodies' answer with their completions' velocity. The treecode sums
        those completions with the double layer."""
        if self.treecode:
            return deflated_operator(lambda y, c: self.double_layer.matvec(y, self.pole_forces(self.held_loads(c))),
                                     self.rigid, ~self.fixed, non_rigid_part=True)
        return deflated_operator(lambda y, c: self.double_layer.matvec(y), self.rigid, ~self.fixed,
                                 non_rigid_part=True, response=lambda c: self.fixed_columns @ self.held_loads(c))

    def body_block(self, body: int, matrix: np.ndarray) -> np.ndarray:
        """The diagonal block of ``matvec`` for one body's density, from that body's own block
        ``matrix`` of 1/2 + D (overwritten): D (I - Pi) + Pi (free) or + C L Pi (fixed: its load
        columns), Pi = Phi Phi^T W, as one rank-6 update in place (each fresh copy of a large
        block cost more than the arithmetic)."""
        rows = self.ranges[body]
        modes = self.rigid.modes[body]
        weighted = modes.T * self.rigid.weights[rows]  # Pi = modes @ weighted
        if self.fixed[body]:
            k = 6 * self.fixed_index[body]
            added = self.own_columns[body] * self.load_per_coefficient[k : k + 6]
        else:
            added = modes
        matrix += (added - matrix @ modes) @ weighted
        return matrix

    def preconditioner(self, previous: "CompletedDoubleLayer | None", kept_for_later: bool = True) -> spla.LinearOperator:
        """Block Jacobi: the exact inverse of each body's own block (LU), kept for bodies that
        did not change since ``previous``. It takes the ill-conditioning of a body near the wall
        (its own image) out of GMRES: the box-shaped adherent cell's unrefined flat base 0.25 um
        above the wall stalled unpreconditioned GMRES at a residual of 3e-8 after 600
        iterations. A moving body's block is factored anew at each solve, so only up to
        FACTOR_LIMIT unknowns (the LU costs n^3: a sphere refined to 1500 elements near the wall
        took 12-30 s to factor against 3-9 s of plain GMRES); larger moving bodies go without,
        and so do larger fixed ones unless their factors are ``kept_for_later`` (a solver that
        reuses its systems: a held sphere of 768 points at h/a = 1.1 took 1.8 s with its LU
        and 0.31 s in 14 plain GMRES iterations).
        Matrix-free operators assemble each body's block alone for it (DoubleLayerOperator.
        diagonal_blocks), so large scenes keep the preconditioner."""
        if self.factors is not None:  # built for this system already
            return self._block_jacobi
        old = previous.factors if previous is not None and previous.factors is not None else []
        kept = [p < len(old) and old[p] is not None and self.unchanged[p] and previous.fixed[p] == self.fixed[p]
                for p in range(len(self.ranges))]
        needed = [p for p, rows in enumerate(self.ranges)
                  if not kept[p] and ((self.fixed[p] and kept_for_later) or rows.stop - rows.start <= FACTOR_LIMIT)]
        blocks = self.double_layer.diagonal_blocks(needed)
        self.factors = [old[p] if kept[p] else
                        scipy.linalg.lu_factor(self.body_block(p, blocks[p]), check_finite=False) if p in blocks else None
                        for p in range(len(self.ranges))]

        ranges, factors = self.ranges, self.factors  # not self: a cycle through the closure kept
        # whole systems (dense matrices) alive until the cyclic collector ran, 3 GB per step

        def apply(r):
            out = r.copy()
            for rows, factor in zip(ranges, factors):
                if factor is not None:
                    out[rows] = scipy.linalg.lu_solve(factor, r[rows], check_finite=False)
            return out

        self._block_jacobi = spla.LinearOperator((self.size, self.size), matvec=apply, dtype=np.float64)
        return self._block_jacobi

    def preconditioner_is_exact(self) -> bool:
        """One body with its block factored: block Jacobi is then the inverse of the system."""
        return len(self.ranges) == 1 and self.factors is not None and self.factors[0] is not None

    def rigid_velocity(self, body: int, x: np.ndarray) -> np.ndarray:
        """(U, Omega) of a free body in scaled units: the rigid field -P_p q."""
        return -self.rigid.to_raw(body, self.rigid.coefficients(body, x))


class MobilitySolver:
    """The mobility problem for a scene solved again and again (time stepping, parameter
    sweeps): the flow and the ``options`` (``SolverOptions``, context defaults resolved as for
    a solve) are fixed here; ``solve`` takes the bodies of the moment.

    With ``keep_systems`` it keeps, between calls, the operator blocks and the fixed-body
    completion columns of bodies whose elements did not change (fixed adherent cells), and
    starts GMRES from the previous solution. The operator mode "auto" is decided at the first
    solve, for every later one (``mode``; ``operator_description`` reports it).
    """

    def __init__(self, shear_rate: float = 0.0, viscosity: float = Flow.viscosity, wall: bool = True, device="cpu",
                 options: SolverOptions | None = None, *, keep_systems: bool = True):
        self.flow = Flow(shear_rate, viscosity, wall)
        self.device = device
        self.options = (options or SolverOptions()).resolved()
        self.quadrature = QuadratureOptions(order=self.options.quadrature_order,
                                            adaptive=self.options.adaptive_quadrature,
                                            near_factor=self.options.near_factor)
        self.mode = None if self.options.operator == "auto" else self.options.operator
        self.keep_systems = bool(keep_systems)
        self._last = None  # (CompletedDoubleLayer, solution vector, speed, bodies key) of the previous solve
        self._warned = set()  # contacts already reported by this solver

    @property
    def operator_description(self) -> str:
        """The operator's mode as decided ("auto (not yet decided)" before the first solve)."""
        return self.mode or "auto (not yet decided)"

    def solve(self, bodies, forces=None, torques=None, initial_guess=None,
              check_placement_first: bool = True, background: bool = True, ambient_flow=None) -> MobilitySolution:
        """Solve for the bodies of the moment. ``check_placement_first=False`` skips the overlap
        and wall checks, for callers that have just checked these very bodies (time stepping).

        ``background=False`` gives the response to the loads alone (no shear flow, fixed bodies
        at rest), e.g. the mobility of a contact for an implicit contact force; such a solve
        reuses the whole system of a preceding solve of the same bodies and leaves the warm
        start of the next ordinary solve alone.

        ``ambient_flow``: the undisturbed flow in place of the shear flow, a function of the
        collocation points (m, (n, 3)) and the index of each point's body (n,) giving the
        velocity there (m/s, (n, 3)); the flow of frozen adherent cells that are not among the
        bodies (``frozen.py``). Ignored with ``background=False``."""
        bodies = checked_bodies(bodies)
        forces = checked_loads("forces", forces, bodies)
        torques = checked_loads("torques", torques, bodies)
        if check_placement_first:
            check_placement(bodies, self.flow.wall)

        length = float(np.mean([b.mesh.equivalent_radius() for b in bodies]))
        fixed = np.array([b.fixed for b in bodies])
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
        previous = self._last[0] if self.keep_systems and self._last else None
        # the meshes themselves, not their ids: the key keeps them alive, so a new mesh can never
        # come back at a garbage-collected one's address and be taken for it
        key = [(b.mesh, b.position.tobytes(), b.orientation.tobytes(), b.fixed) for b in bodies]
        if previous is not None and key == self._last[3]:  # the very same bodies: keep the system
            system = previous
            geometry, double_layer = system.geometry, system.double_layer
        else:
            geometry = SurfaceGeometry.from_bodies(bodies, options.quadrature_order, length, flow.wall,
                                                   options.contact_refinement, options.refine_fixed_at_wall,
                                                   options.density_order)
            self._warn_unresolved(geometry, length)
            if self.mode is None:  # "auto": decided once, for this solve and every later one
                self.mode = choose_operator(3 * geometry.n_points, options.dtype, self.device)
            double_layer = DoubleLayerOperator(geometry, flow.wall, self.quadrature, options.dtype, self.device,
                                               self.mode, previous=previous.double_layer if previous else None,
                                               treecode=options.treecode, point_sources=all_completion_poles(geometry))
            system = CompletedDoubleLayer(geometry, double_layer, fixed, previous)

        rhs = np.zeros(system.size)
        xi = geometry.collocation
        ambient = np.zeros_like(xi)
        if background and ambient_flow is not None:
            ambient = ambient_flow(xi * length, geometry.body_of_point) / speed
        elif background:
            ambient[:, 0] = flow.shear_rate * length / speed * xi[:, 2]
        rhs[:] = -ambient.ravel()
        free_loads = {p: np.concatenate([forces[p] / force_scale, torques[p] / (force_scale * length)])
                      for p in np.flatnonzero(~fixed)}
        free_loads = {p: loads for p, loads in free_loads.items() if np.any(loads)}
        if free_loads and system.treecode:
            rhs -= double_layer.point_sources_velocity(system.pole_forces(None, free_loads)).ravel()
        elif free_loads:
            completions = [system.completion(p, loads) for p, loads in free_loads.items()]
            rhs -= double_layer.point_force_velocity(
                xi, np.concatenate([c[0] for c in completions]), np.concatenate([c[1] for c in completions])).ravel()
        for p in np.flatnonzero(fixed):
            rhs[system.ranges[p]] += geometry.rigid_modes(p) @ (prescribed[p] / speed)
        for p, velocity in enumerate(slip):  # U + Omega x r + w on the surface: w joins the right side
            if velocity is not None:
                rhs[system.ranges[p]] += non_rigid_part(geometry, p, velocity) / speed

        if initial_guess is not None and np.shape(initial_guess) != (system.size,):
            raise ValueError(f"initial_guess must have shape ({system.size},) for this scene, got"
                             f" {np.shape(initial_guess)} (the mesh or the bodies changed)")
        if initial_guess is None and previous is not None and background:
            # the previous solution is in the previous scaling: rescale the loads part with it
            initial_guess = system.initial_guess(previous, self._last[1] * (self._last[2] / speed))
        preconditioner = system.preconditioner(previous, self.keep_systems) if options.precondition else None
        result = deflated_solve(system.linear_operator(), rhs, options, initial_guess=initial_guess,
                                preconditioner=preconditioner, exact_preconditioner=system.preconditioner_is_exact())
        x = result.solution
        if background or self._last is None or system is not self._last[0]:
            self._last = (system, x, speed, key)

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
        return MobilitySolution(velocity, angular_velocity, force, torque, result.iterations,
                                result.residual, result.converged, double_layer.mode, x,
                                double_layer.reused_bodies)

    def fresh(self) -> "MobilitySolver":
        """A solver with these settings and nothing of this one's solves (no kept system, no
        warnings given, "auto" operator not yet decided)."""
        other = copy.copy(self)
        other.mode = None if self.options.operator == "auto" else self.options.operator
        other._last, other._warned = None, set()
        return other

    @property
    def last_system(self):
        """(CompletedDoubleLayer, scaled solution, velocity scale in m/s) of the last ordinary
        solve (``keep_systems``), or None: the density a caller evaluates elsewhere (``frozen.py``)."""
        return None if self._last is None else self._last[:3]

    def _warn_unresolved(self, geometry, length):
        """Warn once per contact (for the life of this solver) that is closer than the contact
        refinement resolves (see refinement.refine_near_contact and the README stability map)."""
        for (p, q), gap in sorted(geometry.unresolved_contacts.items()):
            if (p, q) in self._warned or (q, p) in self._warned:
                continue
            self._warned.add((p, q))
            what = "the wall" if q == WALL else f"body {q}"
            warnings.warn(
                f"body {p} and {what} are {gap * length:.3g} m apart ({gap:.3g} mean radii), closer than"
                f" the mesh resolves (contact_refinement={self.options.contact_refinement:g}): the gap to the wall, or"
                " the gap to another body (half of it with density_order 2), is under 2 % of the body's"
                " element radius, or under three"
                " element radii without refinement, or the refinement stopped at its deepest level."
                " Squeeze-flow forces lose accuracy first, past about 1 % (README: stability map); a finer"
                " mesh helps."
                + (" In float32, GMRES stalls from about here: use dtype='float64'." if self.options.dtype == "float32" else ""),
                ContactResolutionWarning, stacklevel=3)


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
    """
    solver = MobilitySolver(shear_rate, viscosity, wall, device, options, keep_systems=False)
    return solver.solve(bodies, forces, torques, initial_guess)
