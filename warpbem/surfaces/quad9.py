"""Host-side geometry of QUAD9 elements (9-node biquadratic Lagrange quadrilaterals).

Node order on the reference square [-1, 1]^2 (seen from outside the body, counter-clockwise,
so that x_s x x_t points out of the body):

    3 --- 6 --- 2        corners 0-3, mid-edge nodes 4-7, centre node 8
    |           |
    7     8     5        (s, t) of node a: REFERENCE_NODES[a]
    |           |
    0 --- 4 --- 1

The device copy of the same map (with second derivatives) is ``kernels/elements.py``;
``tests/unit/test_quad9.py`` checks that the two agree.
"""

from __future__ import annotations

import functools

import numpy as np

REFERENCE_NODES = np.array(
    [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], dtype=float
)

# the centre node of the 9-node element, (s, t) = (0, 0): the constant density's collocation point
CENTRE_NODE = 8


def _lagrange_1d(u):
    """Quadratic Lagrange basis on the nodes -1, 0, 1 and its derivative; shapes (..., 3)."""
    u = np.asarray(u, dtype=float)[..., None]
    values = np.concatenate([0.5 * u * (u - 1.0), 1.0 - u * u, 0.5 * u * (u + 1.0)], axis=-1)
    slopes = np.concatenate([u - 0.5, -2.0 * u, u + 0.5], axis=-1)
    return values, slopes


_INDEX_1D = (REFERENCE_NODES + 1).astype(int)  # which 1-D basis function (0, 1, 2) per node


def shape_functions(s, t):
    """Values N_a(s, t) and derivatives dN_a/ds, dN_a/dt, each of shape (..., 9)."""
    ls, dls = _lagrange_1d(s)
    lt, dlt = _lagrange_1d(t)
    i, j = _INDEX_1D[:, 0], _INDEX_1D[:, 1]
    return ls[..., i] * lt[..., j], dls[..., i] * lt[..., j], ls[..., i] * dlt[..., j]


def cross(a, b) -> np.ndarray:
    """np.cross of two (..., 3) arrays, the same products and differences bit for bit, without
    its axis handling, which took most of its time on one solve's small arrays (22 against 8 us)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _read_only(*arrays):
    for a in arrays:
        a.flags.writeable = False
    return arrays


@functools.lru_cache(maxsize=None)
def gauss_legendre(order: int):
    """1-D Gauss-Legendre rule on [-1, 1], points and weights (cached: NumPy's eigenvalue
    computation of it took a tenth of a small solve)."""
    return _read_only(*np.polynomial.legendre.leggauss(order))


def gauss_legendre_square(order: int):
    """Tensor Gauss-Legendre rule on [-1, 1]^2: points (order^2, 2) and weights (order^2,)."""
    if int(order) != order or order < 1:
        raise ValueError(f"quadrature order must be a positive integer, got {order!r}")
    return _square_rule(int(order))


@functools.lru_cache(maxsize=None)
def _square_rule(order: int):
    x, w = gauss_legendre(order)
    s, t = np.meshgrid(x, x, indexing="ij")
    return _read_only(np.stack([s.ravel(), t.ravel()], axis=1), np.outer(w, w).ravel())


@functools.lru_cache(maxsize=None)
def _shapes_at_gauss_points(order: int):
    points, weights = gauss_legendre_square(order)
    return _read_only(*shape_functions(points[:, 0], points[:, 1]), weights)


def surface_quadrature(element_nodes: np.ndarray, order: int):
    """Quadrature points on every element.

    element_nodes: (E, 9, 3). Returns positions (E, Q, 3) and vector area weights (E, Q, 3),
    the latter equal to w_q (x_s x x_t): the outward normal times the surface Jacobian times
    the Gauss weight, so that sum_q f(x_q) |a_q| approximates the surface integral of f.
    """
    if int(order) != order or order < 1:
        raise ValueError(f"quadrature order must be a positive integer, got {order!r}")
    n, ns, nt, weights = _shapes_at_gauss_points(int(order))
    positions = np.einsum("qa,eai->eqi", n, element_nodes)
    x_s = np.einsum("qa,eai->eqi", ns, element_nodes)
    x_t = np.einsum("qa,eai->eqi", nt, element_nodes)
    return positions, cross(x_s, x_t) * weights[None, :, None]


def unit_normals(element_nodes: np.ndarray, s, t) -> np.ndarray:
    """Unit outward normals (E, Q, 3) at the points (s, t) (each of shape (Q,)) of every element."""
    _, ns, nt = shape_functions(np.asarray(s, dtype=float), np.asarray(t, dtype=float))
    return normals_from_slopes(element_nodes, ns, nt)


def normals_from_slopes(element_nodes: np.ndarray, ns: np.ndarray, nt: np.ndarray) -> np.ndarray:
    """Unit outward normals (E, Q, 3) of every element at the points where the shape functions'
    derivatives are ``ns`` and ``nt`` ((Q, 9) each; remembered by callers for fixed points)."""
    normal = cross(np.einsum("qa,eai->eqi", ns, element_nodes), np.einsum("qa,eai->eqi", nt, element_nodes))
    return normal / np.linalg.norm(normal, axis=-1, keepdims=True)


@functools.lru_cache(maxsize=None)
def _slopes_at_centre():
    return _read_only(*shape_functions(np.zeros(1), np.zeros(1))[1:])


def centre_normals(element_nodes: np.ndarray) -> np.ndarray:
    """Unit outward normals (E, 3) at the element centres (s = t = 0), the collocation points."""
    return normals_from_slopes(element_nodes, *_slopes_at_centre())[:, 0]
