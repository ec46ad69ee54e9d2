"""The discrete system of the Completed Double Layer boundary element method for the mobility
of many rigid bodies in linear shear flow above a no-slip wall (Power & Miranda 1987; Kim & Karrila 1991 ch. 17;
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

import numpy as np
import scipy.linalg
import scipy.sparse.linalg as spla

from ..kernels.launch import blas_on_all_cores
from .block_factors import BlockFactors, block_key
from .deflated import RigidModes, deflated_operator
from .geometry import SurfaceGeometry
from .operators import DiscreteOperator, dof_indices

FACTOR_LIMIT = 1800  # unknowns (600 elements): largest moving body block factored for GMRES
FORCE_UNIT = 6.0 * np.pi  # scaled force of a unit-speed unit sphere; scales the load unknowns
TORQUE_UNIT = 8.0 * np.pi


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

    def __init__(self, geometry: SurfaceGeometry, double_layer: DiscreteOperator, fixed,
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

    def right_side(self, ambient: np.ndarray, free_loads: dict, prescribed: np.ndarray, slip: list,
                   speed: float) -> np.ndarray:
        """The right side, scaled: minus the undisturbed flow ``ambient`` (n_points, 3, scaled) at
        the collocation points, minus the completions' velocity of the free bodies' given scaled
        loads {body: (6,)}, plus the fixed bodies' ``prescribed`` rigid motions (n_bodies, 6: U and
        Omega L, m/s) and every body's surface velocity beyond its rigid motion (``slip``: per
        body (elements, 3) m/s, or None), both over the velocity scale ``speed``."""
        rhs = np.zeros(self.size)
        rhs[:] = -ambient.ravel()
        if free_loads and self.treecode:
            rhs -= self.double_layer.point_sources_velocity(self.pole_forces(None, free_loads)).ravel()
        elif free_loads:
            completions = [self.completion(p, loads) for p, loads in free_loads.items()]
            rhs -= self.double_layer.point_force_velocity(
                self.geometry.collocation, np.concatenate([c[0] for c in completions]),
                np.concatenate([c[1] for c in completions])).ravel()
        for p in np.flatnonzero(self.fixed):
            rhs[self.ranges[p]] += self.geometry.rigid_modes(p) @ (prescribed[p] / speed)
        for p, velocity in enumerate(slip):  # U + Omega x r + w on the surface: w joins the right side
            if velocity is not None:
                rhs[self.ranges[p]] += non_rigid_part(self.geometry, p, velocity) / speed
        return rhs

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
            return deflated_operator(lambda y, c: self.double_layer.apply(y, self.pole_forces(self.held_loads(c))),
                                     self.rigid, ~self.fixed, non_rigid_part=True)
        response = (lambda c: self.fixed_columns @ self.held_loads(c)) if self.fixed.any() else None
        # without a fixed body's response, the dense matrix on the CPU takes blocks of columns
        blocks = response is None and self.double_layer.mode == "dense" and self.double_layer.device.is_cpu
        return deflated_operator(lambda y, c: self.double_layer.apply(y), self.rigid, ~self.fixed,
                                 non_rigid_part=True, response=response, blocks=blocks)

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

    @staticmethod
    def _factor(block: np.ndarray):
        """A body block's LU factors, on every core when the block is large (kernels/launch.py)."""
        with blas_on_all_cores(len(block)):
            return scipy.linalg.lu_factor(block, check_finite=False)

    def preconditioner(self, previous: "CompletedDoubleLayer | None", kept_for_later: bool = True,
                       every_body: bool = False, factors: BlockFactors | None = None) -> spla.LinearOperator:
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
        Matrix-free operators assemble each body's block alone for it (DiscreteOperator.
        diagonal_blocks), so large scenes keep the preconditioner. ``every_body``: factor every
        body's block whatever its size, for a system solved for many loads (a pair snapshot's 13
        solves: a refined 5 um cell's block of 3663 unknowns factors in about 1 s, and cuts GMRES
        from about 30 iterations per solve; dynamics/pairwise.py). ``factors``: a solver's store
        of free bodies' factors by shape and height (``block_factors.py``), which a moved body
        of a block already seen takes instead of factoring anew."""
        if self.factors is not None:  # built for this system already
            return self._block_jacobi
        old = previous.factors if previous is not None and previous.factors is not None else []
        kept = [p < len(old) and old[p] is not None and self.unchanged[p] and previous.fixed[p] == self.fixed[p]
                for p in range(len(self.ranges))]
        needed = [p for p, rows in enumerate(self.ranges)
                  if not kept[p] and (every_body or (self.fixed[p] and kept_for_later)
                                      or rows.stop - rows.start <= FACTOR_LIMIT)]
        keys = {p: self._block_key(p) for p in needed if factors is not None and not self.fixed[p]}
        stored = {p: found for p, key in keys.items() if (found := factors.get(key)) is not None}
        blocks = self.double_layer.diagonal_blocks([p for p in needed if p not in stored])
        self.factors = [old[p] if kept[p] else stored[p] if p in stored else
                        self._factor(self.body_block(p, blocks[p])) if p in blocks else None
                        for p in range(len(self.ranges))]
        for p, key in keys.items():
            if p not in stored:
                factors.put(key, self.factors[p])

        ranges, factors = self.ranges, self.factors  # not self: a cycle through the closure kept
        # whole systems (dense matrices) alive until the cyclic collector ran, 3 GB per step

        def apply(r):
            out = r.copy()
            for rows, factor in zip(ranges, factors):
                if factor is not None:
                    out[rows] = scipy.linalg.lu_solve(factor, r[rows], check_finite=False)
            return out

        # lu_solve takes a block of columns as it takes one (gmres_batch)
        self._block_jacobi = spla.LinearOperator((self.size, self.size), matvec=apply, matmat=apply, dtype=np.float64)
        return self._block_jacobi

    def _block_key(self, body: int) -> bytes:
        """The store key of a free body's own block (block_factors.block_key)."""
        geometry = self.geometry
        first, last = geometry.element_ranges[body]
        return block_key(geometry.element_nodes[first:last], geometry.centres[body], geometry.density_order,
                         geometry.length_scale)

    def preconditioner_is_exact(self) -> bool:
        """One body with its block factored: block Jacobi is then the inverse of the system."""
        return len(self.ranges) == 1 and self.factors is not None and self.factors[0] is not None

    def rigid_velocity(self, body: int, x: np.ndarray) -> np.ndarray:
        """(U, Omega) of a free body in scaled units: the rigid field -P_p q."""
        return -self.rigid.to_raw(body, self.rigid.coefficients(body, x))
