"""Closest points between QUAD9 surfaces, and between a QUAD9 surface and the wall z = 0.

For a candidate pair of elements (a of body A, b of body B) the squared distance
f(s1, t1, s2, t2) = |x_a(s1, t1) - x_b(s2, t2)|^2 / 2 is minimised by Newton's method with the
exact Hessian (second derivatives of the biquadratic map), Levenberg damping, backtracking and
clipping to the parameter squares; against the wall f = z_a(s, t)^2 / 2, and against a point p
(a receptor tip near a ligand-bearing cell) f = |x_a(s, t) - p|^2 / 2, both by one function. Newton converges
quadratically, so the gap is exact to round-off and varies smoothly as bodies move: the
electrostatic repulsion (thesis eq. 3.1) changes e-fold over 1/tau = 0.5 nm and cannot use a
sampled gap (sampling errors near contact are tens of nanometres for 96-element cells).
Newton rather than alternating projections, which converge at the rate (a/(a + gap))^2 per
sweep, too slowly near contact. The launchers below the kernels fill the caller's arrays.
"""

import functools
from types import SimpleNamespace

import warp as wp

from .elements import make_element_functions

NEWTON_ITERATIONS = 24
BACKTRACKS = 8


@functools.lru_cache(maxsize=None)
def build_contact_kernels(dtype) -> SimpleNamespace:
    el = make_element_functions(dtype)
    vec3 = el.vec3
    vec4 = wp.types.vector(4, dtype)
    mat44 = wp.types.matrix((4, 4), dtype)
    vec2 = wp.types.vector(2, dtype)
    mat22 = wp.types.matrix((2, 2), dtype)

    @wp.func
    def clip(u: dtype):
        return wp.clamp(u, dtype(-1.0), dtype(1.0))

    @wp.func
    def pair_distance2(nodes_a: wp.array(dtype=vec3), ea: int, nodes_b: wp.array(dtype=vec3), eb: int, u: vec4):
        xa, unused_a = el.quad9_point(nodes_a, ea, u[0], u[1])
        xb, unused_b = el.quad9_point(nodes_b, eb, u[2], u[3])
        return wp.length_sq(xa - xb)

    @wp.func
    def newton_pair(nodes_a: wp.array(dtype=vec3), ea: int, nodes_b: wp.array(dtype=vec3), eb: int):
        u = vec4()
        f = pair_distance2(nodes_a, ea, nodes_b, eb, u)
        for it in range(NEWTON_ITERATIONS):
            xa, as_, at, ass, ast, att = el.quad9_second_order(nodes_a, ea, u[0], u[1])
            xb, bs, bt, bss, bst, btt = el.quad9_second_order(nodes_b, eb, u[2], u[3])
            r = xa - xb
            g = vec4(wp.dot(r, as_), wp.dot(r, at), -wp.dot(r, bs), -wp.dot(r, bt))
            h = mat44(
                wp.dot(as_, as_) + wp.dot(r, ass), wp.dot(as_, at) + wp.dot(r, ast), -wp.dot(as_, bs), -wp.dot(as_, bt),
                wp.dot(as_, at) + wp.dot(r, ast), wp.dot(at, at) + wp.dot(r, att), -wp.dot(at, bs), -wp.dot(at, bt),
                -wp.dot(as_, bs), -wp.dot(at, bs), wp.dot(bs, bs) - wp.dot(r, bss), wp.dot(bs, bt) - wp.dot(r, bst),
                -wp.dot(as_, bt), -wp.dot(at, bt), wp.dot(bs, bt) - wp.dot(r, bst), wp.dot(bt, bt) - wp.dot(r, btt))
            scale = (h[0, 0] + h[1, 1] + h[2, 2] + h[3, 3]) * dtype(0.25)
            step = -(wp.inverse(h + wp.identity(n=4, dtype=dtype) * (scale * dtype(1e-8))) * g)
            if wp.dot(step, g) >= dtype(0.0):  # not a descent direction (far from the minimum)
                step = -g / scale
            alpha = dtype(1.0)
            moved = int(0)
            for k in range(BACKTRACKS):
                if moved == 0:
                    trial = vec4(clip(u[0] + alpha * step[0]), clip(u[1] + alpha * step[1]),
                                 clip(u[2] + alpha * step[2]), clip(u[3] + alpha * step[3]))
                    f_trial = pair_distance2(nodes_a, ea, nodes_b, eb, trial)
                    if f_trial < f:
                        u = trial
                        f = f_trial
                        moved = 1
                    alpha = alpha * dtype(0.5)
            if moved == 0:
                break
        return u

    @wp.func
    def newton_masked(nodes_a: wp.array(dtype=vec3), ea: int, target: vec3, mask: vec3):
        """The (s, t) minimising |mask * (x_a(s, t) - target)|^2 (mask of 0s and 1s): the wall z = 0
        with mask (0, 0, 1), a point with mask (1, 1, 1)."""
        u = vec2()
        xa, unused = el.quad9_point(nodes_a, ea, u[0], u[1])
        r0 = wp.cw_mul(mask, xa - target)
        f = wp.dot(r0, r0)
        for it in range(NEWTON_ITERATIONS):
            x, xs, xt, xss, xst, xtt = el.quad9_second_order(nodes_a, ea, u[0], u[1])
            r = wp.cw_mul(mask, x - target)
            ms = wp.cw_mul(mask, xs)
            mt = wp.cw_mul(mask, xt)
            g = vec2(wp.dot(r, xs), wp.dot(r, xt))
            h = mat22(wp.dot(ms, ms) + wp.dot(r, xss), wp.dot(ms, mt) + wp.dot(r, xst),
                      wp.dot(ms, mt) + wp.dot(r, xst), wp.dot(mt, mt) + wp.dot(r, xtt))
            scale = wp.abs(h[0, 0] + h[1, 1]) * dtype(0.5) + dtype(1e-30)
            step = -(wp.inverse(h + wp.identity(n=2, dtype=dtype) * (scale * dtype(1e-8))) * g)
            if wp.dot(step, g) >= dtype(0.0):
                step = -g / scale
            alpha = dtype(1.0)
            moved = int(0)
            for k in range(BACKTRACKS):
                if moved == 0:
                    trial = vec2(clip(u[0] + alpha * step[0]), clip(u[1] + alpha * step[1]))
                    xt2, unused2 = el.quad9_point(nodes_a, ea, trial[0], trial[1])
                    rt = wp.cw_mul(mask, xt2 - target)
                    if wp.dot(rt, rt) < f:
                        u = trial
                        f = wp.dot(rt, rt)
                        moved = 1
                    alpha = alpha * dtype(0.5)
            if moved == 0:
                break
        return u

    @wp.kernel(enable_backward=False, module="unique")
    def closest_points(nodes_a: wp.array(dtype=vec3), element_a: wp.array(dtype=int),
                       nodes_b: wp.array(dtype=vec3), element_b: wp.array(dtype=int), to_wall: int,
                       point_a: wp.array(dtype=vec3), point_b: wp.array(dtype=vec3)):
        """For candidate pair i: the closest points of element_a[i] of surface A and of
        element_b[i] of surface B, or of the wall z = 0 when to_wall is 1."""
        i = wp.tid()
        ea = element_a[i]
        if to_wall == 1:
            u = newton_masked(nodes_a, ea, vec3(), vec3(dtype(0.0), dtype(0.0), dtype(1.0)))
            xa, unused = el.quad9_point(nodes_a, ea, u[0], u[1])
            point_a[i] = xa
            point_b[i] = vec3(xa[0], xa[1], dtype(0.0))
        else:
            eb = element_b[i]
            v = newton_pair(nodes_a, ea, nodes_b, eb)
            xa2, unused3 = el.quad9_point(nodes_a, ea, v[0], v[1])
            xb2, unused4 = el.quad9_point(nodes_b, eb, v[2], v[3])
            point_a[i] = xa2
            point_b[i] = xb2

    @wp.kernel(enable_backward=False, module="unique")
    def closest_to_points(nodes_a: wp.array(dtype=vec3), element_a: wp.array(dtype=int),
                          targets: wp.array(dtype=vec3), point_a: wp.array(dtype=vec3)):
        """For candidate pair i: the point of element_a[i] of surface A closest to targets[i]."""
        i = wp.tid()
        one = dtype(1.0)
        u = newton_masked(nodes_a, element_a[i], targets[i], vec3(one, one, one))
        xa, unused = el.quad9_point(nodes_a, element_a[i], u[0], u[1])
        point_a[i] = xa

    return SimpleNamespace(closest_points=closest_points, closest_to_points=closest_to_points, vec3=vec3)


def closest_points(kernels, device, n: int, nodes_a, element_a, nodes_b, element_b, to_wall: int, point_a, point_b):
    """``point_a`` and ``point_b`` of the n candidate pairs (to the wall when ``to_wall`` is 1)."""
    wp.launch(kernels.closest_points, dim=n, device=device,
              inputs=[nodes_a, element_a, nodes_b, element_b, to_wall, point_a, point_b])


def closest_to_points(kernels, device, n: int, nodes_a, element_a, targets, point_a):
    """``point_a`` of the n candidate pairs."""
    wp.launch(kernels.closest_to_points, dim=n, device=device, inputs=[nodes_a, element_a, targets],
              outputs=[point_a])
