"""The boundary-integral operators (warpbem/hydro/operators/): identity, quadrature, discrete forms."""

import numpy as np
import pytest

from warpbem import Body, mesh, runtime
from warpbem.kernels import launch
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.completed_double_layer import CompletedDoubleLayer
from warpbem.hydro.operators import BoundaryOperator, QuadratureOptions, choose_mode, discrete_form


def make_operator(bodies, wall, mode="dense", device="cpu", kind="double_layer", **quadrature):
    options = QuadratureOptions(**{"order": 3, **quadrature})
    geometry = SurfaceGeometry.from_bodies(bodies, options.order, 1.0, wall)
    return discrete_form(BoundaryOperator(geometry, wall, options, kind), mode, device)


def two_spheres_near_wall():
    s = mesh.sphere(1.0, 3)
    return [Body(s, position=(0, 0, 1.2)), Body(s, position=(2.1, 0.3, 1.5))]


@pytest.mark.parametrize("mode", ["dense", "matrix_free"])
def test_translations_are_annihilated_exactly(mode, device):
    # constant-density identity (thesis ch. 3.3): int_S Sigma.n dS = -1/2 on S, wall included,
    # so (1/2 + D) e_l = 0 on the body that carries it, to round-off
    op = make_operator(two_spheres_near_wall(), True, mode, device)
    n0 = op.geometry.body_ranges[0, 1]
    for axis in range(3):
        q = np.zeros((op.geometry.n_elements, 3))
        q[:n0, axis] = 1.0
        out = op.matvec(q.ravel()).reshape(-1, 3)
        assert np.abs(out[:n0]).max() < 1e-12
        # on the other body the double layer of a rigid motion vanishes up to quadrature error
        assert np.abs(out[n0:]).max() < 2e-3


@pytest.mark.parametrize("kind", ["double_layer", "adjoint_double_layer", "single_layer", "elastic_rotation"])
def test_dense_and_matrix_free_agree(device, rng, kind):
    """Every kernel kind, its self blocks (identity, the double layer's, Duffy) included."""
    dense = make_operator(two_spheres_near_wall(), True, "dense", device, kind)
    free = make_operator(two_spheres_near_wall(), True, "matrix_free", device, kind)
    q = rng.standard_normal(dense.size)
    np.testing.assert_allclose(free.matvec(q), dense.matvec(q), rtol=0, atol=1e-12 * np.abs(q).sum())


def test_every_discrete_form_is_a_linear_operator_of_the_same_matrix(rng):
    """The dense form's assembled matrix, the direct sum's and the treecode's products with
    every unit vector (``to_dense``) are one operator: the direct sum to round-off, the treecode
    (one leaf here holds every element, so all is near field) likewise; and each answers
    SciPy's LinearOperator protocol (``@``) as its own ``apply``."""
    geometry = SurfaceGeometry.from_bodies(two_spheres_near_wall(), 2, 1.0, True)
    description = BoundaryOperator(geometry, True)
    forms = {mode: discrete_form(description, mode) for mode in ("dense", "matrix_free", "treecode")}
    matrices = {mode: form.to_dense() for mode, form in forms.items()}
    scale = np.abs(matrices["dense"]).max()
    for mode in ("matrix_free", "treecode"):
        np.testing.assert_allclose(matrices[mode], matrices["dense"], rtol=0, atol=1e-13 * scale)
    q = rng.standard_normal(description.size)
    for form in forms.values():
        np.testing.assert_array_equal(form @ q, form.apply(q))
    with pytest.raises(ValueError, match="double layer only"):
        discrete_form(BoundaryOperator(geometry, True, kind="single_layer"), "treecode")
    with pytest.raises(ValueError, match="operator kind"):
        BoundaryOperator(geometry, True, kind="stokeslet")


def test_cpu_row_split_is_deterministic(monkeypatch, rng):
    q = rng.standard_normal(make_operator(two_spheres_near_wall(), True).size)
    results = []
    for threads in (1, 2, 3):
        monkeypatch.setattr(launch, "cpu_threads", lambda: threads)
        results.append(make_operator(two_spheres_near_wall(), True, "matrix_free").matvec(q))
        results.append(make_operator(two_spheres_near_wall(), True, "dense").matvec(q))
    # matrix-free: every row is summed by one thread in the same order, however rows are split
    np.testing.assert_array_equal(results[0], results[2])
    np.testing.assert_array_equal(results[0], results[4])
    # dense: the same matrix whatever the split, applied by the same BLAS call
    np.testing.assert_array_equal(results[1], results[3])
    np.testing.assert_array_equal(results[1], results[5])
    np.testing.assert_allclose(results[1], results[0], rtol=0, atol=1e-12 * np.abs(q).sum())


def test_blas_runs_one_thread_beside_the_cpu_thread_pool_and_every_core_for_large_factors(monkeypatch):
    """kernels/launch.py: after a threaded CPU launch BLAS keeps one thread (its spinning threads
    would take cores from the launches); a factorization of BLAS_ALL_CORES_ROWS rows or more
    gets every core inside ``blas_on_all_cores``, a smaller one does not."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    monkeypatch.setattr(launch, "cpu_threads", lambda: 2)

    def blas_threads():
        return {info["num_threads"] for info in threadpoolctl.threadpool_info() if info["user_api"] == "blas"}

    op = make_operator(two_spheres_near_wall(), True, "matrix_free")
    op.matvec(np.ones(op.size))  # launches through launch_rows
    assert blas_threads() == {1}
    with launch.blas_on_all_cores(launch.BLAS_ALL_CORES_ROWS):
        assert blas_threads() == {2}
    assert blas_threads() == {1}
    with launch.blas_on_all_cores(launch.BLAS_ALL_CORES_ROWS - 1):
        assert blas_threads() == {1}


def _block(op, row_body, col_body):
    a0, a1 = op.geometry.body_ranges[row_body]
    b0, b1 = op.geometry.body_ranges[col_body]
    return op.to_dense()[3 * a0:3 * a1, 3 * b0:3 * b1]


@pytest.mark.parametrize("wall, gap", [(False, 1e-2), (False, 1e-3), (True, 1e-2), (True, 1e-3)])
def test_adaptive_quadrature_resolves_nearly_singular_elements(wall, gap):
    """Two spheres a gap apart (both a gap above the wall when ``wall``). For poles on sphere A
    the double layer of a constant density over sphere B vanishes exactly, int_B Sigma.n dS = 0
    for a pole outside B (Pozrikidis 1992 eq. 4.1.7), however close: the row sums of block (A, B)
    measure the quadrature error of the nearly singular entries."""
    s = mesh.sphere(1.0, 3)
    z = 1.0 + gap if wall else 0.0
    bodies = [Body(s, position=(0, 0, z)), Body(s, position=(2.0 + gap, 0, z))]
    errors = {}
    for adaptive in (True, False):
        op = make_operator(bodies, wall, adaptive=adaptive, max_level=16)
        block = _block(op, 0, 1).reshape(-1, 3, op.geometry.body_ranges[1, 1] - op.geometry.body_ranges[1, 0], 3)
        errors[adaptive] = np.abs(block.sum(axis=2)).max()
    assert errors[True] < 2e-5
    assert errors[False] > 20 * errors[True]


def test_adaptive_quadrature_converges_with_order():
    """Entries near contact with order 3 versus order 6 and a stricter near-field criterion."""
    bodies = [Body(mesh.sphere(1.0, 2), position=(0, 0, 1.01)), Body(mesh.sphere(1.0, 2), position=(2.01, 0, 1.01))]
    low = _block(make_operator(bodies, True, order=3), 0, 1)
    high = _block(make_operator(bodies, True, order=6, near_factor=4.0, max_level=16), 0, 1)
    assert np.abs(low - high).max() < 1e-3 * np.abs(high).max()


def test_cdl_spectrum_lies_in_the_right_half_plane():
    # thesis eq. 2.16 with our sign and scaling: eigenvalues of 1/2 + D^PV + P in (0, 1]
    bodies = [Body(mesh.sphere(1.0, 2), position=(0, 0, 1.3))]
    op = make_operator(bodies, True)
    system = CompletedDoubleLayer(op.geometry, op, [False])
    matrix = np.array([system.linear_operator().matvec(e) for e in np.eye(system.size)]).T
    eig = np.linalg.eigvals(matrix)
    assert eig.real.min() > 0.05
    assert eig.real.max() < 1.0 + 1e-6


def test_auto_mode_follows_the_one_rule():
    """mode="auto" of any operator (the traction's too) is choose_mode's: dense while the
    matrix takes at most a quarter of the device's memory, else the treecode for the double
    layer and matrix-free for the other kinds."""
    bodies = two_spheres_near_wall()
    geometry = SurfaceGeometry.from_bodies(bodies, 3, 1.0, True)
    assert discrete_form(BoundaryOperator(geometry, True)).mode == "dense"  # 0.84 MB here
    assert discrete_form(BoundaryOperator(geometry, True, kind="adjoint_double_layer")).mode == "dense"
    too_large = int(np.sqrt(runtime.total_memory(runtime.resolve_device("cpu")) / 8)) + 1
    assert choose_mode(too_large) == "treecode"
    assert choose_mode(too_large, kind="single_layer") == "matrix_free"


@pytest.mark.parametrize("mode", ["dense", "matrix_free"])
@pytest.mark.parametrize("kind, exact", [("single_layer", 2.0 / 3.0), ("inverse_distance", 4.0 * np.pi)])
def test_single_layers_of_a_uniform_density_on_a_sphere(mode, kind, exact, device):
    """On a unit sphere, for xi on it, int G dS = 2a/3 I (G = (I/r + r r/r^3) / 8 pi: a uniform
    force density moves the sphere at F / 6 pi mu a, Stokes) and int dS / r = 4 pi a: the
    weakly singular self elements by Duffy triangles, the rest by the element rules (k = 4:
    3.6e-4 and 6.2e-5 measured)."""
    options = QuadratureOptions(order=2)
    geometry = SurfaceGeometry.from_bodies([Body(mesh.sphere(1.0, 4))], 2, 1.0, False)
    op = discrete_form(BoundaryOperator(geometry, False, options, kind), mode, device)
    density = np.tile([0.3, -0.2, 1.0], geometry.n_elements)
    u = op.matvec(density).reshape(-1, 3)
    assert np.abs(u - exact * density[:3]).max() < 1e-3 * exact


@pytest.mark.parametrize("kind, density_order", [("double_layer", 1), ("double_layer", 2), ("single_layer", 1)])
def test_self_blocks_written_on_the_device_equal_the_host_ones(kind, density_order):
    """The Warp kernels that write the self blocks where the matrix lives (CUDA: no round trip
    through the host), run here on the CPU, give the host's BLAS row sums (or Duffy blocks)."""
    geometry = SurfaceGeometry.from_bodies(two_spheres_near_wall(), 2, 1.0, True, density_order=density_order)
    host = discrete_form(BoundaryOperator(geometry, True, kind=kind), "dense")
    device = discrete_form(BoundaryOperator(geometry, True, kind=kind), "dense")
    expected = host.to_dense()
    matrix = device.matrix()
    values = matrix.numpy()
    a, k = np.arange(geometry.n_points)[:, None, None], np.arange(3)
    diagonal = (3 * a + k[None, :, None], 3 * a + k[None, None, :])
    values[diagonal] = 0.0
    device._device_self_blocks(matrix, range(len(geometry.body_ranges)))
    assert np.abs(expected[diagonal]).max() > 0.1
    np.testing.assert_allclose(values, expected, rtol=0, atol=1e-13 * np.abs(expected).max())


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_the_gpu_dense_product_kernel_matches_blas(rng, dtype):
    """``dense_matvec``, the product CUDA uses (one thread block per row, chunks of 256 entries,
    kernels/assembly.py), run on the CPU against NumPy's BLAS on the same matrix; a row length
    that is not a multiple of the chunk exercises the padded last chunk."""
    geometry = SurfaceGeometry.from_bodies(two_spheres_near_wall(), 2, 1.0, True)
    op = discrete_form(BoundaryOperator(geometry, True, dtype=dtype), "dense", "cpu")
    assert op.size % 256 != 0
    q = rng.standard_normal(op.size)
    blas = op.matvec(q)
    np.testing.assert_allclose(op.device_matvec(q).numpy(), blas, rtol=0,
                               atol=(1e-12 if dtype == "float64" else 1e-4) * np.abs(blas).max())
