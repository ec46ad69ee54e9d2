"""The joint backward-Euler step of every stiff force law (repulsion, bond springs), DESIGN.md §4.

Each implicit interaction gives coordinates s_c (a separation, a bond length; m) with a convex
energy U_c(s) (J) whose force f_c = -U_c'(s) (N, along the coordinate's unit load) and stiffness
k_c = U_c''(s) >= 0 (N/m) it evaluates. Over a step dt the forces are those at the end of the
step (backward Euler):

    s' = s + dt (r + R z),      with the body motion V = V0 + sum_k z_k W_k,

where W_k is the motion of the k-th load of a basis (unit forces along each coordinate when they
are fewer than the free bodies' degrees of freedom, else unit forces and torques on each free
body), z its coefficients (N), r the coordinates' rates under V0 (the motion without the stiff
laws) and R_ck the rate of coordinate c under W_k. The step is the minimiser of

    Phi(z) = z.Q.z / 2 + sum_c U_c(s'_c) / dt,      Q_kl = (load k) . W_l  (symmetric, PSD),

whose stationarity Q z = R^T f(s') says that the basis loads are the stiff forces (the
dissipation of the motion they cause balances the work of the laws). Phi is convex, so Newton's
method with a backtracking line search converges from any start where every U_c is finite
(a repulsion energy is +inf once roughness layers touch): the step is stable for any dt, the
repulsion stays positive, and stiff bonds and repulsion are solved together, however strongly
they are coupled through one cell's mobility. The unknowns are at most 6 per free body, however
many bonds there are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.linalg.blas
import scipy.sparse
import scipy.sparse.linalg as spla

from ..hydro.linalg import ConvergenceError, gmres

MAX_ITERATIONS = 200
LENGTH_TOLERANCE = 1e-16  # m: converged when no coordinate moves by more (plus 1e-13 relative)
STALLED = 0.25  # a Newton step's squared norm above this share of the step before it: not shrinking


# The Newton system Q + dt R^T K R and the holding loads' normal equations are symmetric positive
# semi-definite: a Cholesky factor solves them, where NumPy's least squares (an SVD) took 74 % of
# the implicit step of 64 cells (384 coefficients; py-spy on scenes/rolling_patch_8x8.toml, 106
# against 15 ms per solve beside that run). A factor whose pivots span more than this ratio
# (condition above 1e14: a load that moves nothing, cells without bonds among the holding loads)
# gives way to the least-squares solution of least norm, as before.
PIVOT_RATIO = 1e-7


def solve_semidefinite(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with matrix x = rhs for a symmetric positive semi-definite matrix (comment above)."""
    try:
        factor = scipy.linalg.cho_factor(matrix, check_finite=False)
        pivots = np.abs(np.diag(factor[0]))
        if pivots.min() > PIVOT_RATIO * pivots.max():
            return scipy.linalg.cho_solve(factor, rhs, check_finite=False)
    except np.linalg.LinAlgError:  # not positive definite
        pass
    return np.linalg.lstsq(matrix, rhs, rcond=1e-14)[0]


class ImplicitSolveError(RuntimeError):
    """The joint backward-Euler solve found no admissible start or did not converge."""


class DenseResponse:
    """R (m, p) held whole: the rate of each coordinate under each basis load."""

    def __init__(self, matrix: np.ndarray):
        self.matrix = matrix

    def __matmul__(self, z):
        return self.matrix @ z

    def transposed(self, f):
        """R^T f."""
        return self.matrix.T @ f

    def weighted_gram(self, where, k):
        """R_w^T K R_w of the coordinates ``where`` and their stiffness k (per coordinate, or 3 x 3
        blocks)."""
        r = self.matrix[where]
        if k.ndim == 1:
            return r.T @ (k[:, None] * r)
        g = r.reshape(len(k), 3, -1)
        return np.einsum("gip,gij,gjq->pq", g, k, g)

    def holding_loads(self, rates):
        """The coefficients that hold every coordinate still (R z = -r, least squares)."""
        return np.linalg.lstsq(self.matrix, -rates, rcond=1e-14)[0]

    def newton_step(self, z, force, stiffness, dt):
        """None: R held whole has no structure that solves the Newton system without forming it
        (MobilityResponse has)."""
        return None


class FactoredResponse(DenseResponse):
    """R = G V, never formed: G (m, 6 n, sparse) the rate of each coordinate per unit rigid
    motion of each body (a bond moves with one cell, a contact with two), V (6 n, p) the motion
    of each basis load. With n cells and m = O(n) bonds its products cost O(n p) where the
    whole R's R^T K R costs O(n p^2) (issue 25: the implicit solve sparse over cells)."""

    def __init__(self, geometry, motion: np.ndarray):
        self.geometry, self.motion = geometry, motion

    @classmethod
    def of(cls, coordinates, velocity, angular_velocity) -> "FactoredResponse":
        """From the coordinates (ImplicitCoordinates) and the basis's motions (p, n, 3)."""
        n = coordinates.n_bodies
        motion = np.concatenate([velocity, angular_velocity], axis=2).reshape(-1, 6 * n).T
        return cls(coordinates.rate_geometry(), motion)

    def __matmul__(self, z):
        return self.geometry @ (self.motion @ z)

    def transposed(self, f):
        return self.motion.T @ (self.geometry.T @ f)

    def weighted_gram(self, where, k):
        return self.motion.T @ (self.stiffness_gram(where, k) @ self.motion)

    def stiffness_gram(self, where, k):
        """G_w^T K G_w (sparse, 6 n x 6 n) of the coordinates ``where`` and their stiffness k."""
        g = self.geometry[where]
        if k.ndim == 1:
            weights = scipy.sparse.diags(k)
        else:  # 3 x 3 blocks along the diagonal
            weights = scipy.sparse.bsr_matrix((k, np.arange(len(k)), np.arange(len(k) + 1)),
                                              shape=(g.shape[0], g.shape[0]))
        return (g.T @ (weights @ g)).tocsr()

    def holding_loads(self, rates):
        """Least squares through the normal equations, (G V)^T (G V) z = -(G V)^T r, whose matrix
        is V^T (G^T G) V (p x p)."""
        gram = self.motion.T @ ((self.geometry.T @ self.geometry) @ self.motion)
        return solve_semidefinite(gram, -self.transposed(rates))


# relative residual of the Newton step's GMRES (MobilityResponse): Newton converges linearly at
# this rate once its own steps reach it, and ImplicitSystem.solve stops where they stop shrinking
NEWTON_TOLERANCE = 1e-12
# coefficients from which MobilityResponse solves the Newton step by GMRES: below, H formed and
# factored is cheaper (a synthetic system of cells 25 um apart beside a running scene, one Newton
# step: 0.6 against 1.9 ms at 96 coefficients, 16 cells; 42 against 2.4 ms at 216, 36 cells;
# 46 against 4.3 ms at 384, 64 cells)
STRUCTURED_FROM = 128


def symmetric_product(q: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Q x for the symmetric Q (the symmetrised grand mobility, symmetric bit for bit). From
    STRUCTURED_FROM coefficients on by BLAS symv, which reads one triangle of Q where gemv reads it
    whole: 0.19 against 0.66 ms for the 1536 coefficients of 256 cells on one core, and the
    implicit step takes about a hundred products per time step. Below, as ``q @ x``."""
    if len(x) < STRUCTURED_FROM:
        return q @ x
    return scipy.linalg.blas.dsymv(1.0, q.T, x, lower=1)  # Q's transpose, Q itself, in Fortran order


class MobilityResponse(FactoredResponse):
    """R = G V with V = D Q: the basis of unit forces and torques on each free body (torques of 1 N
    times the outer radius), whose motion is the symmetrised grand mobility Q itself, rows scaled
    by D (1 for a velocity, 1 / radius for an angular velocity; hydrodynamics.py). Then the Newton
    matrix factors as

        H = Q + dt Q A Q = Q (I + dt A Q),      A = D G^T K G D  (sparse over cells),

    and the gradient as g = Q z - R^T f = Q (z - D G^T f), so the Newton step H s = -g is
    (I + dt A Q) s = -(z - D G^T f): solved by GMRES, whose products cost O(p^2), where forming
    H costs O(p^3) (two p x p products per law) and its factor O(p^3) again. Preconditioned by
    the system of each cell alone (its 6 x 6 diagonal block, I + dt A_ii Q_ii): what it leaves to
    GMRES is the hydrodynamic coupling between cells, which is weak for cells several radii apart
    (issue 25: the implicit solve sparse over cells; py-spy put H's products and factor at half
    of a step of 64 cells, 384 coefficients)."""

    def __init__(self, geometry, quadratic: np.ndarray, scales: np.ndarray, rows, bodies):
        super().__init__(geometry, scales[:, None] * quadratic)
        self.quadratic, self.scales = quadratic, scales
        # G D by coordinate: (m, 2, 6) its rows on each of its bodies' 6 degrees of freedom, the
        # bodies (m, 2; -1 for none); and A's pattern (_stiffness_pattern), kept while the laws are
        self.rows, self.bodies = rows, bodies
        self._pattern = None

    @classmethod
    def of(cls, coordinates, quadratic, load_force, load_torque) -> "MobilityResponse":
        """From the coordinates (ImplicitCoordinates) of n free bodies, the symmetrised grand
        mobility ``quadratic`` (6 n, 6 n) and the basis's loads (6 n, n, 3 each), which must be
        one component each, load k on the k-th of the bodies' 6 n degrees of freedom (force x,
        y, z, torque x, y, z of each body in turn): D is one over each load's magnitude."""
        n = coordinates.n_bodies
        loads = np.concatenate([load_force, load_torque], axis=2).reshape(-1, 6 * n)
        if (quadratic.shape != (6 * n, 6 * n) or loads.shape != (6 * n, 6 * n) or np.count_nonzero(loads) != 6 * n
                or np.any(np.diag(loads) == 0.0)):
            raise ValueError(f"MobilityResponse takes the basis of one load per degree of freedom of {n} free bodies,"
                             f" in their order, and its ({6 * n}, {6 * n}) grand mobility")
        scales = 1.0 / np.diag(loads)
        on = np.maximum(coordinates.bodies, 0)[:, :, None] * 6 + np.arange(6)
        rows = np.concatenate([coordinates.unit_force, coordinates.unit_torque], axis=2) * scales[on]
        rows[coordinates.bodies < 0] = 0.0
        return cls(coordinates.rate_geometry(), quadratic, scales, rows, coordinates.bodies)

    def __matmul__(self, z):
        return self.geometry @ (self.scales * symmetric_product(self.quadratic, z))  # V z = D Q z

    def transposed(self, f):
        return symmetric_product(self.quadratic, self.scales * (self.geometry.T @ f))  # V^T y = Q D y

    def newton_step(self, z, force, stiffness, dt):
        """The Newton step s of the class docstring at coefficients ``z`` with forces ``force`` and
        [(slice, stiffness)]; None below STRUCTURED_FROM coefficients or where GMRES does not reach
        NEWTON_TOLERANCE (the caller then forms H)."""
        p = len(z)
        if p < STRUCTURED_FROM:
            return None
        stiff = self._stiffness(stiffness)
        if stiff is None:
            return None
        a, own_a = stiff  # sparse over cells: a bond or contact couples one or two
        q = self.quadratic
        n = p // 6
        cells = np.arange(n)
        own = np.eye(6) + dt * np.einsum("nij,njk->nik", own_a, q.reshape(n, 6, n, 6)[cells, :, cells])
        alone = np.linalg.inv(own)  # each cell's own system (6 x 6), inverted once per Newton step

        def each_cell(r):
            return np.einsum("nij,nj->ni", alone, r.reshape(n, 6)).ravel()

        operator = spla.LinearOperator((p, p), matvec=lambda s: s + dt * (a @ symmetric_product(q, s)),
                                       dtype=np.float64)
        preconditioner = spla.LinearOperator((p, p), matvec=each_cell, dtype=np.float64)
        rhs = -(z - self.scales * (self.geometry.T @ force))
        try:
            return gmres(operator, rhs, tolerance=NEWTON_TOLERANCE, max_iterations=min(p, 200),
                         preconditioner=preconditioner).solution
        except ConvergenceError:
            return None

    def _stiffness(self, stiffness):
        """(A = D G^T K G D as CSR, each cell's own 6 x 6 block of it (n, 6, 6)) for the laws'
        [(slice, stiffness)]. Each block of coordinates (one with a stiffness per coordinate, three
        with a 3 x 3 one: a bond's components, on the same bodies) adds B^T K B on its bodies'
        degrees of freedom, B its rows of G D: one product per block, summed into A's entries by
        one bincount over the pattern, which is the same at every Newton step of a time step and
        found once (64 cells with 1000 bonds: 0.21 ms a Newton step, where scipy's sparse products
        of G took 1.47; 256 cells with 4000 bonds: 0.69 against 3.0). None where a 3 x 3 block's
        coordinates act on different bodies, or a coordinate on its second body alone (the caller
        then forms H)."""
        signature = tuple((where, k.shape) for where, k in stiffness)
        if self._pattern is None or self._pattern[0] != signature:
            self._pattern = (signature, self._stiffness_pattern(stiffness))
        pattern = self._pattern[1]
        if pattern is None:
            return None
        groups, inverse, columns, indptr, own = pattern
        products = []
        for law, blocks, index, width in groups:
            k = stiffness[law][1]
            k = (k.reshape(-1, 1, 1) if k.ndim == 1 else k)[blocks]
            b = self.rows[index][:, :, :width // 6].reshape(len(index), index.shape[1], width)
            products.append((b.transpose(0, 2, 1) @ (k @ b)).ravel())  # B^T K B (a 3-operand einsum: 5 times slower)
        data = np.bincount(inverse, weights=np.concatenate(products), minlength=len(columns))
        n = len(self.scales) // 6
        own_a = np.where(own >= 0, data[np.maximum(own, 0)], 0.0).reshape(n, 6, 6)
        return scipy.sparse.csr_matrix((data, columns, indptr), shape=(6 * n, 6 * n)), own_a

    def _stiffness_pattern(self, stiffness):
        """A's pattern for ``_stiffness``: per law and kind of block (on one body: 6 degrees of
        freedom; on two: 12), (the law, its blocks of that kind, their coordinates, the width);
        the position among A's entries of each entry of the blocks' products; A's CSR columns and
        row pointers; the position of each cell's own 6 x 6 entries (-1: none)."""
        p = len(self.scales)
        groups, keys = [], []
        for law, (where, k) in enumerate(stiffness):
            index = np.arange(len(self.bodies))[where].reshape(-1, 1 if k.ndim == 1 else 3)
            bodies = self.bodies[index]  # (blocks, coordinates of a block, 2)
            if np.any(bodies != bodies[:, :1]) or np.any(bodies[:, 0, 0] < 0):
                return None
            two = bodies[:, 0, 1] >= 0
            for blocks, width in ((np.flatnonzero(~two), 6), (np.flatnonzero(two), 12)):
                dofs = (6 * bodies[blocks, 0, :width // 6, None] + np.arange(6)).reshape(len(blocks), width)
                groups.append((law, blocks, index[blocks], width))
                keys.append((dofs[:, :, None] * p + dofs[:, None, :]).ravel())
        unique, inverse = np.unique(np.concatenate(keys), return_inverse=True)
        indptr = np.concatenate([[0], np.cumsum(np.bincount(unique // p, minlength=p))])
        cells = np.arange(p // 6)[:, None, None] * 6
        own_keys = ((cells + np.arange(6)[:, None]) * p + cells + np.arange(6)).ravel()
        position = np.minimum(np.searchsorted(unique, own_keys), max(len(unique) - 1, 0))
        own = np.where(unique[position] == own_keys, position, -1) if len(unique) else np.full(len(own_keys), -1)
        return groups, inverse.ravel(), unique % p, indptr, own


@dataclass(frozen=True)
class ImplicitSystem:
    """values s (m,), rates r (m,) m/s, rate_response R (m, p) m/(N s) (a DenseResponse or a
    FactoredResponse), quadratic Q (p, p)
    m/(N s) and ``laws``: [(slice of the coordinates, law)] with law(s) -> (U, f, k): energies
    and forces per coordinate, and stiffnesses either per coordinate (m,) or, for laws of
    vectors (a bond's 3 components), as 3 x 3 blocks (m / 3, 3, 3)."""

    values: np.ndarray
    rates: np.ndarray
    rate_response: DenseResponse
    quadratic: np.ndarray
    laws: list

    def evaluate(self, s):
        """Energy (J) and force (N) of every coordinate at s, and [(slice, stiffness N/m)]."""
        energy, force, stiffness = np.empty_like(s), np.empty_like(s), []
        for where, law in self.laws:
            energy[where], force[where], k = law(s[where])
            stiffness.append((where, k))
        return energy, force, stiffness

    def hessian(self, stiffness, dt):
        """Q + dt R^T K R, K block diagonal by laws."""
        h = self.quadratic.copy()
        for where, k in stiffness:
            h += dt * self.rate_response.weighted_gram(where, k)
        return h

    def end_values(self, z, dt):
        return self.values + dt * (self.rates + self.rate_response @ z)

    def objective(self, z, dt):
        energy, force, stiffness = self.evaluate(self.end_values(z, dt))
        return 0.5 * z @ symmetric_product(self.quadratic, z) + np.sum(energy) / dt, force, stiffness

    def _newton_step(self, z, force, stiffness, dt, gradient):
        """The Newton step -H^-1 g: from the rate response's own structure where it has one
        (MobilityResponse), else from H formed."""
        step = self.rate_response.newton_step(z, force, stiffness, dt)
        return -solve_semidefinite(self.hessian(stiffness, dt), gradient) if step is None else step

    def _smaller_gradient(self, z, force, gradient) -> bool:
        return (np.linalg.norm(symmetric_product(self.quadratic, z) - self.rate_response.transposed(force))
                < 0.5 * np.linalg.norm(gradient))

    def solve(self, dt: float, starts) -> tuple[np.ndarray, np.ndarray]:
        """Coefficients z (p,) and forces f(s') (m,) of the step; ``starts``: candidate
        coefficients tried in order after z = 0 and the loads that hold every coordinate still
        (s' = s, admissible since the state is), until one is admissible."""
        p = self.quadratic.shape[0]
        # the holding loads only where z = 0 is not admissible (a least-squares solve of p unknowns)
        for z in [np.zeros(p), None, *starts]:
            z = self.rate_response.holding_loads(self.rates) if z is None else z
            phi, force, stiffness = self.objective(z, dt)
            if np.isfinite(phi):
                break
        else:
            raise ImplicitSolveError("no admissible start: every candidate makes a force law diverge")
        previous = np.inf
        for _ in range(MAX_ITERATIONS):
            gradient = symmetric_product(self.quadratic, z) - self.rate_response.transposed(force)
            step = self._newton_step(z, force, stiffness, dt, gradient)
            moves = dt * np.abs(self.rate_response @ step)
            # converged when the step moves no coordinate and changes the motion it causes by
            # no more than round-off (in the dissipation norm z.Q.z: a rolling cell can turn
            # about its bonds without stretching them, so coordinates alone do not tell), or by
            # no less than the step before it: Newton's steps shrink quadratically, so a step
            # that stops shrinking is the system's round-off floor (with numpy 2.4.6 and scipy
            # 1.17.1 a random 18-coefficient test system's floor was 1.5e-12 of z, its step's
            # norm 3.1e-39 repeated for 190 iterations)
            size = step @ symmetric_product(self.quadratic, step)
            if (np.all(moves <= LENGTH_TOLERANCE + 1e-13 * np.abs(self.end_values(z, dt)))
                    and (size <= 1e-24 * max(z @ symmetric_product(self.quadratic, z), 1e-300)
                         or size >= STALLED * previous)):
                z = z + step
                return z, self.evaluate(self.end_values(z, dt))[1]
            slope = gradient @ step
            t = 1.0
            while True:
                trial = z + t * step
                phi_trial, force_trial, stiffness_trial = self.objective(trial, dt)
                if np.isfinite(phi_trial) and (phi_trial <= phi + 1e-4 * t * slope or self._smaller_gradient(
                        trial, force_trial, gradient)):  # near the minimum phi is round-off, its gradient is not
                    break
                t *= 0.5
                if t < 1e-12:  # no decrease of phi or its gradient along this direction: converged
                    return z, force
            z, phi, force, stiffness, previous = trial, phi_trial, force_trial, stiffness_trial, size
        raise ImplicitSolveError(f"the joint backward-Euler solve did not converge in {MAX_ITERATIONS} Newton"
                                 f" steps (last coordinate change {moves.max():.3g} m)")
