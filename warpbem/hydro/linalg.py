"""GMRES on a LinearOperator, with a result object and an error on non-convergence."""

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
