"""The joint backward-Euler step (warpbem/dynamics/implicit.py) with its rate response held
whole or factored over cells (R = G V, the path of many cells)."""

import numpy as np

from warpbem.dynamics.implicit import DenseResponse, FactoredResponse, ImplicitSystem
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
    Newton matrix's R^T K R is the whole one's for 3 x 3 and per-coordinate stiffnesses."""
    rng = np.random.default_rng(3)
    cells, bonds = 3, 12
    owner = np.repeat(np.arange(cells), bonds // cells)
    unit_force, unit_torque = np.zeros((3 * bonds, cells, 3)), np.zeros((3 * bonds, cells, 3))
    arm = rng.normal(size=(bonds, 3)) * 5e-6
    for g, b in enumerate(owner):
        for i in range(3):
            unit_force[3 * g + i, b, i] = 1.0
            unit_torque[3 * g + i, b] = np.cross(arm[g], np.eye(3)[i])
    coordinates = ImplicitCoordinates(rng.normal(size=3 * bonds) * 40e-9, unit_force, unit_torque)
    p = 6 * cells
    mobility = rng.normal(size=(p, p)) * 1e6
    mobility = mobility @ mobility.T / p + 1e6 * np.eye(p)  # m/(N s), SPD
    velocity = mobility.reshape(p, cells, 6)[:, :, :3]
    angular = mobility.reshape(p, cells, 6)[:, :, 3:] / 5e-6
    factored = FactoredResponse.of(coordinates, velocity, angular)
    whole = np.array([coordinates.rates(u, w) for u, w in zip(velocity, angular)]).T
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
