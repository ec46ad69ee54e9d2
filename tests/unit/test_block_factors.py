"""The store of free bodies' block factors (warpbem/hydro/block_factors.py): a body moved along
the wall, or a pair of cells moved together, takes its block's LU from the store instead of
factoring anew, and its motion is that of a solver without the store (the blocks are equal to
round-off: their entries depend on the elements relative to the body and its height alone); a
body at another height, or with a neighbour close enough to refine its elements, misses; the
store keeps no more than its budget."""

import numpy as np

import warpbem as wb
from warpbem.hydro.block_factors import BlockFactors
from warpbem.hydro.mobility import MobilitySolver

SPHERE = wb.mesh.sphere(1.0, 2)


def solved(solver, positions):
    bodies = [wb.Body(SPHERE, position=p) for p in positions]
    solution = solver.solve(bodies, forces=np.tile([1.0, 0.0, 0.0], (len(bodies), 1)), factor_every_body=True)
    return np.concatenate([solution.velocity.ravel(), solution.angular_velocity.ravel()])


def test_a_body_moved_along_the_wall_takes_its_factors_and_its_motion_is_unchanged():
    solver = MobilitySolver(shear_rate=1.0)
    solved(solver, [(0.0, 0.0, 1.3)])
    assert (solver._factors.hits, solver._factors.misses) == (0, 1)
    moved = solved(solver, [(3.7, -1.9, 1.3)])
    assert (solver._factors.hits, solver._factors.misses) == (1, 1)
    # one body whose block is factored: the preconditioner is the exact inverse, so the motion
    # differs only by the round-off between the two blocks
    np.testing.assert_allclose(moved, solved(MobilitySolver(shear_rate=1.0, keep_systems=False), [(3.7, -1.9, 1.3)]),
                               rtol=1e-10, atol=1e-12)
    solved(solver, [(3.7, -1.9, 1.35)])  # another height: another block
    assert (solver._factors.hits, solver._factors.misses) == (1, 2)


def test_a_pair_moved_together_takes_both_factors_and_a_close_neighbour_refines_a_new_block():
    solver = MobilitySolver(shear_rate=1.0)
    far = [(0.0, 0.0, 1.3), (2.5, 0.4, 1.4)]
    solved(solver, far)
    assert (solver._factors.hits, solver._factors.misses) == (0, 2)
    moved = solved(solver, [(5.0, 1.0, 1.3), (7.5, 1.4, 1.4)])
    assert (solver._factors.hits, solver._factors.misses) == (2, 2)
    fresh = solved(MobilitySolver(shear_rate=1.0, keep_systems=False), [(5.0, 1.0, 1.3), (7.5, 1.4, 1.4)])
    tolerance = MobilitySolver(shear_rate=1.0).options.tolerance  # GMRES's relative residual
    np.testing.assert_allclose(moved, fresh, rtol=0, atol=100 * tolerance * np.abs(fresh).max())
    # 0.05 radii apart: the contact refinement gives both cells new elements near each other
    solved(solver, [(0.0, 0.0, 1.3), (2.05, 0.0, 1.3)])
    assert (solver._factors.hits, solver._factors.misses) == (2, 4)


def test_the_store_drops_the_least_recently_used_factors_beyond_its_budget():
    block = (np.zeros((10, 10)), np.zeros(10, dtype=np.int32))  # 840 bytes
    store = BlockFactors(budget=2000)
    store.put("a", block)
    store.put("b", block)
    assert store.get("a") is block  # "a" used last: "b" goes first
    store.put("c", block)
    assert store.get("b") is None and store.get("a") is block and store.get("c") is block
    store.put("large", (np.zeros((20, 20)), np.zeros(20)))  # 3360 bytes, over the whole budget: not kept
    assert store.get("large") is None and store.get("a") is block
