"""Time integration: quaternion rotation and the order of the Euler and Heun schemes."""

import numpy as np
import pytest

from warpbem.dynamics import integrate
from warpbem.surfaces.body import rotation_matrix


def test_rotation_is_exact_for_constant_angular_velocity():
    q0 = np.array([[1.0, 0.0, 0.0, 0.0]])
    omega = np.array([[0.0, 2.0, 0.0]])
    q = integrate.rotate(q0, omega, 0.25)  # 0.5 rad about y
    expected = np.array([[np.cos(0.5), 0, np.sin(0.5)], [0, 1, 0], [-np.sin(0.5), 0, np.cos(0.5)]])
    np.testing.assert_allclose(rotation_matrix(q[0]), expected, atol=1e-14)
    # composing many small turns about a fixed axis is the same turn
    q_small = q0
    for _ in range(100):
        q_small = integrate.rotate(q_small, omega, 0.0025)
    np.testing.assert_allclose(q_small, q, atol=1e-13)


@pytest.mark.parametrize("scheme, order", [("euler", 1), ("heun", 2)])
def test_schemes_converge_at_their_order(scheme, order):
    """Body moving with U = (-y, x, 0) (a circle): error at t = 1 against the exact rotation."""
    def velocities(state):
        x, y = state.positions[:, 0], state.positions[:, 1]
        return np.stack([-y, x, 0 * x], axis=1), np.zeros((1, 3))

    errors = []
    for n in (20, 40, 80):
        state = integrate.State(0.0, np.array([[1.0, 0.0, 0.0]]), np.array([[1.0, 0, 0, 0]]))
        for _ in range(n):
            state, _ = integrate.step(state, velocities, 1.0 / n, scheme)
        errors.append(np.linalg.norm(state.positions[0] - [np.cos(1.0), np.sin(1.0), 0.0]))
    observed = np.log2(errors[0] / errors[1]), np.log2(errors[1] / errors[2])
    assert min(observed) > order - 0.2, observed
    with pytest.raises(ValueError, match="scheme"):
        integrate.step(state, velocities, 0.1, "rk4")
