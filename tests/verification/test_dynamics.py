"""Dynamics checks (issue 4, first part): Stokes reversibility near the wall, the Jeffery
(1922) orbit of a spheroid, symmetric passing of two spheres, gravity settling."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics import Flow, Model, Simulator, State, StepPolicy
from warpbem.forces import Gravity
from warpbem.surfaces.body import rotation_matrix


def test_free_sphere_in_wall_shear_keeps_its_height():
    """A neutrally buoyant sphere in wall-bounded shear translates parallel to the wall (GCB
    1967b; reversibility of Stokes flow forbids drift). Numerically the turning cube-sphere mesh
    leaves a vertical velocity at the discretisation level (measured |W|/U <= 1.1e-4 with the
    54-element k = 3 sphere): over 0.2 s
    (20 sphere diameters of travel, 50 steps) the height stays within 1e-3 radius."""
    a = 5e-6
    sim = Simulator(Model([wb.mesh.sphere(a, 3)], [False], Flow(shear_rate=100.0, viscosity=1e-3),
                          policy=StepPolicy(dt_max=4e-3, dt_min=1e-4)))
    state = State(0.0, np.array([[0.0, 0.0, 1.3 * a]]), np.array([[1.0, 0.0, 0.0, 0.0]]))
    heights, ratios = [], []

    def record(s, frame):
        heights.append(s.positions[0, 2])
        ratios.append(abs(frame.velocity[0, 2]) / frame.velocity[0, 0])

    state = sim.run(state, 0.2, callback=record)
    assert len(heights) == 50 and state.time == 0.2
    assert np.abs(np.array(heights) - 1.3 * a).max() < 1e-3 * a
    assert max(ratios) < 3e-4
    assert state.positions[0, 0] > 20 * a  # it did travel downstream


def test_jeffery_orbit_period_of_an_oblate_spheroid():
    """Jeffery (1922): in unbounded simple shear a spheroid of aspect ratio r tumbles with period
    T = 2 pi (r + 1/r) / gdot (thesis eq. 2.33); its axis angle phi obeys
    tan(phi) = r tan(gdot t / (r + 1/r)). Oblate r = 0.5, axis starting along z in the shear
    plane; the axis turns about y (the vorticity). Target: period within 2 %."""
    r, gdot = 0.5, 1.0
    period = 2 * np.pi * (r + 1 / r) / gdot
    sim = Simulator(Model([wb.mesh.spheroid(1.0, r, subdivisions=4)], [False], Flow(gdot, 1.0, wall=False),
                          policy=StepPolicy(dt_max=period / 150, dt_min=period / 150, contact_gap=1.0)))
    state = State(0.0, np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0, 0.0]]))
    angles, times = [0.0], [0.0]

    def record(s, frame):
        axis = rotation_matrix(s.orientations[0])[:, 2]  # symmetry axis in the world
        angle = np.arctan2(axis[0], axis[2])
        previous = angles[-1]
        angles.append(previous + (angle - previous + np.pi) % (2 * np.pi) - np.pi)  # unwrap
        times.append(s.time)

    sim.run(state, 1.1 * period, callback=record)
    angles, times = np.abs(np.array(angles)), np.array(times)
    measured = np.interp(2 * np.pi, angles, times)  # time for the axis to turn once
    assert abs(measured / period - 1) < 0.02, (measured, period)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_two_spheres_pass_symmetrically_in_unbounded_shear():
    """Two equal free spheres on either side of the zero-velocity plane pass each other. Stokes
    flow is symmetric under the point reflection about their midpoint, so the trajectories are
    mirror images (the midpoint stays put), and reversible: each sphere leaves on the streamline
    it came in on (smooth spheres, no contact forces; Batchelor & Green 1972)."""
    sim = Simulator(Model([wb.mesh.sphere(1.0, 3)] * 2, [False, False], Flow(1.0, 1.0, wall=False),
                          policy=StepPolicy(dt_max=0.4, dt_min=0.1, contact_gap=0.4)))
    state = State(0.0, np.array([[-3.0, 0.0, 0.8], [3.0, 0.0, -0.8]]), np.tile([1.0, 0, 0, 0], (2, 1)))
    heights = []
    state = sim.run(state, 8.0, callback=lambda s, frame: heights.append(s.positions[0, 2]))
    np.testing.assert_allclose(state.positions[0], -state.positions[1], atol=1e-5)
    assert state.positions[0, 0] > 2.0  # they did pass
    assert max(heights) > 0.9  # lifted over each other on the way
    assert abs(state.positions[0, 2] - 0.8) < 0.01  # and back on the incoming streamline


def test_heavy_cell_settles_at_brenners_speed_and_the_step_shrinks():
    """A cell of 1050 kg/m^3 in plasma of 1000 kg/m^3 sinks (thesis fig. 2.5) at the speed its
    buoyant weight gives against Brenner's (1961) wall-corrected drag, W = F / (6 pi mu a
    lambda(h)); the adaptive step shortens as the gap falls below contact_gap, and it never
    touches the wall. Each frame's velocity is the one at its own height (down to h/a = 1.11,
    where the k = 4 sphere's squeeze drag is 1.5 % off: docs/validation.md)."""
    from .sphere_wall_series import brenner_lambda

    a, mu = 5e-6, 1e-3
    m = wb.mesh.sphere(a, 4)
    gravity = Gravity([1050.0], 1000.0, 9.81)
    sim = Simulator(Model([m], [False], Flow(0.0, mu), interactions=[gravity],
                          policy=StepPolicy(dt_max=0.5, dt_min=0.05, contact_gap=1.5e-6)))
    weight = sim.model.bound("gravity").force[0, 2]
    assert np.isclose(weight, -50 * 9.81 * m.volume())
    state = State(0.0, np.array([[0.0, 0.0, 7.0e-6]]), np.array([[1.0, 0, 0, 0]]))
    steps = []

    def record(s, frame):
        steps.append((s.positions[0, 2], frame.dt, frame.velocity[0, 2], frame.force[0, 2]))

    sim.run(state, 3.0, callback=record)
    z, dt, w, force = map(np.array, zip(*steps))
    assert np.all(force == weight)
    expected = np.array([weight / (6 * np.pi * mu * a * brenner_lambda(h / a)) for h in z])
    np.testing.assert_allclose(w, expected, rtol=0.02)
    assert z.min() > a and np.all(np.diff(z) < 0)  # sinking, never touching
    assert dt[-1] < dt[0]  # the step shrank near the wall


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")  # it ends up close, on purpose
def test_a_step_that_would_cross_the_wall_is_retried_shorter():
    """A cell pushed hard at the wall with a step far too long for it: the Heun predictor (or
    the step's end) would cross the wall, so the step is halved until it does not, and the cell
    never touches. Too short a dt_min to ever allow that is an error that says so."""
    a = 5e-6
    m = wb.mesh.sphere(a, 2)
    heavy = Gravity([1.0e5], 1000.0, 9.81)
    sim = Simulator(Model([m], [False], Flow(0.0, 1e-3), interactions=[heavy],
                          policy=StepPolicy(dt_max=5.0, dt_min=1e-3, contact_gap=1e-9)))
    state = State(0.0, np.array([[0.0, 0.0, 1.4 * a]]), np.array([[1.0, 0, 0, 0]]))
    new, frame = sim.step(state)
    assert frame.dt < 5.0 and new.time == frame.dt and new.positions[0, 2] > a
    stiff = Simulator(Model([m], [False], Flow(0.0, 1e-3), interactions=[heavy],
                            policy=StepPolicy(dt_max=5.0, dt_min=5.0, contact_gap=1e-9)))
    with pytest.raises(wb.PlacementError, match="even the smallest step"):
        stiff.step(state)
