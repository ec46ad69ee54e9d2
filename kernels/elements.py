"""QUAD9 element geometry on the device: the biquadratic Lagrange map of ``warpbem/quad9.py``
(node order there) with its first and second derivatives, shared by the boundary integrals
(``assembly.py``) and the closest-point search (``contact.py``)."""

import functools
from types import SimpleNamespace

import warp as wp

# (s, t) index (0, 1, 2 for -1, 0, 1) of each QUAD9 node, in the order of
# warpbem.surfaces.quad9.REFERENCE_NODES: corners 0-3 counter-clockwise, mid-edges 4-7, centre 8
_NODE_INDEX = wp.types.vector(9, wp.int32)
NODE_S = wp.constant(_NODE_INDEX(0, 2, 2, 0, 1, 2, 1, 0, 1))
NODE_T = wp.constant(_NODE_INDEX(0, 0, 2, 2, 0, 1, 2, 1, 1))


@functools.lru_cache(maxsize=None)
def make_element_functions(dtype) -> SimpleNamespace:
    vec3 = wp.types.vector(3, dtype)

    @wp.func
    def lagrange(u: dtype, node: int):
        # quadratic Lagrange basis on the nodes -1, 0, 1 (index node = 0, 1, 2)
        half = dtype(0.5)
        one = dtype(1.0)
        if node == 0:
            return half * u * (u - one)
        if node == 1:
            return one - u * u
        return half * u * (u + one)

    @wp.func
    def lagrange_slope(u: dtype, node: int):
        half = dtype(0.5)
        if node == 0:
            return u - half
        if node == 1:
            return dtype(-2.0) * u
        return u + half

    @wp.func
    def lagrange_curvature(node: int):
        # second derivative of the quadratic basis: constant 1, -2, 1
        if node == 1:
            return dtype(-2.0)
        return dtype(1.0)

    @wp.func
    def quad9_frame(nodes: wp.array(dtype=vec3), element: int, s: dtype, t: dtype):
        """Position and tangents x, x_s, x_t at (s, t) of an element. The 1-D values and slopes
        are taken once per direction rather than once per node (the same products, bit for bit):
        this map is most of an adaptive assembly's arithmetic."""
        ls = vec3(lagrange(s, 0), lagrange(s, 1), lagrange(s, 2))
        lt = vec3(lagrange(t, 0), lagrange(t, 1), lagrange(t, 2))
        ds = vec3(lagrange_slope(s, 0), lagrange_slope(s, 1), lagrange_slope(s, 2))
        dt = vec3(lagrange_slope(t, 0), lagrange_slope(t, 1), lagrange_slope(t, 2))
        x = vec3()
        xs = vec3()
        xt = vec3()
        for a in range(9):
            p = nodes[element * 9 + a]
            i = NODE_S[a]
            j = NODE_T[a]
            x += p * (ls[i] * lt[j])
            xs += p * (ds[i] * lt[j])
            xt += p * (ls[i] * dt[j])
        return x, xs, xt

    @wp.func
    def quad9_point(nodes: wp.array(dtype=vec3), element: int, s: dtype, t: dtype):
        """Position and x_s x x_t (outward normal times Jacobian) at (s, t) of an element."""
        x, xs, xt = quad9_frame(nodes, element, s, t)
        return x, wp.cross(xs, xt)

    @wp.func
    def quad9_second_order(nodes: wp.array(dtype=vec3), element: int, s: dtype, t: dtype):
        """x, x_s, x_t, x_ss, x_st, x_tt at (s, t): the data of a Newton step on the surface."""
        x, xs, xt = quad9_frame(nodes, element, s, t)
        xss = vec3()
        xst = vec3()
        xtt = vec3()
        for a in range(9):
            p = nodes[element * 9 + a]
            i = NODE_S[a]
            j = NODE_T[a]
            xss += p * (lagrange_curvature(i) * lagrange(t, j))
            xst += p * (lagrange_slope(s, i) * lagrange_slope(t, j))
            xtt += p * (lagrange(s, i) * lagrange_curvature(j))
        return x, xs, xt, xss, xst, xtt

    return SimpleNamespace(vec3=vec3, lagrange=lagrange, lagrange_slope=lagrange_slope,
                           quad9_point=quad9_point, quad9_second_order=quad9_second_order)
