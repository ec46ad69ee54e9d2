"""The accuracy target (``SolverOptions.accuracy``, hydro/accuracy.py, issue 27) against the exact
series: a sphere above the wall at h/a = 1.05 ... 3 and two spheres in unbounded fluid at gaps
0.1 ... 4 radii, heights and gaps between those of the error model's data
(benchmarks/error_model.py), so that these check its interpolation, not its data points.

The quantities are the model's: at the wall the free sphere's U and Omega in shear (Goldman, Cox
& Brenner 1967b), the parallel mobilities (the inverse of O'Neill 1964 / Dean & O'Neill 1963's
resistance matrix) and the normal one (Brenner 1961); U and Omega alone for a solve given no load
("shear"); a held sphere's force and torque in shear
(GCB 1967b); two spheres pushed together (Stimson &
Jeffery 1926) and towards each other (Maude 1961). The true error is the largest relative error
of these. Measured over 84 cases (benchmarks/accuracy_target.py, docs/benchmarks.md) the true
error was within the accuracy in every case the target did not warn it could not reach (8),
within its bound in 83 (not for two spheres 0.4 radius apart at 1e-3: 2.8e-4 against 1.6e-4),
and the estimate at least 0.34 of the true error and at most 6.4 times it (a free sphere at
h/a 1.1 in a solve given no load, at 1e-4).
"""

import numpy as np
import pytest

import warpbem as wb
from warpbem.hydro.accuracy import MARGINS

from .sphere_wall_series import (approaching_spheres_lambda, brenner_lambda, fixed_sphere_in_shear,
                                 free_sphere_in_shear, parallel_resistance, stimson_jeffery_lambda)

pytestmark = pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
LIBRARY_SPHERE = wb.mesh.sphere(1.0, 4)  # a user's mesh; the target rebuilds it at its k


def wall_errors(h: float, accuracy: float):
    """(the largest relative error of the five quantities, the solution's ChosenSettings)."""
    r, pi = parallel_resistance(h), np.pi
    mobility = np.linalg.inv([[6 * pi * r["Ft"], -6 * pi * r["Fr"]], [-8 * pi * r["Tt"], 8 * pi * r["Tr"]]])
    free = free_sphere_in_shear(h)
    exact = [free["U_over_gdot_h"] * h, free["Omega_over_gdot"], mobility[0, 0], mobility[1, 1],
             1.0 / (6 * pi * brenner_lambda(h))]
    solver = wb.MobilitySolver(1.0, 1.0, options=wb.SolverOptions(accuracy=accuracy))
    zero = [[0.0, 0.0, 0.0]]
    shear, fx, fz, ty = solver.solve_loads([wb.Body(LIBRARY_SPHERE, position=(0, 0, h))],
                                           [[[1, 0, 0]], [[0, 0, 1]], zero], [zero, zero, [[0, 1, 0]]],
                                           with_background=True)
    measured = [shear.velocity[0, 0], shear.angular_velocity[0, 1], fx.velocity[0, 0], ty.angular_velocity[0, 1],
                fz.velocity[0, 2]]
    return max(abs(m / e - 1) for m, e in zip(measured, exact)), shear.chosen


def shear_errors(h: float, accuracy: float):
    """A free sphere at h/a = h in shear, solved with no load: the larger relative error of U and
    Omega (GCB 1967b), the quantities the target then bounds."""
    free = free_sphere_in_shear(h)
    solution = wb.solve_mobility([wb.Body(LIBRARY_SPHERE, position=(0, 0, h))], shear_rate=1.0, viscosity=1.0,
                                 options=wb.SolverOptions(accuracy=accuracy))
    measured, exact = [solution.velocity[0, 0], solution.angular_velocity[0, 1]], [free["U_over_gdot_h"] * h,
                                                                                  free["Omega_over_gdot"]]
    return max(abs(m / e - 1) for m, e in zip(measured, exact)), solution.chosen


def fixed_errors(h: float, accuracy: float):
    """A sphere held at h/a = h in shear: the larger relative error of the fluid's force and
    torque on it, F_x = 6 pi mu a h gdot f*, T_y = 4 pi mu a^3 gdot t* (GCB 1967b; the solver
    returns the load that holds it, their negative)."""
    loads = fixed_sphere_in_shear(h)
    exact = [6 * np.pi * h * loads["f_star"], 4 * np.pi * loads["t_star"]]
    held = wb.solve_mobility([wb.Body(LIBRARY_SPHERE, position=(0, 0, h), fixed=True)], shear_rate=1.0, viscosity=1.0,
                             options=wb.SolverOptions(accuracy=accuracy))
    measured = [-held.force[0, 0], -held.torque[0, 1]]
    return max(abs(m / e - 1) for m, e in zip(measured, exact)), held.chosen


def pair_errors(gap: float, accuracy: float):
    exact = [1.0 / (6 * np.pi * f(1.0 + gap / 2)) for f in (stimson_jeffery_lambda, approaching_spheres_lambda)]
    solver = wb.MobilitySolver(0.0, 1.0, wall=False, options=wb.SolverOptions(accuracy=accuracy))
    bodies = [wb.Body(LIBRARY_SPHERE, position=(-1 - gap / 2, 0, 0)),
              wb.Body(LIBRARY_SPHERE, position=(1 + gap / 2, 0, 0))]
    zero = [[0.0, 0.0, 0.0]] * 2
    together, approaching = solver.solve_loads(bodies, [[[1, 0, 0], [1, 0, 0]], [[1, 0, 0], [-1, 0, 0]]], [zero, zero])
    measured = [together.velocity[0, 0], approaching.velocity[0, 0]]
    return max(abs(m / e - 1) for m, e in zip(measured, exact)), together.chosen


@pytest.mark.parametrize("part, gap, accuracy", [("wall", g, 1e-2) for g in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)]
                         + [("wall", g, 1e-3) for g in (0.2, 0.5, 1.0, 2.0)]
                         + [("shear", g, 1e-2) for g in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)]
                         + [("shear", g, 1e-3) for g in (0.2, 0.5, 1.0, 2.0)]
                         + [("fixed", g, 1e-2) for g in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)]
                         + [("fixed", g, 1e-3) for g in (0.2, 0.5, 1.0, 2.0)]
                         + [("pair", g, 1e-2) for g in (0.2, 0.4, 1.0, 2.0, 4.0)]
                         + [("pair", g, 1e-3) for g in (1.0, 2.0, 4.0)])
def test_the_true_error_is_within_its_bound_and_the_accuracy_and_the_estimate_within_3_2_times_it(part, gap, accuracy):
    """The target's promise: the true error within the chosen setting's bound (its estimate
    times its margin, hydro/accuracy.py MARGINS), and the bound within the accuracy asked. The
    estimate is not so pessimistic that it is useless: at most 3.2 times the true error. Of these
    cases only the two spheres 1 radius apart at 1e-2 lie outside a factor 3 (their estimate
    5.4e-3, 3.15 times the true error); of the check's 84 also the free sphere at h/a 1.1 in a
    solve given no load at 1e-4 (6.4)."""
    errors = {"wall": lambda: wall_errors(1.0 + gap, accuracy), "shear": lambda: shear_errors(1.0 + gap, accuracy),
              "fixed": lambda: fixed_errors(1.0 + gap, accuracy), "pair": lambda: pair_errors(gap, accuracy)}
    error, chosen = errors[part]()
    assert error <= chosen.error_bound <= accuracy, (error, chosen)
    assert chosen.error_estimate <= 3.2 * error, (error, chosen)


@pytest.mark.parametrize("gap, reached", [(0.05, 1e-3), (0.02, 3e-3)])
def test_two_spheres_near_contact_at_1e_3_are_within_its_reach_and_their_bound(gap, reached):
    """Two k = 4 library spheres 0.05 and 0.02 radius apart asked for 1e-3: below the gaps where
    the model's bound reaches 1e-3 (0.03 is its nearest gap, 0.02 extrapolated), so the target
    warns and takes its most accurate setting (the biquadratic density with 3 x 3 Gauss points on
    k = 6, refined; benchmarks/two_spheres.py). The pair pushed together (Stimson & Jeffery 1926)
    and towards each other (Maude 1961) then lies within 1e-3 at 0.05 radius and 3e-3 at 0.02
    (measured 5.5e-4 and 2.8e-3; with the bilinear density and the default refinement on k = 4,
    4.5e-3 and 8.6e-3), within the bound the target reports, and the estimate within 3 times the
    true error (measured 0.93 and 1.08 times it)."""
    with pytest.warns(wb.AccuracyWarning):
        error, chosen = pair_errors(gap, 1e-3)
    assert error <= reached, (error, chosen)
    assert error <= chosen.error_bound, (error, chosen)
    assert error / 3 <= chosen.error_estimate <= 3 * error, (error, chosen)


@pytest.mark.parametrize("accuracy", [1e-2, 1e-3])
def test_a_free_sphere_s_rotation_in_shear_at_h_1_5_is_within_the_accuracy(accuracy):
    """A free sphere at h/a = 1.5 in wall shear, solved with no load: its angular velocity
    against Goldman, Cox & Brenner 1967b's Omega / gdot (the exact series), within the accuracy
    asked (the estimate alone gave 1.04e-3 at 1e-3)."""
    exact = free_sphere_in_shear(1.5)["Omega_over_gdot"]
    solution = wb.solve_mobility([wb.Body(LIBRARY_SPHERE, position=(0, 0, 1.5))], shear_rate=1.0, viscosity=1.0,
                                 options=wb.SolverOptions(accuracy=accuracy))
    assert abs(solution.angular_velocity[0, 1] / exact - 1) <= accuracy


@pytest.mark.parametrize("accuracy", [1e-2, 1e-3])
def test_a_free_sphere_s_normal_drag_at_h_1_1_is_within_the_accuracy(accuracy):
    """A free sphere at h/a = 1.1 pushed towards the wall: its velocity against Brenner 1961's
    U = F / (6 pi mu a lambda) (the exact series), within the accuracy asked (the estimate alone
    gave the solve's five quantities to 1.22e-3 at 1e-3)."""
    exact = 1.0 / (6 * np.pi * brenner_lambda(1.1))
    solution = wb.solve_mobility([wb.Body(LIBRARY_SPHERE, position=(0, 0, 1.1))], viscosity=1.0,
                                 forces=[[0, 0, -1]], options=wb.SolverOptions(accuracy=accuracy))
    assert abs(-solution.velocity[0, 2] / exact - 1) <= accuracy


def test_a_solve_to_an_accuracy_is_the_solve_of_the_settings_it_chose():
    """Rebuilding the library mesh at the chosen k and solving with the chosen density order and
    refinement gives, digit for digit, what the target's solve gives."""
    body = wb.Body(LIBRARY_SPHERE, position=(0, 0, 1.3))
    target = wb.solve_mobility([body], shear_rate=1.0, viscosity=1.0, options=wb.SolverOptions(accuracy=1e-3))
    chosen = target.chosen
    assert chosen.subdivisions != LIBRARY_SPHERE.subdivisions  # the case tests a rebuilt mesh
    direct = wb.solve_mobility([wb.Body(wb.mesh.sphere(1.0, chosen.subdivisions), position=(0, 0, 1.3))],
                               shear_rate=1.0, viscosity=1.0,
                               options=wb.SolverOptions(density_order=chosen.density_order,
                                                        contact_refinement=chosen.contact_refinement))
    np.testing.assert_array_equal(target.velocity, direct.velocity)
    np.testing.assert_array_equal(target.angular_velocity, direct.angular_velocity)
    assert target.error_estimate == chosen.error_estimate and direct.error_estimate is None


def test_a_time_stepped_model_solves_each_step_to_its_accuracy():
    """``[solver] accuracy`` in a time-stepped model: a neutrally buoyant sphere at h/a = 1.1 in
    wall shear, given as the coarse k = 2 mesh, over its first frame and 2 steps. Every frame's
    velocity against GCB 1967b's at the frame's height: within the accuracy asked with the
    target, and at least 3 times closer than the mesh as given with the time-stepping defaults
    (p = 1, ratio 3); measured 1.2e-4 against 9.8e-3 at every frame."""
    from warpbem.dynamics import Flow, Model, Simulator, State, StepPolicy

    def frames(options):
        sim = Simulator(Model([wb.mesh.sphere(1.0, 2)], [False], Flow(shear_rate=1.0, viscosity=1.0),
                              solver=options, policy=StepPolicy(dt_max=1e-2, dt_min=1e-4, contact_gap=1e-3)))
        state = State(0.0, np.array([[0.0, 0.0, 1.1]]), np.array([[1.0, 0.0, 0.0, 0.0]]))
        out = [sim.frame(state)]
        for _ in range(2):
            state, frame = sim.step(state)
            out.append(frame)
        return out

    def error(frame):
        h = frame.positions[0, 2]
        return abs(frame.velocity[0, 0] / (free_sphere_in_shear(h)["U_over_gdot_h"] * h) - 1)

    targeted, as_given = frames(wb.SolverOptions(accuracy=1e-3)), frames(wb.SolverOptions())
    assert [f.steps for f in targeted] == [0, 1, 2] and targeted[-1].time > 0
    for frame, given in zip(targeted, as_given):
        assert error(frame) <= 1e-3 and error(given) > 3 * error(frame), (frame.steps, error(frame), error(given))
        # the frame records what was chosen (HDF5 columns accuracy_*): its estimate within the
        # accuracy by at least the smallest margin, a mesh finer than the one given
        assert frame.derived["accuracy_error_estimate"] * min(min(m) for m in MARGINS.values()) <= 1e-3
        assert frame.derived["accuracy_subdivisions"] > 2 and "accuracy_error_estimate" not in given.derived
