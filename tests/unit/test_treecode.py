"""The treecode (warpbem/hydro/treecode.py): its interpolation, its tree, its error against the
direct sum, the solver with it, and the automatic choice of operator."""

import warnings

import numpy as np
import pytest

import warpbem as wb
from warpbem import runtime
from warpbem.kernels import integrals
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, choose_mode, discrete_form
from warpbem.hydro.treecode import TreecodeOptions, chebyshev_points, interaction_offsets, lagrange_basis


def grid_of_spheres(side, refinement=2, fixed=False, pitch=3.0):
    sphere = wb.mesh.sphere(1.0, refinement)
    return [wb.Body(sphere, position=(pitch * (i % side), pitch * (i // side), 1.5), fixed=fixed)
            for i in range(side * side)]


@pytest.fixture(scope="module")
def array_8x8():
    """64 spheres of 24 elements 3 radii apart: a tree of 3 levels, so the far field passes
    every stage (anterpolation, children to parents, interactions, parents to children)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        geometry = SurfaceGeometry.from_bodies(grid_of_spheres(8), 2, 1.0, True)
    poles = geometry.centres
    direct = discrete_form(BoundaryOperator(geometry, True), "matrix_free")
    rng = np.random.default_rng(7)
    q, forces = rng.standard_normal(3 * geometry.n_points), rng.standard_normal(poles.shape)
    return geometry, poles, q, forces, direct.matvec(q), direct.point_force_velocity(geometry.collocation, poles, forces)


def test_lagrange_basis_reproduces_polynomials_of_degree_below_its_order():
    """Lagrange interpolation on p points is exact for degree < p (Berrut & Trefethen 2004),
    here by the barycentric formula, also at the nodes themselves."""
    p = 6
    u = np.concatenate([np.linspace(-1, 1, 17), chebyshev_points(p)[:2]])
    basis = lagrange_basis(u, p)
    nodes = chebyshev_points(p)
    for degree in range(p):
        np.testing.assert_allclose(basis @ nodes**degree, u**degree, atol=1e-13)
    np.testing.assert_allclose(basis.sum(axis=1), 1.0, atol=1e-14)


def test_interaction_lists_and_neighbours_cover_every_leaf_exactly_once():
    """For any leaf of a 16 x 16 quadtree, its leaf neighbours plus the interaction lists of it
    and of all its ancestors, expanded to leaves, partition the whole grid (each source leaf is
    summed once: near directly or far at exactly one level)."""
    levels = 4
    n = 2**levels
    for target in [(0, 0), (5, 9), (15, 15), (8, 7)]:
        count = np.zeros((n, n), dtype=int)
        ti, tj = target
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                if 0 <= ti + di < n and 0 <= tj + dj < n:
                    count[ti + di, tj + dj] += 1
        for level in range(2, levels + 1):
            shrink = 2 ** (levels - level)
            bi, bj = ti // shrink, tj // shrink
            for di, dj in interaction_offsets((bi % 2, bj % 2)):
                si, sj = bi + di, bj + dj
                if 0 <= si < 2**level and 0 <= sj < 2**level:
                    count[si * shrink : (si + 1) * shrink, sj * shrink : (sj + 1) * shrink] += 1
        np.testing.assert_array_equal(count, 1)
    assert len(interaction_offsets((0, 0))) == 27


@pytest.mark.parametrize("tolerance", [1e-3, 1e-5])
def test_treecode_product_matches_the_direct_sum_within_its_tolerance(array_8x8, tolerance):
    """The double layer and the completion's point forces, by the treecode, against the direct
    sum of the same element integrals: relative error below the tolerance asked for
    (TreecodeOptions), with more points per box for the tighter one."""
    geometry, poles, q, forces, exact, exact_forces = array_8x8
    tree = discrete_form(BoundaryOperator(geometry, True), "treecode",
                         treecode=TreecodeOptions(tolerance=tolerance), point_sources=poles)
    assert tree.far_field.tree.levels == 3
    error = np.linalg.norm(tree.matvec(q) - exact) / np.linalg.norm(exact)
    assert 1e-12 < error < tolerance  # a far field there is, and it is accurate
    # the point forces alone: their far field is a larger share of their whole (no 1/2 q, no
    # near double layer), so their relative error runs to a few times the tolerance (treecode.py)
    velocity = tree.point_sources_velocity(forces)
    assert np.linalg.norm(velocity - exact_forces) / np.linalg.norm(exact_forces) < 3 * tolerance
    both = tree.apply(q, forces)  # one pass for both: linear, the sum of the two
    np.testing.assert_allclose(both, tree.matvec(q) + velocity.ravel(), atol=1e-12 * np.abs(both).max())


def test_stored_and_recomputed_near_fields_agree(array_8x8):
    """The near field assembled once (BLAS) and recomputed in each product are the same exact
    element integrals."""
    geometry, poles, q, *unused = array_8x8
    stored, recomputed = (discrete_form(BoundaryOperator(geometry, True), "treecode",
                                        treecode=TreecodeOptions(tolerance=1e-3, near_field=mode))
                          for mode in ("stored", "recomputed"))
    assert stored.near_field_stored and not recomputed.near_field_stored
    np.testing.assert_allclose(stored.matvec(q), recomputed.matvec(q), rtol=0, atol=1e-12)


def test_treecode_without_far_field_is_the_direct_sum():
    """A scene narrower than two leaves has no far field: every element is near."""
    geometry = SurfaceGeometry.from_bodies(grid_of_spheres(2), 2, 1.0, True)
    q = np.random.default_rng(3).standard_normal(3 * geometry.n_points)
    tree = discrete_form(BoundaryOperator(geometry, True), "treecode")
    direct = discrete_form(BoundaryOperator(geometry, True), "matrix_free")
    assert not tree.far_field.has_far_field
    np.testing.assert_allclose(tree.matvec(q), direct.matvec(q), rtol=0, atol=1e-12)


def test_solver_with_the_treecode_matches_the_dense_solve():
    """A free sphere above a 6 x 6 array of fixed ones in shear: velocities and holding loads by
    the treecode (tolerance 1e-5) within 1e-4 of the dense solve (the product's error grows by
    the system's conditioning), in about the same GMRES iterations."""
    bodies = grid_of_spheres(6, fixed=True)
    bodies.append(wb.Body(wb.mesh.sphere(1.0, 2), position=(7.4, 7.9, 3.2)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        runs = {mode: wb.solve_mobility(bodies, shear_rate=1.0, options=wb.SolverOptions(operator=mode, density_order=1, contact_refinement=0.0, treecode=TreecodeOptions(tolerance=1e-5)),
                                        forces=np.r_[np.zeros((36, 3)), [[0, 0, -1e-13]]])
                for mode in ("dense", "treecode")}
    dense, tree = runs["dense"], runs["treecode"]
    assert tree.operator_mode == "treecode"
    scale = np.abs(dense.velocity[-1]).max()
    np.testing.assert_allclose(tree.velocity[-1], dense.velocity[-1], atol=1e-4 * scale)
    np.testing.assert_allclose(tree.force[:-1], dense.force[:-1], atol=1e-4 * np.abs(dense.force[:-1]).max())
    assert abs(tree.iterations - dense.iterations) <= 3


def test_automatic_operator_is_decided_once_from_total_memory(monkeypatch):
    """"auto": dense while the matrix takes at most a quarter of the device's total memory,
    else the treecode; decided when a solver is built (given its unknowns) or at its first solve,
    and kept for the run, whatever the memory does after (a run that chose by free memory flipped to matrix-free part-way)."""
    size = 3000
    monkeypatch.setattr(runtime, "total_memory", lambda device: 4 * size**2 * 8)
    assert choose_mode(size) == "dense"
    assert choose_mode(size + 1) == "treecode"
    assert choose_mode(2 * size, "float32") == "treecode" and choose_mode(size, "float32") == "dense"

    solver = wb.MobilitySolver(shear_rate=1.0, options=wb.SolverOptions(density_order=1))
    body = [wb.Body(wb.mesh.sphere(1.0, 2), position=(0, 0, 2.0))]
    assert solver.solve(body).operator_mode == "dense"
    monkeypatch.setattr(runtime, "total_memory", lambda device: 1)  # memory "gone" after the first solve
    moved = [wb.Body(wb.mesh.sphere(1.0, 2), position=(0.5, 0, 2.0))]
    assert solver.solve(moved).operator_mode == "dense"
    assert wb.MobilitySolver(shear_rate=1.0, options=wb.SolverOptions(density_order=1)).solve(moved).operator_mode == "treecode"
    # told its unknowns, a solver decides when it is built, by the same rule, and keeps it
    monkeypatch.setattr(runtime, "total_memory", lambda device: 4 * size**2 * 8)
    built = wb.MobilitySolver(shear_rate=1.0, options=wb.SolverOptions(density_order=1), unknowns=size + 1)
    assert built.mode == "treecode" and built.operator_description == "treecode"
    assert wb.MobilitySolver(unknowns=size).mode == "dense" and wb.MobilitySolver().mode is None


def test_treecode_options_are_checked():
    for bad in (dict(tolerance=0.0), dict(tolerance=0.5), dict(tolerance=float("nan")),
                dict(near_field="sometimes"),
                dict(near_memory_fraction=2.0)):
        with pytest.raises(ValueError):
            TreecodeOptions(**bad)
    with pytest.raises(ValueError, match="operator: 'fmm' is not one of"):
        wb.SolverOptions(operator="fmm")
    geometry = SurfaceGeometry.from_bodies(grid_of_spheres(1), 2, 1.0, True)
    with pytest.raises(ValueError, match="double layer"):
        discrete_form(BoundaryOperator(geometry, True, kind="single_layer"), "treecode")
    with pytest.raises(ValueError, match="treecode only"):
        discrete_form(BoundaryOperator(geometry, True), "dense").apply(
            np.zeros(3 * geometry.n_points), np.zeros((7, 3)))


def test_interaction_matrices_follow_from_their_symmetry_class():
    """The 40 offsets of an interaction list come from 7 matrices: the kernel is equivariant
    under the square's symmetries R, K(R x, R y) = R K(x, y) H(R)^T, so the matrix of offset R c
    is the one of c with the points permuted and the components rotated. Checked against the
    matrix computed directly at every offset (order of the points from ``_proxies``)."""
    from warpbem.hydro.treecode import STRENGTHS, square_symmetries, strength_transform

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wb.ContactResolutionWarning)
        geometry = SurfaceGeometry.from_bodies(grid_of_spheres(6, refinement=1), 2, 1.0, True)
    tree = discrete_form(BoundaryOperator(geometry, True), "treecode",
                         treecode=TreecodeOptions(tolerance=1e-2)).far_field
    level = 2
    targets = tree._proxies(level, "targets")
    size = len(targets)

    def direct(offset):
        return integrals.proxy_interactions(tree.kernels, tree.device, targets, tree._proxies(level, "sources", offset),
                                            STRENGTHS)

    symmetries = square_symmetries()
    for offset, (canonical, index) in tree.offsets.items():
        pi, r = tree.permutations[level][index], symmetries[index]
        k_c = direct(canonical).reshape(size, 3, size, STRENGTHS)
        expected = np.empty_like(k_c)
        expected[np.ix_(pi, range(3), pi, range(STRENGTHS))] = np.einsum(
            "ab,tbjc,dc->tajd", r, k_c, strength_transform(r))
        np.testing.assert_allclose(direct(offset).reshape(k_c.shape), expected, atol=1e-13 * np.abs(k_c).max())
    assert len({c for c, unused in tree.offsets.values()}) == 7 and len(tree.offsets) == 40


def test_preconditioner_blocks_cut_from_the_stored_near_field_equal_the_assembled_ones(array_8x8):
    """Each body's own block, cut from the treecode's stored near field, is the block of the
    dense operator (the same element integrals and self blocks)."""
    geometry, *unused = array_8x8
    tree = discrete_form(BoundaryOperator(geometry, True), "treecode",
                         treecode=TreecodeOptions(tolerance=1e-3, near_field="stored"))
    dense = discrete_form(BoundaryOperator(geometry, True), "dense")
    bodies = [0, 9, 63]
    assert all(tree._block_from_near_field(p) is not None for p in bodies)
    cut, assembled = tree.diagonal_blocks(bodies), dense.diagonal_blocks(bodies)
    for p in bodies:
        np.testing.assert_allclose(cut[p], assembled[p], rtol=0, atol=1e-13)
