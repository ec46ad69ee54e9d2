"""Bad input stops with a message naming the body and the problem, never a NaN result."""

import numpy as np
import pytest

import warpbem as wb

SPHERE = wb.mesh.sphere(1.0, 2)


def test_body_rejects_bad_values():
    with pytest.raises(ValueError, match="position must be finite"):
        wb.Body(SPHERE, position=(0.0, np.nan, 2.0))
    with pytest.raises(ValueError, match="position must have 3 components"):
        wb.Body(SPHERE, position=(0.0, 2.0))
    with pytest.raises(ValueError, match="orientation quaternion must be non-zero"):
        wb.Body(SPHERE, orientation=(0, 0, 0, 0))
    with pytest.raises(TypeError, match="mesh must be"):
        wb.Body("sphere.q9")
    with pytest.raises(ValueError, match="needs fixed=True"):
        wb.Body(SPHERE, velocity=(1.0, 0, 0))


def test_a_position_and_a_mesh_in_different_units_are_refused():
    """6 meaning 6 um with a mesh in metres puts the cell a million of its sizes away; unit spheres
    (Stokes flow has no scale of its own) and far placements of up to 1e5 sizes are fine."""
    with pytest.raises(ValueError, match=r"position: 6 m is 1.2e\+06 times the body's size \(5e-06 m\): the"
                                         r" position and the mesh are in different units"):
        wb.Body(wb.mesh.sphere(5e-6, 1), position=(0.0, 0.0, 6.0))
    assert wb.Body(SPHERE, position=(-9e4, 0.0, 2.0)).position[0] == -9e4


def test_wall_crossing_names_the_body():
    bodies = [wb.Body(SPHERE, position=(0, 0, 3.0)), wb.Body(SPHERE, position=(5, 0, 0.9))]
    with pytest.raises(wb.PlacementError, match=r"body 1 touches or crosses the wall"):
        wb.solve_mobility(bodies, shear_rate=1.0)
    # without the wall the same placement is fine
    sol = wb.solve_mobility(bodies, shear_rate=1.0, wall=False)
    assert np.all(np.isfinite(sol.velocity))


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")  # a 1e-3 gap, on purpose
def test_overlap_names_both_bodies_even_when_barely_touching():
    bodies = [wb.Body(SPHERE, position=(0, 0, 2.0)), wb.Body(SPHERE, position=(1.999, 0, 2.0))]
    with pytest.raises(wb.PlacementError, match="bodies 0 and 1 overlap"):
        wb.solve_mobility(bodies)
    # a gap of 1e-3 radii is a valid (if demanding) configuration; solved here on the bare mesh
    # (resolving it takes thousands of elements, and is not what this test is about)
    bodies[1] = wb.Body(SPHERE, position=(2.001, 0, 2.0))
    with pytest.warns(wb.ContactResolutionWarning):
        wb.solve_mobility(bodies, wall=False, forces=[[0, 0, 1.0], [0, 0, 0]], options=wb.SolverOptions(contact_refinement=0.0, density_order=1))


def test_messages_call_named_bodies_by_their_names():
    """A body's name (Body.name, Model.names, a scene's bodies.N.name) is how messages call it;
    unnamed, or with the default name "body<i>", by its index."""
    cell, dome = (wb.Body(SPHERE, position=(0, 0, 2.0), name=name) for name in ("free cell", "dome"))
    with pytest.raises(wb.PlacementError, match="bodies 'free cell' and 'dome' overlap"):
        wb.solve_mobility([cell, dome])
    with pytest.raises(wb.PlacementError, match="body 'free cell' touches or crosses the wall"):
        wb.solve_mobility([wb.Body(SPHERE, position=(0, 0, 0.5), name="free cell")])
    # a time-stepped model's bodies carry the model's names (Simulator.geometry checks them)
    model = wb.Model(meshes=[SPHERE, SPHERE], fixed=[False, True], names=["free cell", "body1"])
    with pytest.raises(wb.PlacementError, match="bodies 'free cell' and 1 overlap"):
        wb.Simulator(model).geometry(model.initial_state([[0, 0, 2.0], [1.0, 0, 2.0]]))
    # a model's default name is its number wherever the body sits (a lone snapshot's list: index 0)
    from warpbem.surfaces.placement import body_label

    assert [body_label(name, 0) for name in (None, "body3", "dome")] == ["0", "3", "'dome'"]


def test_reference_point_must_be_inside_the_mesh():
    shifted = wb.mesh.Mesh(SPHERE.nodes + [3.0, 0, 0], SPHERE.elements)
    with pytest.raises(wb.PlacementError, match="body 0: its reference point"):
        wb.solve_mobility([wb.Body(shifted, position=(0, 0, 10.0))])


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(forces=np.zeros((2, 3))), ValueError, r"forces must have shape \(1, 3\)"),
    (dict(torques=[[0, np.inf, 0]]), ValueError, r"torques\[0\] \(body 0\) is not finite"),
    (dict(viscosity=0.0), ValueError, r"viscosity: 0 is outside the allowed range \(0, 1000\]"),
    (dict(shear_rate=np.nan), ValueError, "shear_rate: expected a finite number"),
    (dict(device="cuda:7"), wb.DeviceError, "device 'cuda:7' is not available"),
])
def test_solver_arguments_are_checked(kwargs, error, message):
    with pytest.raises(error, match=message):
        wb.solve_mobility([wb.Body(SPHERE, position=(0, 0, 3.0))], **{"shear_rate": 1.0, **kwargs})


@pytest.mark.parametrize("options, message", [
    (dict(dtype="float16"), "dtype: 'float16' is not one of 'float64', 'float32'"),
    (dict(operator="sparse"), "operator: 'sparse' is not one of 'auto'"),
    (dict(quadrature_order=0), r"quadrature_order: 0 is outside the allowed range \[1, 10\]"),
    (dict(tolerance=2.0), r"tolerance: 2 is outside the allowed range \(0, 0.1\]"),
    (dict(density_order=1.5), "density_order: expected an integer"),
])
def test_solver_options_are_checked_by_their_declaration(options, message):
    """SolverOptions checks each field against its declared range (warpbem/options.py), with
    the message the scene files get too (tests/unit/test_scene.py)."""
    with pytest.raises(ValueError, match=message):
        wb.SolverOptions(**options)


def test_loads_on_fixed_bodies_are_refused():
    bodies = [wb.Body(SPHERE, position=(0, 0, 3.0), fixed=True)]
    with pytest.raises(ValueError, match="body 0 is fixed"):
        wb.solve_mobility(bodies, forces=[[1.0, 0, 0]])


def test_gmres_failure_reports_iterations_and_residual():
    bodies = [wb.Body(SPHERE, position=(0, 0, 1.3)), wb.Body(SPHERE, position=(2.2, 0, 1.3), fixed=True)]
    with pytest.raises(wb.ConvergenceError, match=r"\d+ iterations, relative residual \d"):
        wb.solve_mobility(bodies, shear_rate=1.0, options=wb.SolverOptions(tolerance=1e-14, max_iterations=3))


def test_empty_scene_is_refused():
    with pytest.raises(ValueError, match="at least one Body"):
        wb.solve_mobility([])


def test_body_refuses_an_open_or_inward_mesh():
    with pytest.raises(wb.MeshError, match="open|shared"):
        wb.Body(wb.mesh.Mesh(SPHERE.nodes, SPHERE.elements[:-1]))
    with pytest.raises(wb.MeshError, match="inwards"):
        wb.Body(wb.mesh.Mesh(SPHERE.nodes, SPHERE.elements[:, [0, 3, 2, 1, 7, 6, 5, 4, 8]]))


def test_declared_density_orders_are_the_kernels():
    """The option's range is the orders kernels/assembly.py generates, declared there once."""
    from warpbem.kernels.assembly import DENSITY_ORDERS
    from warpbem.options import declared

    spec = next(spec for name, _, spec in declared(wb.SolverOptions) if name == "density_order")
    assert tuple(range(int(spec.low), int(spec.high) + 1)) == DENSITY_ORDERS
