"""The CDL mobility solver: reciprocity between bodies, free/fixed consistency, apply modes,
precision, warm starts, and CUDA compilation of every kernel."""

import gc
import tempfile
import weakref

import numpy as np
import pytest

import warpbem as wb
from warpbem import runtime

SPHERE = wb.mesh.sphere(1.0, 3)


def _two_sphere_mobility():
    """12x12 mobility of two free spheres near the wall: columns from unit forces/torques."""
    positions = [(0.0, 0.0, 1.4), (2.3, 0.7, 1.8)]
    bodies = [wb.Body(SPHERE, position=p) for p in positions]
    columns = []
    for k in range(12):
        loads = np.zeros(12)
        loads[k] = 1.0
        f = loads.reshape(2, 6)
        sol = wb.solve_mobility(bodies, viscosity=1.0, forces=f[:, :3], torques=f[:, 3:])
        columns.append(np.concatenate([np.concatenate([sol.velocity[i], sol.angular_velocity[i]]) for i in range(2)]))
    return np.array(columns).T


def test_two_body_mobility_is_reciprocal():
    # Lorentz reciprocal theorem: the grand mobility matrix is symmetric, body-to-body blocks too
    # (to the discretisation error of this 54-element mesh, a few 1e-3 of the coupling)
    m = _two_sphere_mobility()
    assert np.abs(m[:6, 6:] - m[6:, :6].T).max() < 5e-3 * np.abs(m[:6, 6:]).max()
    assert np.abs(m - m.T).max() < 2e-3 * np.abs(m).max()
    assert np.linalg.eigvalsh(0.5 * (m + m.T)).min() > 0


@pytest.mark.parametrize("shape", ["sphere", "tilted spheroid, off-centre reference point"])
def test_fixed_and_free_formulations_agree(shape):
    """Hold a body in shear next to a free one; then free it and apply the holding load: it
    must stay at rest, and its neighbour must move exactly as before. The spheroid case has no
    symmetry left: tilted, its reference point off its centroid."""
    neighbour = wb.Body(SPHERE, position=(2.4, 0.5, 1.5))
    mesh = SPHERE
    orientation = (1.0, 0.0, 0.0, 0.0)
    if shape != "sphere":
        spheroid = wb.mesh.spheroid(1.0, 0.6, subdivisions=3)
        mesh = wb.mesh.Mesh(spheroid.nodes + [0.2, -0.1, 0.05], spheroid.elements)
        orientation = (0.9, 0.3, -0.2, 0.1)
    held = wb.Body(mesh, position=(0.0, 0.0, 1.3), orientation=orientation, fixed=True)
    fixed = wb.solve_mobility([held, neighbour], shear_rate=1.0, viscosity=1.0, options=wb.SolverOptions(tolerance=1e-11))
    free = wb.solve_mobility([wb.Body(mesh, position=(0.0, 0.0, 1.3), orientation=orientation), neighbour],
                             shear_rate=1.0, viscosity=1.0, forces=[fixed.force[0], [0, 0, 0]],
                             torques=[fixed.torque[0], [0, 0, 0]], options=wb.SolverOptions(tolerance=1e-11))
    scale = np.abs(fixed.velocity[1]).max()
    assert np.abs(free.velocity[0]).max() < 1e-3 * scale
    assert np.abs(free.angular_velocity[0]).max() < 1e-3 * scale
    np.testing.assert_allclose(free.velocity[1], fixed.velocity[1], atol=1e-3 * scale)


def _scene():
    return [wb.Body(SPHERE, position=(0.0, 0.0, 1.5)), wb.Body(SPHERE, position=(1.5, 2.0, 1.3), fixed=True)]


def test_matrix_free_solve_matches_dense(device):
    dense = wb.solve_mobility(_scene(), shear_rate=1.0, options=wb.SolverOptions(operator="dense", tolerance=1e-10), device=device)
    free = wb.solve_mobility(_scene(), shear_rate=1.0, options=wb.SolverOptions(operator="matrix_free", tolerance=1e-10), device=device)
    assert dense.operator_mode == "dense" and free.operator_mode == "matrix_free"
    np.testing.assert_allclose(free.velocity, dense.velocity, atol=1e-8)
    np.testing.assert_allclose(free.force, dense.force, atol=1e-8 * np.abs(dense.force).max())


def test_float32_agrees_with_float64_to_single_precision():
    d = wb.solve_mobility(_scene(), shear_rate=1.0, viscosity=1e-3)
    s = wb.solve_mobility(_scene(), shear_rate=1.0, viscosity=1e-3, options=wb.SolverOptions(dtype="float32", tolerance=1e-6))
    np.testing.assert_allclose(s.velocity, d.velocity, atol=2e-5 * np.abs(d.velocity).max())
    np.testing.assert_allclose(s.force, d.force, atol=2e-5 * np.abs(d.force).max())


def test_warm_start_from_previous_solution_needs_no_iterations():
    first = wb.solve_mobility(_scene(), shear_rate=1.0)
    again = wb.solve_mobility(_scene(), shear_rate=1.0, initial_guess=first.solution_vector)
    assert first.iterations > 5
    assert again.iterations <= 1
    np.testing.assert_allclose(again.velocity, first.velocity, rtol=1e-7)


def test_results_do_not_depend_on_mesh_orientation_or_units():
    """A turned sphere mesh and SI-sized cells (a = 5 um, mu = 1 mPa s, 100 1/s) give the same
    scaled motion as the unit problem, up to the discretisation error of the turned mesh."""
    unit = wb.solve_mobility([wb.Body(SPHERE, position=(0, 0, 1.5))], shear_rate=1.0, viscosity=1.0)
    a = 5e-6
    q = np.array([0.9, 0.2, -0.3, 0.25])
    cell = wb.Body(wb.mesh.sphere(a, 3), position=(0, 0, 1.5 * a), orientation=q)
    si = wb.solve_mobility([cell], shear_rate=100.0, viscosity=1e-3)
    np.testing.assert_allclose(si.velocity[0] / (100.0 * a), unit.velocity[0], atol=3e-3)
    np.testing.assert_allclose(si.angular_velocity[0] / 100.0, unit.angular_velocity[0], atol=3e-3)


def test_all_kernels_compile_for_cuda():
    """The same kernels must build for NVIDIA GPUs: compile each module to PTX for sm_90 with
    NVRTC (no GPU needed). Skips cleanly where Warp has no CUDA compiler."""
    wp = runtime.init()
    from warpbem.kernels.assembly import build_kernels
    from warpbem.kernels.contact import build_contact_kernels

    for dtype in (wp.float64, wp.float32):
        for wall in (False, True):
            k = build_kernels(dtype, wall)
            for kernel in (k.assemble_entries, k.gather_entries, k.apply_matrix_free, k.same_body_row_sums,
                           k.point_force_velocity, k.proxy_interactions, k.dense_matvec, k.identity_self_blocks, k.field_at_points,
                           k.write_self_blocks,
                           build_contact_kernels(dtype).closest_points):
                with tempfile.TemporaryDirectory() as out:
                    try:
                        files = wp.compile_aot_module(kernel.module, arch=90, module_dir=out, use_ptx=True)
                    except RuntimeError as err:  # no NVRTC in this Warp build
                        pytest.skip(f"CUDA compilation unavailable: {err}")
                    assert files and all(f.stat().st_size > 1000 for f in files)


def test_repeated_solves_reuse_fixed_blocks_and_match_fresh_solves():
    """One free cell passing two fixed ones: the solver keeps the fixed-fixed blocks and
    completion columns, warm-starts GMRES, and gives what a fresh solve gives."""
    fixed = [wb.Body(SPHERE, position=(0.0, 0.0, 1.3), fixed=True),
             wb.Body(SPHERE, position=(3.0, 0.5, 1.2), fixed=True)]
    solver = wb.MobilitySolver(shear_rate=1.0, viscosity=1.0, options=wb.SolverOptions(tolerance=1e-10))
    for step, x in enumerate((-3.0, -2.8, -2.6)):
        bodies = [*fixed, wb.Body(SPHERE, position=(x, 1.8, 1.9))]
        sol = solver.solve(bodies)
        fresh = wb.solve_mobility(bodies, shear_rate=1.0, viscosity=1.0, options=wb.SolverOptions(tolerance=1e-10))
        np.testing.assert_allclose(sol.velocity, fresh.velocity, rtol=0, atol=1e-8)
        np.testing.assert_allclose(sol.force, fresh.force, rtol=0, atol=1e-8 * np.abs(fresh.force).max())
        if step == 0:
            assert not sol.reused_bodies.any()
        else:
            assert sol.reused_bodies.tolist() == [True, True, False]
            assert sol.iterations < fresh.iterations  # warm start from the previous step


def test_a_dense_run_updates_its_matrix_in_place():
    """Item 6 of issue 12: a time-stepping run holds one dense matrix, not two. While the moving
    cell keeps its element count, each new operator takes the previous one's buffer and
    reassembles only the rows and columns of the moving cell (same result as a fresh solve);
    when the count changes (contact refinement), it assembles a new one."""
    fixed = [wb.Body(SPHERE, position=(0.0, 0.0, 1.3), fixed=True),
             wb.Body(SPHERE, position=(3.0, 0.5, 1.2), fixed=True)]
    flow = dict(shear_rate=1.0, viscosity=1.0)
    options = wb.SolverOptions(tolerance=1e-10, operator="dense", density_order=1)
    solver = wb.MobilitySolver(**flow, options=options)
    buffers = []
    for x in (-3.0, -2.8):
        bodies = [*fixed, wb.Body(SPHERE, position=(x, 1.8, 1.9))]
        sol = solver.solve(bodies)
        buffers.append(solver._last[0].double_layer.matrix().ptr)
        fresh = wb.solve_mobility(bodies, **flow, options=options)
        np.testing.assert_allclose(sol.velocity, fresh.velocity, rtol=0, atol=1e-8)
    assert buffers[0] == buffers[1]
    # the moving cell first, refined near contact, then away: its count changes, and the kept
    # cells' block moves within the same buffer (the other way it would not fit: a new one)
    solver = wb.MobilitySolver(**flow, options=options)
    pointers = []
    for z in (3.5, 5.5):  # 0.2 radius above the first fixed cell: refined; then 2.2: not
        bodies = [wb.Body(SPHERE, position=(0.0, 0.0, z)), *fixed]
        sol = solver.solve(bodies)
        pointers.append(solver._last[0].double_layer.matrix().ptr)
        np.testing.assert_allclose(sol.velocity, wb.solve_mobility(bodies, **flow, options=options).velocity, rtol=0, atol=1e-8)
    sizes = solver._last[0].geometry.body_ranges[0]
    assert sizes[1] - sizes[0] == len(SPHERE.elements) and pointers[0] == pointers[1]
    # and a superseded system is gone at once, not when the cyclic collector gets to it
    gc.disable()
    try:
        last = weakref.ref(solver._last[0])
        solver.solve([wb.Body(SPHERE, position=(0.3, 0.0, 5.5)), *fixed])
        assert last() is None
    finally:
        gc.enable()


def test_unresolved_contacts_warn_once_naming_the_bodies():
    """Closer than the mesh resolves (docs/benchmarks.md, stability map: errors pass 1 %), the solver warns,
    naming the bodies; a solver used for many steps warns once per contact. Unrefined meshes
    (contact_refinement 0, cheap here) warn below three element radii; refined ones below
    refinement.WARN_FRACTION of the body's element radius (checked on the refinement alone: a
    solve there takes thousands of elements)."""
    import warnings

    from warpbem.surfaces.gaps import WALL
    from warpbem.surfaces.refinement import WARN_FRACTION, refine_near_contact

    sphere = wb.mesh.sphere(1.0, 4)
    bare = wb.SolverOptions(contact_refinement=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning where the contact is resolved
        wb.solve_mobility([wb.Body(sphere, position=(0, 0, 1.1))], shear_rate=1.0)
    with pytest.warns(wb.ContactResolutionWarning, match="body 0 and the wall are 0.03 m apart"):
        wb.solve_mobility([wb.Body(sphere, position=(0, 0, 1.03))], shear_rate=1.0, options=bare)
    pair = [wb.Body(sphere, position=(0, 0, 3.0)), wb.Body(sphere, position=(2.005, 0, 3.0))]
    with pytest.warns(wb.ContactResolutionWarning, match="body 0 and body 1"):
        wb.solve_mobility(pair, shear_rate=1.0, options=bare)
    with pytest.warns(wb.ContactResolutionWarning, match="In float32, GMRES stalls"):
        try:
            wb.solve_mobility([wb.Body(sphere, position=(0, 0, 1.03))], shear_rate=1.0,
                              options=wb.SolverOptions(contact_refinement=0.0, dtype="float32", tolerance=1e-6))
        except wb.ConvergenceError:
            pass  # the stall the warning announces
    solver = wb.MobilitySolver(shear_rate=1.0, options=bare)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for z in (1.03, 1.031, 1.032):
            solver.solve([wb.Body(sphere, position=(0, 0, z))])
    assert len([w for w in caught if issubclass(w.category, wb.ContactResolutionWarning)]) == 1
    limit = WARN_FRACTION * 0.2755  # the k = 4 sphere's element radius
    for gap, expected in ((1.2 * limit, {}), (0.8 * limit, {(0, WALL)})):
        nodes = sphere.element_nodes() + np.array([0, 0, 1 + gap])
        _, unresolved, _ = refine_near_contact([nodes], True, 1.1)
        assert set(unresolved) == set(expected)


def test_block_jacobi_preconditioner_matches_plain_gmres_and_is_kept_for_fixed_bodies():
    """The box-shaped adherent cell (scenes/adherent_box.q9, flat base 0.25 um above the wall,
    not refined) made plain GMRES crawl (956 iterations to 1e-8 with two boxes, fig. 5.12): with the
    exact inverse of each body's own block it needs a few tens, gives the same motion, and the
    fixed cell's LU factors are computed once and kept while only the free cell moves; the free
    cell's are taken from the solver's store while it moves along the wall (the same block,
    hydro/block_factors.py) and computed anew at another height."""
    from pathlib import Path

    box = wb.mesh.load(Path(__file__).resolve().parents[2] / "scenes" / "adherent_box.q9")
    free = wb.mesh.sphere(5e-6, 2)
    adherent = wb.Body(box, position=(0.0, 0.0, 3.25e-6), fixed=True)
    plain = wb.MobilitySolver(100.0, 1.2e-3, options=wb.SolverOptions(refine_fixed_at_wall=False, precondition=False, max_iterations=3000))
    solver = wb.MobilitySolver(100.0, 1.2e-3, options=wb.SolverOptions(refine_fixed_at_wall=False))
    factors = None
    for x in (-20e-6, -19e-6):  # far enough that the box is not refined for the free cell
        bodies = [wb.Body(free, position=(x, 3.5e-6, 11e-6)), adherent]
        sol = solver.solve(bodies)
        if factors is None:
            reference = plain.solve(bodies)
            np.testing.assert_allclose(sol.velocity, reference.velocity, rtol=0,
                                       atol=1e-7 * np.abs(reference.velocity).max())
            assert sol.iterations * 10 < reference.iterations
        system = solver._last[0]
        if factors is not None:
            assert system.factors[1] is factors  # the fixed cell's LU, kept
            assert system.factors[0] is first_free  # the free cell's, from the store
        factors, first_free = system.factors[1], system.factors[0]
    solver.solve([wb.Body(free, position=(-19e-6, 3.5e-6, 11.5e-6)), adherent])
    assert solver._last[0].factors[1] is factors and solver._last[0].factors[0] is not first_free


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")  # unrefined on purpose: a short test
def test_block_jacobi_preconditioner_in_matrix_free_mode():
    """Matrix-free operators keep the preconditioner: each body's own block is assembled alone
    (its integrals are those of the whole operator's diagonal block), so the box-shaped adherent
    cell converges as fast as with the assembled matrix, to the same motion."""
    from pathlib import Path

    box = wb.mesh.load(Path(__file__).resolve().parents[2] / "scenes" / "adherent_box.q9")
    bodies = [wb.Body(wb.mesh.sphere(5e-6, 2), position=(-20e-6, 3.5e-6, 11e-6)),
              wb.Body(box, position=(0.0, 0.0, 3.25e-6), fixed=True)]
    dense = wb.solve_mobility(bodies, 100.0, 1.2e-3, options=wb.SolverOptions(operator="dense", contact_refinement=0.0))
    free = wb.solve_mobility(bodies, 100.0, 1.2e-3, options=wb.SolverOptions(operator="matrix_free", contact_refinement=0.0))
    assert free.operator_mode == "matrix_free"
    assert free.iterations <= dense.iterations + 1 and free.iterations < 30  # plain GMRES: hundreds
    np.testing.assert_allclose(free.velocity, dense.velocity, rtol=0, atol=1e-7 * np.abs(dense.velocity).max())
    np.testing.assert_allclose(free.force, dense.force, rtol=0, atol=1e-7 * np.abs(dense.force).max())


def test_float32_converges_with_its_default_tolerance():
    """dtype="float32" needs no tolerance of its own: the default follows the precision (1e-6;
    float32 products cannot reach float64's 1e-8) and agrees with float64 to single precision."""
    d = wb.solve_mobility(_scene(), shear_rate=1.0, viscosity=1e-3)
    s = wb.solve_mobility(_scene(), shear_rate=1.0, viscosity=1e-3, options=wb.SolverOptions(dtype="float32"))
    assert s.converged and s.residual < 1e-5 and d.residual < 1e-7
    np.testing.assert_allclose(s.velocity, d.velocity, atol=2e-5 * np.abs(d.velocity).max())
    assert wb.MobilitySolver(options=wb.SolverOptions(dtype="float32")).options.tolerance == 1e-6
    assert wb.MobilitySolver().options.tolerance == 1e-8
    with pytest.raises(ValueError, match="dtype: 'float16' is not one of"):
        wb.MobilitySolver(options=wb.SolverOptions(dtype="float16"))


def test_kept_system_is_never_taken_for_a_new_mesh():
    """The solver keeps the system of its last bodies while they stay the same. A new mesh in
    the same place is not the same body, even where CPython hands the new mesh the address (the
    id) of a collected one: the solver holds the meshes of its key, so they are not collected,
    and a mesh of another shape gets its own answer."""
    import gc
    import weakref

    solver = wb.MobilitySolver(shear_rate=1.0, viscosity=1.0)
    first = wb.mesh.sphere(1.0, 2)
    held = weakref.ref(first)
    old_id = id(first)
    sphere_motion = solver.solve([wb.Body(first, position=(0, 0, 1.5))]).velocity[0, 0]
    del first
    gc.collect()
    assert held() is not None  # kept alive by the solver's key: its id cannot come back
    for _ in range(200):  # try to get a new mesh at the old address anyway
        candidate = wb.mesh.spheroid(1.0, 0.5, subdivisions=2)
        if id(candidate) == old_id:
            break
    flat = solver.solve([wb.Body(candidate, position=(0, 0, 1.5))]).velocity[0, 0]
    fresh = wb.solve_mobility([wb.Body(candidate, position=(0, 0, 1.5))], shear_rate=1.0, viscosity=1.0).velocity[0, 0]
    assert flat == pytest.approx(fresh, rel=1e-7) and abs(flat / sphere_motion - 1) > 1e-3
