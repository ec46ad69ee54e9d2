"""GMRES on several right-hand sides at once (warpbem/hydro/linalg.py, ``gmres_batch``)."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import warpbem as wb
from warpbem.hydro import linalg


def system(rng, n=120):
    """A non-symmetric matrix whose spectrum lies near 1 (the deflated CDL's, deflated.py), with
    the exact inverses of its two diagonal blocks as block Jacobi (CompletedDoubleLayer's)."""
    a = np.eye(n) + 0.4 * rng.standard_normal((n, n)) / np.sqrt(n)
    half = n // 2
    blocks = [np.linalg.inv(a[:half, :half]), np.linalg.inv(a[half:, half:])]

    def precondition(r):
        return np.concatenate([blocks[0] @ r[:half], blocks[1] @ r[half:]])

    operator = spla.LinearOperator((n, n), matvec=lambda x: a @ x, matmat=lambda x: a @ x, dtype=float)
    return a, operator, spla.LinearOperator((n, n), matvec=precondition, matmat=precondition, dtype=float)


@pytest.mark.parametrize("preconditioned", [False, True])
def test_each_column_is_the_solution_to_the_tolerance_also_across_restarts(rng, preconditioned):
    """Every column of X solves A x = b (numpy's LU as the reference) to the tolerance, through
    several restarts (restart 4: more iterations are needed), from given initial guesses; a zero
    column gives x = 0 in no iterations; the columns agree with SciPy's GMRES on each one."""
    a, operator, preconditioner = system(rng)
    rhs = rng.standard_normal((a.shape[0], 5))
    rhs[:, 2] = 0.0
    guess = 0.1 * rng.standard_normal(rhs.shape)
    tolerance = 1e-10
    results = linalg.gmres_batch(operator, rhs, tolerance=tolerance, restart=4, initial_guess=guess,
                                 preconditioner=preconditioner if preconditioned else None)
    exact = np.linalg.solve(a, rhs)
    for c, result in enumerate(results):
        assert result.converged
        if c == 2:
            assert result.iterations == 0 and not np.any(result.solution)
            continue
        assert np.linalg.norm(rhs[:, c] - a @ result.solution) / np.linalg.norm(rhs[:, c]) <= 10 * tolerance
        assert result.residual <= 10 * tolerance
        assert result.iterations > 4  # restarted
        np.testing.assert_allclose(result.solution, exact[:, c], rtol=0, atol=1e-8 * np.abs(exact[:, c]).max())
        alone = linalg.gmres(operator, rhs[:, c], tolerance=tolerance, restart=4, initial_guess=guess[:, c],
                             preconditioner=preconditioner if preconditioned else None)
        np.testing.assert_allclose(result.solution, alone.solution, rtol=0, atol=1e-8 * np.abs(exact[:, c]).max())


def test_batches_wider_than_the_memory_share_are_solved_in_turn(rng, monkeypatch):
    """Columns beyond BATCH_BYTES of Krylov vectors go in later batches, with the same answers."""
    a, operator, preconditioner = system(rng)
    rhs = rng.standard_normal((a.shape[0], 7))
    whole = linalg.gmres_batch(operator, rhs, tolerance=1e-10, preconditioner=preconditioner)
    calls = []
    matmat = operator.matmat
    narrow = spla.LinearOperator(operator.shape, matvec=operator.matvec,
                                 matmat=lambda x: calls.append(x.shape[1]) or matmat(x), dtype=float)
    monkeypatch.setattr(linalg, "BATCH_BYTES", 2 * 61 * a.shape[0] * 8)  # two columns' Krylov vectors
    split = linalg.gmres_batch(narrow, rhs, tolerance=1e-10, preconditioner=preconditioner)
    assert max(calls) == 2
    for x, y in zip(whole, split):
        np.testing.assert_allclose(y.solution, x.solution, rtol=0, atol=1e-9 * np.abs(x.solution).max())


def test_a_column_that_does_not_converge_raises_with_its_figures(rng):
    a, operator, _ = system(rng)
    a_bad = a + np.diag(np.linspace(-2.0, 2.0, a.shape[0]))  # eigenvalues around 0: GMRES(2) stalls
    bad = spla.LinearOperator(a.shape, matvec=lambda x: a_bad @ x, matmat=lambda x: a_bad @ x, dtype=float)
    with pytest.raises(wb.ConvergenceError, match=r"did not converge: \d+ iterations, relative residual .*column"):
        linalg.gmres_batch(bad, rng.standard_normal((a.shape[0], 3)), tolerance=1e-12, restart=2, max_iterations=20)


def test_the_loads_solved_together_are_the_loads_solved_one_by_one():
    """MobilitySolver.solve_loads (one batched GMRES, the dense matrix applied to all loads at
    once) gives each load's motion as solve(background=False) does, to the GMRES tolerance: two
    spheres near the wall, unit forces and torques on each; with the background among them, its
    motion in the flow as solve(bodies) gives it."""
    s = wb.mesh.sphere(1.0, 2)
    bodies = [wb.Body(s, position=(0.0, 0.0, 1.3)), wb.Body(s, position=(2.4, 0.5, 1.6))]
    solver = wb.MobilitySolver(1.0, 1.0)
    forces, torques = np.zeros((12, 2, 3)), np.zeros((12, 2, 3))
    for k in range(12):
        (forces if k % 6 < 3 else torques)[k, k // 6, k % 3] = 1.0
    in_flow = solver.solve(bodies)
    background, *together = wb.MobilitySolver(1.0, 1.0).solve_loads(bodies, forces, torques, with_background=True)
    np.testing.assert_allclose(background.velocity, in_flow.velocity, rtol=0, atol=1e-7 * np.abs(in_flow.velocity).max())
    for f, t, batched in zip(forces, torques, together):
        alone = solver.solve(bodies, f, t, check_placement_first=False, background=False)
        for name in ("velocity", "angular_velocity"):
            a, b = getattr(batched, name), getattr(alone, name)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-7 * np.abs(b).max())
