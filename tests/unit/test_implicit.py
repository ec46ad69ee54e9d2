"""The joint backward-Euler step (warpbem/dynamics/implicit.py) with its rate response held
whole or factored over cells (R = G V, the path of many cells), and its Newton step solved
without forming the Newton matrix (MobilityResponse)."""

import numpy as np
import pytest

from warpbem.dynamics.implicit import (STRUCTURED_FROM, DenseResponse, FactoredResponse, ImplicitSystem,
                                       MobilityResponse, symmetric_product)
from warpbem.forces.bond_model import BondLaws
from warpbem.forces.interaction import ImplicitCoordinates


class Springs(BondLaws):
    spring_constant, equilibrium_length, compression = 0.1, 30e-9, False


def test_the_factored_response_takes_the_same_step_as_the_whole_one():
    """Twelve stiff bonds (100 dyn/cm) on three cells, each bond moving with its own cell only
    (G sparse over cells), the basis's motion V random but fixed (seeded) and its dissipation Q =
    V^T M V positive definite: the step from R = G V held whole (DenseResponse) and never formed
    (FactoredResponse) is the same minimiser of the same convex Phi, to the Newton tolerance;
    the hand-made G is also the one FactoredResponse.of builds from the unit loads, and the
    Newton matrix's R^T K R is the whole one's for 3 x 3 and per-coordinate stiffnesses. The
    coordinates, held per coordinate on its own cell, give the rates and loads of the unit loads
    on every cell."""
    rng = np.random.default_rng(3)
    cells, bonds = 3, 12
    owner = np.repeat(np.arange(cells), bonds // cells)
    unit_force, unit_torque = np.zeros((3 * bonds, cells, 3)), np.zeros((3 * bonds, cells, 3))
    arm = rng.normal(size=(bonds, 3)) * 5e-6
    for g, b in enumerate(owner):
        for i in range(3):
            unit_force[3 * g + i, b, i] = 1.0
            unit_torque[3 * g + i, b] = np.cross(arm[g], np.eye(3)[i])
    carriers = np.stack([np.repeat(owner, 3), np.full(3 * bonds, -1)], axis=1)
    on_own_cell = np.arange(3 * bonds), np.repeat(owner, 3)
    coordinates = ImplicitCoordinates(rng.normal(size=3 * bonds) * 40e-9, carriers,
                                      np.stack([unit_force[on_own_cell], np.zeros((3 * bonds, 3))], axis=1),
                                      np.stack([unit_torque[on_own_cell], np.zeros((3 * bonds, 3))], axis=1), cells)
    p = 6 * cells
    mobility = rng.normal(size=(p, p)) * 1e6
    mobility = mobility @ mobility.T / p + 1e6 * np.eye(p)  # m/(N s), SPD
    velocity = mobility.reshape(p, cells, 6)[:, :, :3]
    angular = mobility.reshape(p, cells, 6)[:, :, 3:] / 5e-6
    factored = FactoredResponse.of(coordinates, velocity, angular)
    # R by virtual work from the loads on every cell, the coordinates' own rates alike
    whole = np.einsum("cbi,pbi->cp", unit_force, velocity) + np.einsum("cbi,pbi->cp", unit_torque, angular)
    np.testing.assert_allclose(np.array([coordinates.rates(u, w) for u, w in zip(velocity, angular)]).T, whole,
                               rtol=1e-12, atol=1e-12 * np.abs(whole).max())
    magnitudes = rng.normal(size=3 * bonds) * 1e-12
    loads = coordinates.loads(magnitudes)  # and the loads of forces along them, by the same virtual work
    np.testing.assert_allclose(loads.force, np.einsum("c,cbi->bi", magnitudes, unit_force), rtol=1e-12, atol=1e-30)
    np.testing.assert_allclose(loads.torque, np.einsum("c,cbi->bi", magnitudes, unit_torque), rtol=1e-12, atol=1e-36)
    np.testing.assert_array_equal(coordinates.dense_loads()[0], unit_force)
    np.testing.assert_array_equal(coordinates.dense_loads()[1], unit_torque)
    np.testing.assert_allclose(factored.geometry @ factored.motion, whole, rtol=1e-12, atol=1e-12 * np.abs(whole).max())
    blocks = rng.normal(size=(bonds, 3, 3))
    blocks = blocks @ blocks.transpose(0, 2, 1)  # a bond's 3 x 3 stiffness, symmetric
    every = slice(0, 3 * bonds)
    for k in (blocks, rng.uniform(size=3 * bonds)):  # per bond, per coordinate
        dense = DenseResponse(whole).weighted_gram(every, k)
        np.testing.assert_allclose(factored.weighted_gram(every, k), dense, rtol=1e-10, atol=1e-10 * np.abs(dense).max())
    quadratic = mobility
    rates = rng.normal(size=3 * bonds) * 1e-6
    steps = []
    for response in (DenseResponse(whole), factored):
        system = ImplicitSystem(coordinates.values, rates, response, quadratic, [(slice(0, 3 * bonds), Springs().law)])
        steps.append(system.solve(1e-4, []))
    (z0, f0), (z1, f1) = steps
    np.testing.assert_allclose(z1, z0, rtol=1e-8, atol=1e-8 * np.abs(z0).max())
    np.testing.assert_allclose(f1, f0, rtol=1e-8, atol=1e-8 * np.abs(f0).max())
    assert np.abs(f0).max() > 1e-12  # the bonds carry load: the step is not the trivial one


def test_the_newton_step_without_its_matrix_is_the_formed_one():
    """H = Q + dt Q A Q = Q (I + dt A Q) with A = D G^T K G D when the basis's motion is V = D Q
    (implicit.MobilityResponse): for 24 cells (144 coefficients, above STRUCTURED_FROM) with
    three stiff bonds each on their lower half, a grand mobility Q of self blocks and couplings
    that fall as (a / r)^3 over a 25 um patch (seeded, symmetric positive definite), the Newton
    step from GMRES on (I + dt A Q) s = -(z - D G^T f) is the step -H^-1 g of H formed and
    factored (FactoredResponse with V = D Q), to 1e-9; the whole backward-Euler solve gives the
    same coefficients and forces to 1e-8; and the GMRES path was taken (the formed one is
    patched to fail loudly)."""
    rng = np.random.default_rng(7)
    cells, radius, mu = 24, 5e-6, 1e-3
    p = 6 * cells
    assert p >= STRUCTURED_FROM
    grid = np.array([(i % 6, i // 6) for i in range(cells)]) * 25e-6
    stokes = 1.0 / (6 * np.pi * mu * radius)  # m/(N s)
    quadratic = np.kron(np.eye(cells), np.diag([0.3, 0.3, 0.05, 0.3, 0.3, 0.6]) * stokes)
    for i in range(cells):
        for j in range(i):
            coupling = rng.normal(size=(6, 6)) * 0.3 * stokes * (radius / np.linalg.norm(grid[i] - grid[j])) ** 3
            quadratic[6 * i:6 * i + 6, 6 * j:6 * j + 6] = coupling
            quadratic[6 * j:6 * j + 6, 6 * i:6 * i + 6] = coupling.T
    assert np.linalg.eigvalsh(quadratic).min() > 0
    bonds = 3 * cells
    unit_force, unit_torque = np.zeros((3 * bonds, cells, 3)), np.zeros((3 * bonds, cells, 3))
    for g in range(bonds):
        arm = rng.normal(size=3) * 1e-6 - np.array([0.0, 0.0, radius])
        for i in range(3):
            unit_force[3 * g + i, g // 3, i] = 1.0
            unit_torque[3 * g + i, g // 3] = np.cross(arm, np.eye(3)[i])
    carriers = np.stack([np.arange(3 * bonds) // 9, np.full(3 * bonds, -1)], axis=1)
    on_own_cell = np.arange(3 * bonds), carriers[:, 0]
    coordinates = ImplicitCoordinates(rng.normal(size=3 * bonds) * 40e-9, carriers,
                                      np.stack([unit_force[on_own_cell], np.zeros((3 * bonds, 3))], axis=1),
                                      np.stack([unit_torque[on_own_cell], np.zeros((3 * bonds, 3))], axis=1), cells)
    load_force, load_torque = np.zeros((p, cells, 3)), np.zeros((p, cells, 3))
    for b in range(cells):
        for i in range(3):
            load_force[6 * b + i, b, i], load_torque[6 * b + 3 + i, b, i] = 1.0, radius
    structured = MobilityResponse.of(coordinates, quadratic, load_force, load_torque)
    np.testing.assert_array_equal(structured.scales.reshape(cells, 6), [[1.0] * 3 + [1.0 / radius] * 3] * cells)
    with pytest.raises(ValueError, match="one load per degree of freedom"):
        MobilityResponse.of(coordinates, quadratic, load_force[::-1], load_torque[::-1])
    formed = FactoredResponse(structured.geometry, structured.motion)
    rates = rng.normal(size=3 * bonds) * 1e-5
    laws = [(slice(0, 3 * bonds), Springs().law)]
    dt = 1e-4
    system = ImplicitSystem(coordinates.values, rates, structured, quadratic, laws)
    z = rng.normal(size=p) * 1e-12
    _, force, stiffness = system.objective(z, dt)
    gradient = quadratic @ z - structured.transposed(force)
    step = structured.newton_step(z, force, stiffness, dt)
    expected = -np.linalg.solve(system.hessian(stiffness, dt), gradient)
    np.testing.assert_allclose(step, expected, rtol=0, atol=1e-9 * np.abs(expected).max())

    def refuse(*args):
        raise AssertionError("the structured response formed its Newton matrix")

    solves = []
    for response in (structured, formed):
        system = ImplicitSystem(coordinates.values, rates, response, quadratic, laws)
        if response is structured:
            object.__setattr__(system, "hessian", refuse)  # a frozen dataclass: on this instance only
        solves.append(system.solve(dt, []))
    (z0, f0), (z1, f1) = solves
    np.testing.assert_allclose(z0, z1, rtol=0, atol=1e-8 * np.abs(z1).max())
    np.testing.assert_allclose(f0, f1, rtol=0, atol=1e-8 * np.abs(f1).max())
    assert np.abs(f1).max() > 1e-12


def test_the_symmetric_product_is_the_matrix_product():
    """symmetric_product (BLAS symv from STRUCTURED_FROM coefficients on, reading one triangle)
    gives Q x to round-off for a symmetric Q, below and above that size; a wrong triangle or
    storage order would give another matrix's product."""
    rng = np.random.default_rng(3)
    for p in (STRUCTURED_FROM - 1, STRUCTURED_FROM, 3 * STRUCTURED_FROM + 5):
        a = rng.normal(size=(p, p))
        q = 0.5 * (a + a.T)
        x = rng.normal(size=p)
        np.testing.assert_allclose(symmetric_product(q, x), q @ x, rtol=0, atol=1e-12 * np.abs(q @ x).max())


def test_the_stiffness_matrix_by_blocks_is_the_sparse_product():
    """A = D G^T K G D of the Newton step (MobilityResponse._stiffness: one product per block of
    coordinates, summed by its pattern) against scipy's sparse products of G's rows: bonds (3 x 3
    stiffness) on one cell each, and contacts (a stiffness per coordinate) between two cells or a
    cell and the wall, on 24 cells (seeded); and each cell's own 6 x 6 block of it. A second call
    with other stiffnesses reuses the pattern and still matches; a 3 x 3 block whose coordinates
    act on different bodies, or a coordinate on its second body alone, is refused (None: the caller
    forms H)."""
    rng = np.random.default_rng(11)
    cells, bonds, contacts = 24, 40, 30
    p = 6 * cells
    owner = rng.integers(cells, size=bonds)
    pairs = np.stack([rng.integers(cells, size=contacts), rng.integers(-1, cells, size=contacts)], axis=1)
    pairs[pairs[:, 0] == pairs[:, 1], 1] = -1  # a contact with the wall
    bodies = np.concatenate([np.stack([np.repeat(owner, 3), np.full(3 * bonds, -1)], axis=1), pairs])
    m = len(bodies)
    unit_force, unit_torque = rng.normal(size=(m, 2, 3)), rng.normal(size=(m, 2, 3)) * 5e-6
    unit_force[bodies < 0], unit_torque[bodies < 0] = 0.0, 0.0
    coordinates = ImplicitCoordinates(rng.normal(size=m) * 1e-8, bodies, unit_force, unit_torque, cells)
    load_force, load_torque = np.zeros((p, cells, 3)), np.zeros((p, cells, 3))
    for b in range(cells):
        for i in range(3):
            load_force[6 * b + i, b, i], load_torque[6 * b + 3 + i, b, i] = 1.0, 5e-6
    a = rng.normal(size=(p, p))
    response = MobilityResponse.of(coordinates, a @ a.T, load_force, load_torque)
    scale = np.diag(response.scales)
    for _ in range(2):
        blocks = rng.normal(size=(bonds, 3, 3))
        stiffness = [(slice(0, 3 * bonds), blocks @ blocks.transpose(0, 2, 1)),
                     (slice(3 * bonds, m), rng.uniform(size=contacts))]
        expected = scale @ sum(response.stiffness_gram(where, k) for where, k in stiffness).toarray() @ scale
        matrix, own = response._stiffness(stiffness)
        np.testing.assert_allclose(matrix.toarray(), expected, rtol=0, atol=1e-12 * np.abs(expected).max())
        own_expected = np.array([expected[6 * c:6 * c + 6, 6 * c:6 * c + 6] for c in range(cells)])
        np.testing.assert_allclose(own, own_expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    bodies[1, 0] = (bodies[1, 0] + 1) % cells  # a bond's second component on another cell
    split = MobilityResponse.of(ImplicitCoordinates(coordinates.values, bodies, unit_force, unit_torque, cells),
                                a @ a.T, load_force, load_torque)
    assert split._stiffness(stiffness) is None
    bodies[3 * bonds] = (-1, max(bodies[3 * bonds, 1], 0))  # a contact held on its second body alone
    bodies[1, 0] = bodies[0, 0]
    second_only = MobilityResponse.of(ImplicitCoordinates(coordinates.values, bodies, unit_force, unit_torque, cells),
                                      a @ a.T, load_force, load_torque)
    assert second_only._stiffness(stiffness) is None
