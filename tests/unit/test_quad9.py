"""QUAD9 shape functions, Gauss rules, and the device copy of the element map."""

import numpy as np
import pytest

from warpbem import mesh, runtime
from warpbem.surfaces import quad9


def test_shape_functions_interpolate_nodes_and_sum_to_one():
    s, t = quad9.REFERENCE_NODES.T
    n, ns, nt = quad9.shape_functions(s, t)
    np.testing.assert_allclose(n, np.eye(9), atol=1e-15)
    pts = np.random.default_rng(1).uniform(-1, 1, size=(50, 2))
    n, ns, nt = quad9.shape_functions(pts[:, 0], pts[:, 1])
    np.testing.assert_allclose(n.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(ns.sum(axis=1), 0.0, atol=1e-13)
    # biquadratic fields are reproduced exactly, with their derivatives
    f = lambda s, t: 1 + 2 * s - t + 3 * s * t - s**2 * t**2  # noqa: E731
    fn = f(*quad9.REFERENCE_NODES.T)
    np.testing.assert_allclose(n @ fn, f(pts[:, 0], pts[:, 1]), atol=1e-13)
    np.testing.assert_allclose(ns @ fn, 2 + 3 * pts[:, 1] - 2 * pts[:, 0] * pts[:, 1] ** 2, atol=1e-13)


@pytest.mark.parametrize("order", [1, 2, 3, 4, 6])
def test_gauss_rule_is_exact_to_degree_2n_minus_1(order):
    pts, w = quad9.gauss_legendre_square(order)
    deg = 2 * order - 1
    exact = (2.0 / (deg + 1)) ** 2 if deg % 2 == 0 else 0.0  # int s^deg t^deg over [-1,1]^2
    assert np.isclose(np.sum(w * pts[:, 0] ** deg * pts[:, 1] ** deg), exact, atol=1e-14)
    assert np.isclose(w.sum(), 4.0)
    with pytest.raises(ValueError, match="positive integer"):
        quad9.gauss_legendre_square(0)


def test_device_element_map_matches_host(device):
    wp = runtime.init()
    from warpbem.kernels.assembly import build_kernels

    k = build_kernels(wp.float64, False)
    vec3 = k.green.vec3
    nodes = mesh.spheroid(2.0, 0.6, subdivisions=2).element_nodes()
    params = np.random.default_rng(2).uniform(-1, 1, size=(len(nodes), 2))

    @wp.kernel(enable_backward=False, module="unique")
    def evaluate(nodes: wp.array(dtype=vec3), st: wp.array2d(dtype=wp.float64),
                 x: wp.array(dtype=vec3), a: wp.array(dtype=vec3)):
        e = wp.tid()
        p, area = k.quad9_point(nodes, e, st[e, 0], st[e, 1])
        x[e] = p
        a[e] = area

    d_nodes = wp.array(nodes.reshape(-1, 3), dtype=vec3, device=device)
    x = wp.zeros(len(nodes), dtype=vec3, device=device)
    a = wp.zeros(len(nodes), dtype=vec3, device=device)
    wp.launch(evaluate, dim=len(nodes), inputs=[d_nodes, wp.array(params, dtype=wp.float64, device=device), x, a],
              device=device)
    n, ns, nt = quad9.shape_functions(params[:, 0], params[:, 1])
    expected_x = np.einsum("ea,eai->ei", n, nodes)
    expected_a = np.cross(np.einsum("ea,eai->ei", ns, nodes), np.einsum("ea,eai->ei", nt, nodes))
    np.testing.assert_allclose(x.numpy(), expected_x, atol=1e-14)
    np.testing.assert_allclose(a.numpy(), expected_a, atol=1e-14)
