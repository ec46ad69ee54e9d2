"""Two equal cells near contact from the exact two-sphere resistance plus the wall's part on a
lattice of gaps (warpbem/dynamics/close_pairs.py, ``[solver] close_pairs = "lubrication"``)."""

import numpy as np
import pytest

from warpbem.dynamics.close_pairs import generalised, lattice_gap, with_resistance
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.hydro import two_spheres
from warpbem.surfaces.body import Body
from tests.unit.test_pairwise import A, EXACT, HEIGHT, MESH, motion, relative_change

VISCOSITY = 1e-3

pytestmark = pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")


def solves(wall=True, **solver):
    model = Model([MESH] * 2, [False] * 2, Flow(100.0, VISCOSITY, wall=wall), solver=SolverOptions(**solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))


def pair(gap, angle, wall=True):
    distance = 2 * A + gap
    z = HEIGHT if wall else 0.0
    return [Body(MESH, position=(0.3e-6, -0.2e-6, z)),
            Body(MESH, position=(0.3e-6 + distance * np.cos(angle), -0.2e-6 + distance * np.sin(angle), z))]


@pytest.mark.parametrize("angle", [0.0, np.pi], ids=["along", "exchanged"])
def test_on_a_gap_of_its_lattice_along_the_flow_the_close_pair_is_its_direct_solve(angle):
    """At a lattice gap with the line of centres along the flow the model inverts the snapshot's
    resistance, W + R_JO = Q^-1, and its holding loads, so it returns the direct solve to
    round-off, the cells in either order (exchanged: the second cell upstream); the cells alone
    differ from it by the coupling, the size of the entries."""
    bodies = pair(lattice_gap(2) * A, angle)
    model = solves(**EXACT, grand_mobility="pairs")
    assert model.pairwise.close.takes(np.array([0]), np.array([1]), np.array([b.position for b in bodies]))[0]
    direct = motion(Motion.of(model.mobility.solve(bodies)), model._grand_mobility(bodies))
    assert max(relative_change(motion(*model._snapshot(bodies)), direct)) < 1e-7
    alone = motion(*solves(**EXACT, grand_mobility="pairs", pair_cutoff=0.0)._snapshot(bodies))
    assert min(relative_change(alone, direct)) > 1e-2


def test_between_gaps_and_at_an_angle_the_close_pair_is_near_its_direct_solve():
    """Between two lattice gaps (linear in the gap) and 0.3 rad off the flow (the pair along x
    turned, the flow's holding loads along and across the line combined by the angle) the model
    stays near the direct solve of the pair: the k = 2 mesh's own lack of symmetry under the turn
    and the interpolation (3.8e-4 and 8.4e-4 measured), against a coupling of 0.34 and 0.08 of the
    entries."""
    bodies = pair(0.5 * (lattice_gap(1) + lattice_gap(2)) * A, 0.3)
    model = solves(**EXACT, grand_mobility="pairs")
    direct = motion(Motion.of(model.mobility.solve(bodies)), model._grand_mobility(bodies))
    assert max(relative_change(motion(*model._snapshot(bodies)), direct)) < 2e-3


def test_far_below_its_lattice_the_squeeze_follows_jeffrey_and_onishi():
    """Two spheres without the wall, 1 % of the radius apart, pushed together along their line
    of centres: the exact two-sphere resistance (Jeffrey & Onishi 1984, X^A_11 - X^A_12 ~ 1 /
    (2 xi), hydro/two_spheres.py) carries the squeeze the elements cannot resolve, so the
    model's relative mobility along the line is that of the exact resistance to the elements'
    remainder, extrapolated from gaps of 0.1 and 0.14 radii (W = Q^-1 - R_JO: the k = 2 mesh's
    error there; 1.5 % off measured), about 1 / 50 of the cells' alone."""
    gap = 0.01 * A
    bodies = pair(gap, 0.0, wall=False)
    model = solves(wall=False, **EXACT, grand_mobility="pairs")
    q, _ = motion(*model._snapshot(bodies))
    exact = np.linalg.inv(generalised(two_spheres.resistance_matrix(VISCOSITY, A, (2 * A + gap, 0.0, 0.0)), A))
    squeeze = np.zeros(12)
    squeeze[0], squeeze[6] = 1.0, -1.0  # equal and opposite forces along the line
    relative = lambda m: squeeze @ m @ squeeze  # noqa: E731: the approach velocity per unit force
    assert relative(q) == pytest.approx(relative(exact), rel=2e-2)
    alone, _ = motion(*solves(wall=False, **EXACT, grand_mobility="pairs", pair_cutoff=0.0)._snapshot(bodies))
    assert relative(q) < 0.03 * relative(alone)


def test_films_are_added_to_the_assembled_resistance():
    """with_resistance gives M = (Q^-1 + sum P^T L P)^-1 and u = M Q^-1 u_s (the holding loads kept)
    for a smooth grand mobility Q of four cells and films between cells 0-1 and 1-2, against the
    inverses formed directly; cell 3, in no film, keeps its own rows but feels the others' change."""
    rng = np.random.default_rng(1)
    n, radii = 4, np.array([1.0, 1.5, 2.0, 2.5]) * 1e-6
    basis = rng.normal(size=(6 * n, 6 * n))
    q = basis @ basis.T / (6 * n) + np.eye(6 * n)
    u = rng.normal(size=6 * n)
    films = []
    for i, j in ((0, 1), (1, 2)):
        half = rng.normal(size=(12, 3))
        films.append((i, j, 5.0 * half @ half.T))  # positive semidefinite, rank 3 as a film's singular part
    resistance = np.linalg.inv(q)
    for i, j, film in films:
        rows = np.concatenate([6 * i + np.arange(6), 6 * j + np.arange(6)])
        resistance[np.ix_(rows, rows)] += film
    expected_q = np.linalg.inv(resistance)
    expected_u = expected_q @ np.linalg.solve(q, u)
    by_cell, flow = q.reshape(6 * n, n, 6), u.reshape(n, 6)
    parts = (flow[:, :3], flow[:, 3:] / radii[:, None], by_cell[:, :, :3], by_cell[:, :, 3:] / radii[None, :, None])
    velocity, angular, basis_velocity, basis_angular = with_resistance(*parts, radii, [(np.array([i, j]), film, None) for i, j, film in films])
    got_q = np.concatenate([basis_velocity, basis_angular * radii[None, :, None]], axis=2).reshape(6 * n, 6 * n)
    got_u = np.concatenate([velocity, angular * radii[:, None]], axis=1).ravel()
    assert np.abs(got_q - expected_q).max() < 1e-12 * np.abs(expected_q).max()
    assert np.abs(got_u - expected_u).max() < 1e-12 * np.abs(expected_u).max()
    assert np.abs(got_q - q).max() > 1e-2 * np.abs(q).max()  # the films matter


def test_a_cell_between_two_close_neighbours_is_held_by_both_films():
    """Three cells in a line 0.1 radius apart above the wall: the middle one pushed along the
    line squeezes two films. The pairs' sum of mobilities takes each pair's film as if the
    other cell were absent; the films added in resistance hold the middle cell as the whole
    system's solve does. Largest change over largest entry of the grand mobility against the
    whole system (measured 0.136 summed, 1.4e-2 with the films; 0.11 and 1.1e-2 on three 5 um
    k = 3 cells 0.5 um apart) and the middle cell's mobility along the line (0.877 and 1.008 of
    the whole system's)."""
    distance = 2 * A + 0.1 * A
    bodies = [Body(MESH, position=(x, 0.0, HEIGHT)) for x in (-distance, 0.0, distance)]
    model = Model([MESH] * 3, [False] * 3, Flow(100.0, VISCOSITY), solver=SolverOptions())
    whole = HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))
    exact, _ = motion(Motion.of(whole.mobility.solve(bodies)), whole._grand_mobility(bodies))
    three = dict(EXACT, grand_mobility="pairs", close_clusters="none")  # the films alone (test_close_clusters.py)
    assembled = {}
    for close_pairs in ("lubrication", "lattice"):
        model = Model([MESH] * 3, [False] * 3, Flow(100.0, VISCOSITY),
                      solver=SolverOptions(**three, close_pairs=close_pairs))
        pairs = HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))
        assembled[close_pairs], _ = motion(*pairs._snapshot(bodies))
    error = {k: np.abs(q - exact).max() / np.abs(exact).max() for k, q in assembled.items()}
    squeeze = {k: q[6, 6] / exact[6, 6] for k, q in assembled.items()}  # the middle cell's x mobility
    assert error["lubrication"] < 0.3 * error["lattice"]
    assert squeeze["lubrication"] == pytest.approx(1.0, abs=0.04)
    assert abs(squeeze["lattice"] - 1.0) > 0.08
