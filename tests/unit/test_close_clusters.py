"""Three or more cells near contact: the part their pairs leave out, added in resistance
(warpbem/dynamics/close_clusters.py, ``[solver] close_clusters = "resistance"``)."""

import numpy as np
import pytest

from warpbem.dynamics import close_clusters
from warpbem.dynamics.close_clusters import clusters, pairwise_resistance
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.options import OptionError
from warpbem.surfaces.body import Body
from tests.unit.test_pairwise import A, EXACT, HEIGHT, MESH, motion, relative_change


def solves(**solver):
    model = Model([MESH] * 3, [False] * 3, Flow(100.0, 1e-3), solver=SolverOptions(**solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu"))


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.parametrize("heights", [(0.0, 0.0, 0.0), (0.0, 8e-9, -6e-9)], ids=["one-height", "three-heights"])
def test_a_close_train_with_its_three_body_part_from_its_own_mesh_is_the_whole_system(monkeypatch, heights):
    """The cluster's resistance is its pairs' sum plus R_3 = R_system - (the same sum on the
    cluster mesh). On the cells' own mesh and density, at a gap on the close pairs' lattice (0.1
    radius, where their model is the pair's direct solve) and positions on the cluster lattice,
    the two sums are one and the pairs path gives the whole system's solve: exact algebra, so to
    round-off (measured 1e-15 / 2.5e-12 of the grand mobility / flow's motion), where without the
    cluster part three cells 0.1 radius apart err by 5.1e-2 / 1.2e-2 (the middle cell screening
    the outer two). A wrong sign, a film counted
    twice or a pair's cells at the wrong height leave errors of the size of the coupling."""
    distance = 2.1 * A  # between centres, a gap of 0.1 radius at the cells' heights
    x = np.cumsum([0.0] + [np.sqrt(distance**2 - (b - a) ** 2) for a, b in zip(heights, heights[1:])])
    bodies = [Body(MESH, position=(x_i, 0.0, HEIGHT + h)) for x_i, h in zip(x, heights)]
    cheap = dict(density_order=1, contact_refinement=0.0)  # the identity holds on any discretisation
    whole = solves(**cheap)
    exact = motion(Motion.of(whole.mobility.solve(bodies)), whole._grand_mobility(bodies))
    own = whole.model.solver
    monkeypatch.setattr(close_clusters, "CLUSTER_SUBDIVISIONS", 2)
    monkeypatch.setattr(close_clusters, "CLUSTER_DENSITY_ORDER", own.density_order)
    monkeypatch.setattr(close_clusters, "CLUSTER_REFINEMENT", own.contact_refinement)
    monkeypatch.setattr(close_clusters, "CLUSTER_LATERAL", 1e-12)
    with_part, without = (motion(*solves(**EXACT, **cheap, grand_mobility="pairs", far_field="none",
                                         close_clusters=mode)._snapshot(bodies)) for mode in ("resistance", "none"))
    assert max(relative_change(with_part, exact)) < 1e-6
    assert max(relative_change(without, exact)) > 5e-3


def test_clusters_are_the_cells_joined_by_close_pairs_three_or_more():
    # 0-1-2 a train, 3-4 a lone close pair, 5-6-7-5 a ring, 8 alone
    first, second = np.array([0, 1, 3, 5, 6, 7]), np.array([1, 2, 4, 6, 7, 5])
    found = clusters(first, second, 9)
    assert [c.tolist() for c in found] == [[0, 1, 2], [5, 6, 7]]
    assert clusters(np.array([], int), np.array([], int), 4) == []


def test_the_pairwise_resistance_of_two_cells_is_their_pair_resistance():
    """R = R_0 + R_1 + (R_01 - R_0 - R_1) = R_01 = Q^-1 + L, and the holding loads Q^-1 u (the
    film does no work on cells held still), for a random symmetric positive pair mobility."""
    rng = np.random.default_rng(2)
    basis = rng.normal(size=(12, 12))
    q, u = basis @ basis.T / 12 + np.eye(12), rng.normal(size=12)
    half = rng.normal(size=(12, 3))
    film = half @ half.T
    alone = [(q[:6, :6] + 0.1 * np.eye(6), rng.normal(size=6)), (q[6:, 6:] + 0.2 * np.eye(6), rng.normal(size=6))]
    r, f = pairwise_resistance(alone, {(0, 1): (q, u, film)})
    assert np.allclose(r, np.linalg.inv(q) + film, rtol=0, atol=1e-12 * np.abs(r).max())
    assert np.allclose(f, np.linalg.solve(q, u), rtol=0, atol=1e-12 * np.abs(f).max())


def test_the_cluster_part_defaults_on_and_is_refused_beside_the_coarse_remainder():
    assert SolverOptions(grand_mobility="pairs").resolved(time_stepping=True).close_clusters == "resistance"
    assert (SolverOptions(grand_mobility="pairs", many_body="coarse").resolved(time_stepping=True).close_clusters
            == "none")
    with pytest.raises(OptionError, match="close_clusters: 'resistance' with many_body = 'coarse' would count"):
        SolverOptions(grand_mobility="pairs", many_body="coarse", close_clusters="resistance")
