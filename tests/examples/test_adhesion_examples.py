"""The adhesion and sweep scripts of examples/ run at a small size and give their headline numbers
(issue 26 item 3)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tests.examples.test_examples import example
from tests.verification.sphere_wall_series import brenner_lambda, free_sphere_in_shear

# scenes/fig4_09_11_soft_bonds.toml (thesis Table 4.1, fig. 4.9's cell), written out here so that
# the expectations do not come from the code under test
RADIUS, HEIGHT, SHEAR_RATE = 5e-6, 5.24e-6, 100.0        # m, m, 1/s
SHEAR_MODULUS, POISSON_RATIO = 4e3, 0.33                 # Pa, 1


def test_rolling_cell(tmp_path, capsys):
    """Before any bond the cell moves as a free sphere at h/a = 1.048: U = X gdot h with X from
    the exact series of Goldman, Cox & Brenner (1967b) (tests/verification/sphere_wall_series.py;
    the collocation at a gap of 0.048 a errs by +1.4 % with k = 2, +1.0 % with k = 3 and +0.8 % with
    k = 4); bonds then form and slow it well below that; its contact area is the Hertz disc
    pi a_s^2, a_s = (3 F R / 4 E*)^(1/3), E* = 2 G (1 + nu) / (1 - nu^2) (thesis eq. 4.9) of the
    frame's normal bond force F."""
    ex = example("rolling_cell")
    # 4 ms at the kinetics' own step (k dt <= 0.1: 2.7e-4 s) instead of the scene's 2e-5 s
    frames = ex.main(tmp_path, end=0.004, subdivisions=2, dt_max=2.5e-4)
    assert "bonds" in capsys.readouterr().out and frames["chart"].stat().st_size > 10_000
    free = free_sphere_in_shear(HEIGHT / RADIUS)["U_over_gdot_h"] * SHEAR_RATE * HEIGHT  # 345.6 um/s
    t, u, x, bonds = frames["time"], frames["velocity"], frames["x"], frames["bonds"]
    assert bonds[0] == 0 and u[0] == pytest.approx(free, rel=0.02)
    # the last half of the run, bound: the mean velocity along the flow is well below the free one
    late = t >= t[-1] / 2
    mean_late = (x[-1] - x[late][0]) / (t[-1] - t[late][0])
    assert np.all(bonds[late] > 0) and mean_late < 0.85 * free
    # Hertz (eq. 4.9), written out independently of warpbem/forces/hertz.py. The library takes R as
    # the radius of the sphere of the k = 2 mesh's volume, 5.8e-4 below 5 um: the area, ~ R^(2/3),
    # by 3.9e-4
    e_star = 2 * SHEAR_MODULUS * (1 + POISSON_RATIO) / (1 - POISSON_RATIO**2)
    hertz_area = np.pi * (3 * frames["contact_force"] * RADIUS / (4 * e_star)) ** (2 / 3)
    np.testing.assert_allclose(frames["contact_area"], hertz_area, rtol=5e-4, atol=0)
    assert frames["contact_area"][-1] > 0 and frames["contact_force"][-1] > 0


def brenner_descent(density_difference, end, height=7.5e-6, radius=5e-6, viscosity=1.2e-3, g=9.80665):
    """dz (m) of a sphere settling from ``height`` for ``end`` s under its buoyant weight
    (4/3) pi a^3 drho g, at dz/dt = -F / (6 pi mu a lambda(z / a)), lambda Brenner's (1961)
    exact wall correction (tests/verification/sphere_wall_series.py), integrated to 1e-12."""
    force = 4 / 3 * np.pi * radius**3 * density_difference * g
    path = solve_ivp(lambda t, z: [-force / (6 * np.pi * viscosity * radius * brenner_lambda(z[0] / radius))],
                     (0.0, end), [height], rtol=1e-12, atol=1e-20)
    return path.y[0, -1] - height


def test_sweep_on_dask(tmp_path, capsys):
    """Two points on a local Dask cluster (two spawned worker processes): a 5 um cell settling
    7.5 um above the wall in still plasma, in fluids of 1000 and 1025 kg/m^3. Each descent is
    Brenner's (1961) exact wall-corrected Stokes settling integrated over the run (the k = 3 mesh
    errs by +8e-4 at h/a = 1.5; 2e-3 allowed), and their ratio is the buoyancy ratio 50 / 25 = 2 to
    the change of lambda over the descent (the Brenner ratio 1.99906 to 1e-4; 2 to 1e-3)."""
    ex = example("sweep_on_dask")
    end = 0.01
    rows = ex.main(tmp_path, end=end, subdivisions=3)
    out = capsys.readouterr().out
    assert "W ratio" in out and (tmp_path / "summary.csv").exists()
    assert (tmp_path / "settling.png").stat().st_size > 10_000
    assert [float(r["physics.fluid_density"]) for r in rows] == [1000.0, 1025.0]
    dz = [float(r["free_dz_m"]) for r in rows]
    expected = [brenner_descent(50.0, end), brenner_descent(25.0, end)]  # -7.075 and -3.539 nm
    assert dz == pytest.approx(expected, rel=2e-3)
    assert dz[0] / dz[1] == pytest.approx(expected[0] / expected[1], rel=1e-4)
    assert dz[0] / dz[1] == pytest.approx(2.0, rel=1e-3)
    assert [r["settling_velocity"] for r in rows] == pytest.approx([-d / end for d in dz], rel=1e-12)


# REGRESSION reference, not a published one: the states that this code's own earlier run of the
# full diagram (scenes/README.md, "The adhesion state diagram": 5 x 4 runs of 0.2 s at k = 3, V /
# V_free 0.0015, 0.67, 0.11 and 0.76 at these points) gave at the four points of the small one.
# Chang, Tees & Hammer (2000) publish the diagram's shape only for their own model's parameters,
# so the published part checked below is the ordering of the states, not these labels.
FULL_DIAGRAM_EARLIER_RUN = {(1.0, 0.1e-10): "firm adhesion", (1.0, 1.2e-10): "no adhesion",
                            (100.0, 0.1e-10): "rolling", (100.0, 1.2e-10): "no adhesion"}


def test_state_diagram_regression_against_the_full_diagrams_earlier_run(tmp_path, capsys):
    """Regression test: a 2 x 2 state diagram of 10 ms runs at k = 2 (mobility snapshots on a
    10 nm lattice: 9e-4 of the velocity, docs/adhesion.md) gives the states this code's run of
    the full diagram gave at its four points (``FULL_DIAGRAM_EARLIER_RUN``): firm adhesion at
    slow rupture and short reach, rolling where rupture is 100 times faster, no adhesion at the
    long reactive compliance, each with a margin of the rule's thresholds. Independent of that
    run: Bell's rupture rate k_r = k_r0 exp(r0 F / kT) (thesis eq. 4.1) grows with k_r0 and with
    r0, so V / V_free grows along both axes (the shape Chang, Tees & Hammer 2000 publish)."""
    ex = example("state_diagram")
    rows = ex.main(tmp_path, end=0.01, subdivisions=2, overrides=["solver.reuse_tolerance=1e-8"])
    assert "firm adhesion" in capsys.readouterr().out and (tmp_path / "states.png").stat().st_size > 10_000
    assert {(r["off_rate"], r["reactive_compliance"]): r["state"] for r in rows} == FULL_DIAGRAM_EARLIER_RUN
    for r in rows:  # and with a margin of the rule's thresholds (1 % and 50 % of V_free)
        low, high = {"firm adhesion": (-1.0, 0.002), "rolling": (0.03, 0.3), "no adhesion": (0.55, 1.0)}[r["state"]]
        assert low < r["velocity_ratio"] < high and (r["bonds_end"] > 0 or r["state"] == "no adhesion")
    ratio = {(r["off_rate"], r["reactive_compliance"]): r["velocity_ratio"] for r in rows}
    assert ratio[1.0, 0.1e-10] < ratio[100.0, 0.1e-10] < ratio[100.0, 1.2e-10]  # faster rupture
    assert ratio[1.0, 0.1e-10] < ratio[1.0, 1.2e-10] < ratio[100.0, 1.2e-10]  # longer reach
