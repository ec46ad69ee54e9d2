"""GMRES on a LinearOperator, with a result object and an error on non-convergence; and GMRES on
several right-hand sides at once, whose products are matrix-matrix ones."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla


class ConvergenceError(RuntimeError):
    """GMRES stopped before reaching its tolerance; the message gives iterations and residual."""


@dataclass(frozen=True)
class GMRESResult:
    solution: np.ndarray
    iterations: int
    residual: float  # ||b - A x|| / ||b||, recomputed from the returned solution
    converged: bool


def gmres(operator: spla.LinearOperator, rhs: np.ndarray, tolerance: float = 1e-8,
          restart: int = 60, max_iterations: int = 600, initial_guess=None,
          preconditioner: spla.LinearOperator | None = None, exact_preconditioner: bool = False) -> GMRESResult:
    """Solve A x = b with SciPy's restarted GMRES (``preconditioner`` M ~ A^-1, optional);
    raise ConvergenceError if it fails. The residual checked is the true one, ||b - A x||.

    ``exact_preconditioner``: M is A^-1 up to round-off (one body, its block factored), so
    x = x0 + M (b - A x0) is the solution; GMRES runs only if its residual says otherwise. This
    saves GMRES's own set-up, a sizeable part of a small solve."""
    if not 0 < tolerance < 1:
        raise ValueError(f"GMRES tolerance must lie in (0, 1), got {tolerance!r}")
    rhs_norm = float(np.linalg.norm(rhs))
    if rhs_norm == 0.0:
        return GMRESResult(np.zeros_like(rhs), 0, 0.0, True)
    iterations = 0

    def count(_):
        nonlocal iterations
        iterations += 1

    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise ValueError(f"max_iterations must be a positive integer, got {max_iterations!r}")
    restart = min(restart, int(max_iterations))
    if exact_preconditioner and preconditioner is not None:
        if initial_guess is None:
            x = preconditioner.matvec(rhs)
        else:
            x0 = np.asarray(initial_guess, dtype=float)
            x = x0 + preconditioner.matvec(rhs - operator.matvec(x0))
        residual = float(np.linalg.norm(rhs - operator.matvec(x)) / rhs_norm)
        if np.all(np.isfinite(x)) and residual <= tolerance:
            return GMRESResult(x, 1, residual, True)
        initial_guess = x
    x, info = spla.gmres(operator, rhs, x0=initial_guess, rtol=tolerance, atol=0.0, M=preconditioner,
                         restart=restart, maxiter=-(-int(max_iterations) // restart),
                         callback=count, callback_type="pr_norm")
    residual = float(np.linalg.norm(rhs - operator.matvec(x)) / rhs_norm)
    if info != 0 or not np.all(np.isfinite(x)) or residual > 10 * tolerance:
        raise ConvergenceError(
            f"GMRES did not converge: {iterations} iterations, relative residual {residual:.3e}"
            f" (tolerance {tolerance:.1e}, restart {restart})"
        )
    return GMRESResult(x, iterations, residual, True)


# bytes of Krylov vectors a batch holds at once (restart + 1 of them per right-hand side); wider
# batches are solved in turn
BATCH_BYTES = 256 * 2**20


def gmres_batch(operator: spla.LinearOperator, rhs: np.ndarray, tolerance: float = 1e-8, restart: int = 60,
                max_iterations: int = 600, initial_guess=None, preconditioner: spla.LinearOperator | None = None,
                exact_preconditioner: bool = False) -> list[GMRESResult]:
    """Solve A X = B for the k columns of ``rhs`` (N, k) at once, as ``gmres`` does each: one
    restarted GMRES per column (Saad & Schultz 1986), right-preconditioned (A M y = b - A x0,
    x = x0 + M y, so the Arnoldi residual is the true one), whose Krylov vectors advance
    together, so the operator and the preconditioner apply to (N, k) blocks: one BLAS-3 product
    of the matrix with k columns instead of k memory-bound matrix-vector ones (a pair snapshot's
    12 loads of two refined cells: 15 iterations of 12 columns). Each column's Gram-Schmidt is
    classical, done twice (CGS2: orthogonal to round-off, as modified Gram-Schmidt, in block
    products). Columns that converge keep iterating until all do (a GMRES residual never grows).
    The results, one per column, as ``gmres``'s; ConvergenceError if any column fails."""
    if not 0 < tolerance < 1:
        raise ValueError(f"GMRES tolerance must lie in (0, 1), got {tolerance!r}")
    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise ValueError(f"max_iterations must be a positive integer, got {max_iterations!r}")
    rhs = np.asarray(rhs, dtype=float)
    x0 = np.zeros_like(rhs) if initial_guess is None else np.array(initial_guess, dtype=float)
    restart = min(restart, int(max_iterations))
    width = max(1, int(BATCH_BYTES // ((restart + 1) * rhs.shape[0] * 8)))
    results = []
    for start in range(0, rhs.shape[1], width):
        part = slice(start, start + width)
        results += _gmres_columns(operator, rhs[:, part], x0[:, part], tolerance, restart, int(max_iterations),
                                  preconditioner, exact_preconditioner)
    return results


def _gmres_columns(operator, rhs, x, tolerance, restart, max_iterations, preconditioner, exact_preconditioner):
    """``gmres_batch`` on one batch of columns (``x`` the initial guesses, overwritten)."""
    def apply(v):
        return operator.matmat(v)

    def precondition(v):
        return v if preconditioner is None else preconditioner.matmat(v)

    rhs_norm = np.linalg.norm(rhs, axis=0)
    live = rhs_norm > 0.0
    x[:, ~live] = 0.0
    iterations = np.zeros(rhs.shape[1], dtype=int)
    if exact_preconditioner and preconditioner is not None:  # as gmres: M is A^-1 up to round-off
        x = x + precondition(rhs - apply(x))
        iterations[:] = 1
    residual = np.linalg.norm(rhs - apply(x), axis=0) / np.where(live, rhs_norm, 1.0)
    todo = live & ~(residual <= tolerance)
    while np.any(todo) and iterations[todo].max() < max_iterations:
        b, cols = rhs[:, todo], np.flatnonzero(todo)
        r = b - apply(x[:, cols])
        beta = np.linalg.norm(r, axis=0)
        k, steps = len(cols), min(restart, max_iterations - int(iterations[cols].max()))
        basis = np.zeros((steps + 1,) + r.shape)
        basis[0] = r / beta
        hessenberg = np.zeros((k, steps + 1, steps))
        cosines, sines = np.zeros((k, steps)), np.zeros((k, steps))
        g = np.zeros((k, steps + 1))
        g[:, 0] = beta
        done = 0
        for j in range(steps):
            w = apply(precondition(basis[j]))
            h = np.zeros((j + 1, k))
            for _ in range(2):  # CGS2
                c = np.einsum("lnk,nk->lk", basis[: j + 1], w)
                w -= np.einsum("lnk,lk->nk", basis[: j + 1], c)
                h += c
            norm = np.linalg.norm(w, axis=0)
            basis[j + 1] = w / np.where(norm > 0.0, norm, 1.0)
            column = np.vstack([h, norm]).T  # (k, j + 2): this step's column of each Hessenberg matrix
            for i in range(j):  # the earlier Givens rotations, column by column
                column[:, i], column[:, i + 1] = (cosines[:, i] * column[:, i] + sines[:, i] * column[:, i + 1],
                                                  -sines[:, i] * column[:, i] + cosines[:, i] * column[:, i + 1])
            radius = np.hypot(column[:, j], column[:, j + 1])
            radius = np.where(radius > 0.0, radius, 1.0)
            cosines[:, j], sines[:, j] = column[:, j] / radius, column[:, j + 1] / radius
            column[:, j], column[:, j + 1] = radius, 0.0
            g[:, j + 1], g[:, j] = -sines[:, j] * g[:, j], cosines[:, j] * g[:, j]
            hessenberg[:, : j + 2, j] = column
            done = j + 1
            if np.all(np.abs(g[:, j + 1]) <= 0.5 * tolerance * rhs_norm[cols]) or np.all(norm == 0.0):
                break
        y = np.stack([np.linalg.solve(hessenberg[c, :done, :done], g[c, :done]) if np.any(g[c, :done]) else
                      np.zeros(done) for c in range(k)], axis=1)  # (done, k)
        x[:, cols] += precondition(np.einsum("lnk,lk->nk", basis[:done], y))
        iterations[cols] += done
        residual[cols] = np.linalg.norm(b - apply(x[:, cols]), axis=0) / rhs_norm[cols]
        todo = live & ~(residual <= tolerance)
    residual[~live] = 0.0
    failed = live & ~(np.isfinite(residual) & (residual <= 10 * tolerance))
    if np.any(failed) or not np.all(np.isfinite(x)):
        worst = int(np.argmax(np.where(np.isfinite(residual), residual, np.inf)))
        raise ConvergenceError(
            f"GMRES did not converge: {iterations[worst]} iterations, relative residual {residual[worst]:.3e}"
            f" (tolerance {tolerance:.1e}, restart {restart}; column {worst} of a batch of {rhs.shape[1]})")
    return [GMRESResult(x[:, c].copy(), int(iterations[c]), float(residual[c]), True) for c in range(rhs.shape[1])]
