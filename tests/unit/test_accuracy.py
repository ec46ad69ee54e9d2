"""The accuracy target's bookkeeping (hydro/accuracy.py): which meshes it rebuilds, which
settings it holds, the options it refuses; the physics is checked against exact series in
tests/verification/test_accuracy_target.py."""

import warnings

import numpy as np
import pytest

import warpbem as wb
from warpbem.hydro import accuracy
from warpbem.hydro import error_model_table as table
from warpbem.options import OptionError
from warpbem.surfaces.shapes import adherent_cell


def test_library_meshes_rebuild_the_same_surface_at_another_subdivision():
    sphere = wb.mesh.sphere(2.0, 3, pole_grading=2.0)
    np.testing.assert_array_equal(sphere.at_subdivisions(5).nodes, wb.mesh.sphere(2.0, 5, pole_grading=2.0).nodes)
    assert sphere.at_subdivisions(3) is sphere
    spheroid = wb.mesh.spheroid(1.0, 0.5, 2)
    np.testing.assert_array_equal(spheroid.at_subdivisions(4).nodes, wb.mesh.spheroid(1.0, 0.5, 4).nodes)
    dome, _ = adherent_cell("dome", subdivisions=2)
    np.testing.assert_array_equal(dome.at_subdivisions(3).nodes, adherent_cell("dome", subdivisions=3)[0].nodes)


def test_a_mesh_from_a_file_cannot_be_rebuilt_and_keeps_its_size(tmp_path):
    wb.mesh.save(wb.mesh.sphere(1.0, 3), tmp_path / "s.q9")
    loaded = wb.mesh.load(tmp_path / "s.q9")
    with pytest.raises(wb.MeshError, match="library generator"):
        loaded.at_subdivisions(4)
    bodies = [wb.Body(loaded, position=(0, 0, 2.0))]
    chosen = accuracy.choose_for(bodies, True, 1e-2)
    assert chosen.subdivisions is None  # nothing rebuilt
    assert accuracy.rebuilt(bodies, chosen)[0].mesh is loaded
    terms = accuracy.scene_terms(bodies, True)
    assert [t.held_k for t in terms] == [3]  # read at its own size


def test_a_surface_velocity_holds_the_mesh_and_the_constant_density():
    mesh = wb.mesh.sphere(1.0, 2)
    body = wb.Body(mesh, position=(0, 0, 3.0), surface_velocity=np.zeros((mesh.n_elements, 3)))
    chosen = accuracy.choose_for([body], True, 1e-2)
    assert chosen.density_order == 1 and chosen.subdivisions is None


def test_repeated_solves_reuse_the_rebuilt_meshes():
    body = wb.Body(wb.mesh.sphere(1.0, 4), position=(0, 0, 2.0))
    chosen = accuracy.choose_for([body], True, 1e-2)
    first, second = accuracy.rebuilt([body], chosen), accuracy.rebuilt([body], chosen)
    assert first[0].mesh is second[0].mesh and first[0].mesh.subdivisions == chosen.subdivisions


def test_fixed_cells_unrefined_at_the_wall_count_as_far_from_it():
    dome, position = adherent_cell("dome", radius=1.0, gap=0.05, subdivisions=2)
    bodies = [wb.Body(wb.mesh.sphere(1.0, 2), position=(0, 3.0, 2.0)), wb.Body(dome, position=position, fixed=True)]
    refined = accuracy.scene_terms(bodies, True, refine_fixed_at_wall=True)
    unrefined = accuracy.scene_terms(bodies, True, refine_fixed_at_wall=False)
    assert min(t.gap for t in refined if t.model is not accuracy.PAIR_MODEL) < 0.06
    # the free sphere alone: 1 radius (of its k = 2 mesh's equivalent sphere)
    assert min(t.gap for t in unrefined if t.model is not accuracy.PAIR_MODEL) == pytest.approx(1.0, rel=1e-3)


def test_an_accuracy_out_of_reach_warns_and_solves_with_the_most_accurate_setting():
    with pytest.warns(wb.AccuracyWarning, match="no measured setting reaches"):
        chosen = accuracy.choose(1e-6, [accuracy._Term(accuracy.WALL_MODEL, 0.5)])
    errors = accuracy.WALL_MODEL.at(0.5)[0]
    assert chosen.error_estimate == pytest.approx(errors.min())


@pytest.mark.parametrize("model, gap, target", [(accuracy.WALL_MODEL, 0.1, 1e-3), (accuracy.SHEAR_MODEL, 0.5, 1e-3),
                                                (accuracy.FIXED_MODEL, 0.1, 1e-2), (accuracy.PAIR_MODEL, 0.3, 1e-3)])
def test_the_choice_is_the_cheapest_whose_estimate_times_its_margin_is_within_the_accuracy(model, gap, target):
    """The bound is the estimate times the setting's margin (the refined one where its refinement
    splits elements at the gap), within the accuracy; every setting predicted cheaper has its
    bound above it, among them one whose estimate alone is within it (the margin changed the
    choice)."""
    term = accuracy._Term(model, gap)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        chosen = accuracy.choose(target, [term])
    errors, ms, _ = accuracy.scene_costs([term])
    margins = model.margin_at(gap)
    best = accuracy.WALL_MODEL.settings.index((chosen.subdivisions, chosen.density_order, chosen.contact_refinement))
    assert chosen.error_bound == pytest.approx(margins[best] * chosen.error_estimate) and chosen.error_bound <= target
    cheaper = ms < chosen.predicted_ms
    assert np.all(margins[cheaper] * errors[0][cheaper] > target)
    assert np.any(errors[0][cheaper] <= target)


def test_a_refined_setting_has_the_refined_margin_only_where_its_refinement_splits_elements():
    """k = 2, p = 2, ratio 0.6 splits the sphere's lowest elements below h/a - 1 = 0.31
    (refinement_threshold); above it the mesh is the unrefined one's, and so is its margin."""
    model, index = accuracy.SHEAR_MODEL, accuracy.SHEAR_MODEL.settings.index((2, 2, 0.6))
    threshold = accuracy.refinement_threshold(2, 0.6)
    assert 0.2 < threshold < 0.5
    assert model.margin_at(0.9 * threshold)[index] == model.margins[1] > model.margins[0]
    assert model.margin_at(1.1 * threshold)[index] == model.margins[0]
    assert model.margin_at(0.05)[model.settings.index((2, 2, 0.0))] == model.margins[0]


@pytest.mark.parametrize("changes, message", [(dict(contact_refinement=1.0), "chooses it"),
                                              (dict(quadrature_order=3), "quadrature_order"),
                                              (dict(), "accuracy")])
def test_options_the_target_cannot_honour_are_refused(changes, message):
    with pytest.raises(OptionError, match=message):
        wb.SolverOptions(accuracy=1e-3 if changes else 0.9, **changes)


def test_a_held_density_order_restricts_the_choice():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        chosen = accuracy.choose(1e-2, [accuracy._Term(accuracy.WALL_MODEL, 0.5)], density_order=2)
    assert chosen.density_order == 2


@pytest.mark.parametrize("k", [2, 4])
def test_a_fixed_sphere_has_the_model_sphere_s_unknowns(k):
    """A held body's excess over the model (accuracy.body_excess) counts its own refined mesh: a
    held library sphere at the model's measured gaps (benchmarks/error_model.py places it at h =
    1 + gap) has, in every setting, the unknowns the model measured for it (to the interpolation
    between the gaps its equivalent radius reads them at), which is why fixed_body_excess leaves
    held spheres out."""
    assert accuracy.fixed_body_excess([wb.Body(wb.mesh.sphere(1.0, k), position=(0, 0, 1.1), fixed=True)], True) is None
    for gap in accuracy.table.WALL_GAPS[1:4]:
        body = wb.Body(wb.mesh.sphere(1.0, k), position=(0, 0, 1.0 + gap), fixed=True)
        modelled = accuracy.FIXED_MODEL.at(gap)[2][accuracy._mapped(accuracy._Term(accuracy.FIXED_MODEL, gap))]
        excess = accuracy.body_excess(body)
        finite = np.isfinite(modelled)
        assert np.all(np.abs(excess[finite]) <= 0.02 * modelled[finite])


def test_an_adherent_dome_s_refined_base_counts_in_the_cost():
    """A dome 0.05 radius above the wall has its flat base refined: more unknowns than the sphere
    the error model reads it as wherever the setting refines, as many where it does not; the
    predicted time grows with them, and only for fixed bodies refined at the wall."""
    dome, position = adherent_cell("dome", radius=1.0, gap=0.05, subdivisions=4)
    bodies = [wb.Body(dome, position=position, fixed=True), wb.Body(wb.mesh.sphere(1.0, 4), position=(3.0, 0, 2.0))]
    excess = accuracy.fixed_body_excess(bodies, True)
    ratios = np.array([ratio for _, _, ratio in accuracy.WALL_MODEL.settings])
    np.testing.assert_allclose(excess[ratios == 0], 0.0, atol=1e-6)  # the same element count
    assert np.all(excess[ratios >= 1.1] > 1000)
    assert accuracy.fixed_body_excess(bodies, True, refine_fixed_at_wall=False) is None
    assert accuracy.fixed_body_excess(bodies, False) is None
    terms = accuracy.scene_terms(bodies, True)
    _, plain, _ = accuracy.scene_costs(terms)
    _, counted, unknowns = accuracy.scene_costs(terms, excess)
    refined = np.isfinite(plain) & (excess >= 1)  # at least one unknown more
    assert np.all(counted[refined] > plain[refined])
    np.testing.assert_array_equal(counted[ratios == 0], plain[ratios == 0])
    assert np.all(unknowns[refined] > accuracy.scene_costs(terms)[2][refined])


def test_a_held_sphere_is_read_by_its_holding_load_and_other_held_shapes_by_a_free_sphere():
    """accuracy.wall_model: the held sphere's table for a sphere held at rest (its nodes on one
    sphere, translated or turned), the free sphere's for a free body, a held one given a velocity
    and a held dome."""
    sphere = wb.mesh.sphere(2.0, 3)
    dome, position = adherent_cell("dome", radius=1.0, gap=0.05, subdivisions=2)
    assert accuracy.wall_model(wb.Body(sphere, position=(1.0, 2.0, 3.0), fixed=True,
                                       orientation=(0.9, 0.1, 0.3, 0.2))) is accuracy.FIXED_MODEL
    assert accuracy.wall_model(wb.Body(sphere, position=(0, 0, 3.0))) is accuracy.WALL_MODEL
    assert accuracy.wall_model(wb.Body(dome, position=position, fixed=True)) is accuracy.WALL_MODEL
    # held but moved: its load is a drag, read with the free sphere's mobilities
    assert accuracy.wall_model(wb.Body(sphere, position=(0, 0, 3.0), fixed=True, velocity=(0, 0, 1.0))) is (
        accuracy.WALL_MODEL)


def test_a_solve_given_no_load_is_read_by_the_motion_in_shear_alone():
    """accuracy.wall_model: a free body in a solve given no load is read in the table of its U
    and Omega in shear (SHEAR_MODEL), two of the free sphere's five quantities, measured from the
    same systems (benchmarks/error_model.py): at every setting and gap its error at most the
    five's, its unknowns and time the same. MobilitySolver.solve reads a free sphere so when it
    is given no load, and by the five when pushed; at h/a = 1.1 and 1e-2 the first is cheaper."""
    for setting, cells in table.SHEAR.items():
        for shear, wall in zip(cells, table.WALL[setting]):
            assert (shear is None) == (wall is None)
            assert shear is None or (shear[0] <= wall[0] and shear[1:] == wall[1:])
    sphere = wb.Body(wb.mesh.sphere(1.0, 4), position=(0, 0, 1.1))
    assert accuracy.wall_model(sphere, unloaded=True) is accuracy.SHEAR_MODEL
    held = wb.Body(wb.mesh.sphere(1.0, 4), position=(0, 0, 1.1), fixed=True)
    assert accuracy.wall_model(held, unloaded=True) is accuracy.FIXED_MODEL
    solver = wb.MobilitySolver(1.0, 1.0, options=wb.SolverOptions(accuracy=1e-2))
    free = solver.solve([sphere]).chosen
    pushed = solver.solve([sphere], forces=[[0.0, 0.0, 1.0]]).chosen
    assert free == accuracy.choose_for([sphere], True, 1e-2, unloaded=True)
    assert pushed == accuracy.choose_for([sphere], True, 1e-2)
    assert free.predicted_ms < pushed.predicted_ms
    # a held body given a velocity drives the free one: the five quantities again
    moved = wb.Body(wb.mesh.sphere(1.0, 4), position=(3.0, 0, 1.5), fixed=True, velocity=(1.0, 0, 0))
    assert accuracy.choose_for([sphere, moved], True, 1e-2, unloaded=True) == accuracy.choose_for(
        [sphere, moved], True, 1e-2)


def test_a_choice_larger_than_any_measured_solve_says_its_time_is_extrapolated():
    """Beside a k = 4 dome 0.05 radius above the wall, refined at it, accuracy 1e-3 chooses a
    setting whose counted unknowns (28 224 measured by benchmarks/accuracy_shapes.py) exceed the
    error model's largest solve (accuracy.LARGEST_MEASURED): the target warns; at 3e-2 it does not."""
    dome, position = adherent_cell("dome", radius=1.0, gap=0.05, subdivisions=4)
    bodies = [wb.Body(dome, position=position, fixed=True), wb.Body(wb.mesh.sphere(1.0, 4), position=(2.8, 0, 1.6))]
    with pytest.warns(accuracy.AccuracyWarning, match="extrapolated"):
        accuracy.choose_for(bodies, True, 1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", accuracy.AccuracyWarning)
        accuracy.choose_for(bodies, True, 3e-2)
