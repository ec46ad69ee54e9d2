"""One deflated solve for the three second-kind problems: the mobility (CDL, thesis eq.
2.7-2.17), the traction (completed adjoint double layer, eq. 2.22-2.25) and the interior elastic
problem (eq. 2.30-2.31).

Each operator A has the rigid motions of every body as eigenfunctions (eigenvalue 0 of 1/2 + D
and of its adjoint and elastic analogues, the -1 of the thesis's unscaled D). Wielandt's
deflation adds back the projection on them, with the six rigid fields phi_p of body p made
orthonormal by Gram-Schmidt in the discrete inner product <u, v> = sum_a u_a . v_a A_a (area
weights A_a; a Cholesky factor L_p of the Gram matrix, phi = raw L^-T), the same quadrature as
the operator's, which non-spherical bodies need:

    M x = A x~ + sum_{p shifted} phi_p <phi_p, x> + R(c),    c_p = <phi_p, x>,

x~ = x - P x (the operator applied to the non-rigid part only, where A annihilates rigid fields
exactly in the continuum but not in the discretisation: the CDL) or x itself (traction,
elasticity), and R the response of bodies whose rigid coefficients stand for another unknown
(the CDL's fixed bodies, whose coefficients carry their holding loads), given by the caller
through ``apply``. The spectrum then lies in (0, 1] up to the discretisation and GMRES
converges in a few tens of iterations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg as spla

from .linalg import gmres, gmres_batch


@dataclass(frozen=True)
class RigidModes:
    """The orthonormal rigid modes of each body of a ``SurfaceGeometry``: ``modes[p]`` (3 n_p, 6),
    ``<phi_k, phi_l> = delta_kl``; ``cholesky[p]`` the factor L_p of the raw fields' Gram matrix
    (raw = phi L^T: the translation and rotation fields of ``geometry.rigid_modes``)."""

    modes: tuple
    cholesky: tuple
    weights: np.ndarray  # (3 n,) area weight of every unknown
    ranges: tuple  # slice of each body's unknowns

    @classmethod
    def of(cls, geometry) -> "RigidModes":
        weights = np.repeat(geometry.areas, 3)
        ranges = tuple(slice(3 * a, 3 * b) for a, b in geometry.body_ranges)
        modes, factors = [], []
        for p, rows in enumerate(ranges):
            raw = geometry.rigid_modes(p)
            factor = np.linalg.cholesky(raw.T @ (weights[rows, None] * raw))
            modes.append(scipy.linalg.solve_triangular(factor, raw.T, lower=True).T)
            factors.append(factor)
        return cls(tuple(modes), tuple(factors), weights, ranges)

    def coefficients(self, body: int, x: np.ndarray) -> np.ndarray:
        """<phi_p^l, x> for the six modes of body p ((6,), or (6, k) for the k columns of x)."""
        rows = self.ranges[body]
        return self.modes[body].T @ (self.weights[rows] * x[rows].T).T

    def to_raw(self, body: int, coefficients: np.ndarray) -> np.ndarray:
        """The raw coefficients (U, Omega) of the rigid field sum_l c_l phi_l: L^-T c."""
        return scipy.linalg.solve_triangular(self.cholesky[body].T, coefficients, lower=False)

    def dual_of_loads(self, body: int, loads: np.ndarray) -> np.ndarray:
        """Coefficients c with <raw_k, sum_l c_l phi_l> = loads_k (a force and torque as the
        moments of a traction): L^-1 loads."""
        return scipy.linalg.solve_triangular(self.cholesky[body], loads, lower=True)


def deflated_operator(apply, modes: RigidModes, shifted, non_rigid_part: bool, response=None,
                      blocks: bool = False) -> spla.LinearOperator:
    """The deflated system M of the module docstring as a LinearOperator: ``apply(y, c)`` the
    operator on y (x~), given the rigid coefficients ``c`` ((n_bodies, 6)) for operators that
    sum the bodies' responses with it (the treecode); ``shifted``: per body, whether its rigid
    part is mapped to itself (Wielandt); ``response(c)``: R(c), added last, or None. ``blocks``:
    ``apply`` takes (N, k) blocks (c then (n_bodies, 6, k)) and ``response`` is None, so
    ``matmat`` applies M to k columns at once (``linalg.gmres_batch``); else column by column."""
    shifted = np.asarray(shifted, dtype=bool)
    size = len(modes.weights)

    def matvec(x):
        if not blocks and x.ndim == 2:  # LinearOperator's own matmat passes single (N, 1) columns
            x = x[:, 0]
        c = np.array([modes.coefficients(p, x) for p in range(len(modes.ranges))])
        rigid = np.zeros_like(x)
        for p, rows in enumerate(modes.ranges):
            rigid[rows] = modes.modes[p] @ c[p]
        out = apply(x - rigid if non_rigid_part else x, c)
        for p, rows in enumerate(modes.ranges):
            if shifted[p]:
                out[rows] += rigid[rows]
        return out if response is None else out + response(c)

    if blocks and response is not None:
        raise ValueError("a deflated operator with a response R(c) applies column by column")
    return spla.LinearOperator((size, size), matvec=matvec, matmat=matvec if blocks else None, dtype=np.float64)


def deflated_solve(system: spla.LinearOperator, rhs: np.ndarray, options, *, initial_guess=None,
                   preconditioner=None, exact_preconditioner: bool = False):
    """GMRES on a deflated system with the tolerance and iteration limit of ``options`` (a
    resolved ``SolverOptions``): a GMRESResult, or for ``rhs`` of k columns (N, k) a list of
    them (``gmres_batch``)."""
    solver = gmres_batch if np.ndim(rhs) == 2 else gmres
    return solver(system, rhs, tolerance=options.tolerance, max_iterations=options.max_iterations,
                  initial_guess=initial_guess, preconditioner=preconditioner,
                  exact_preconditioner=exact_preconditioner)
