"""The far-field coupling of pairs of cells above the wall, from their surface tractions
compressed to a few point forces each (``warpbem/dynamics/far_field.py`` builds them).

Cell a's surface traction under a load (a unit force or torque, or the ambient flow) drives the
velocity u(x) = -sum_q G(x, y_q) w_q / mu at a point x far from it (eq. 2.18 of the thesis, the
point forces w_q = traction x area of its compressed stencil at y_q, the force the fluid exerts on
the cell, hence the minus sign); cell b, free and far from a, moves in that flow as the reciprocal
theorem says (Kim & Karrila 1991, sec. 5.3; the generalised Faxen law): its velocity and angular
velocity along basis load r are -sum_p v_p . u(x_p), v_p the traction x area of b under that
load. So the first reflection of the method of reflections is

    M_ba[r, c] = sum_p sum_q v_p^(r) . G(x_p, y_q) w_q^(c) / mu,

with G the wall's Green's function of ``greens.py`` (its 1 / (8 pi) included). One thread per
pair key: the coupling of a's seven source columns (six loads and the flow) onto b's six motions,
and the flow of b onto a's motions (G(y, x) = G(x, y)^T, Blake's tensor being reciprocal).
Each thread owns its output rows: deterministic on CPU and CUDA alike.
"""

import functools
from types import SimpleNamespace

import numpy as np
import warp as wp

from .greens import make_green_functions
from .launch import launch_rows

SOURCES = 7  # a cell's source columns: unit force x, y, z, unit torque x, y, z, the ambient flow
MOTIONS = 6  # a cell's motions: velocity, angular velocity
SPLIT_THREADS = 64  # launches at least this long are split over the CPU threads (each thread ~0.1 ms)


@functools.lru_cache(maxsize=None)
def build_far_field_kernels(dtype, wall: bool) -> SimpleNamespace:
    vec3 = wp.types.vector(3, dtype)
    sources = wp.types.matrix((3, SOURCES), dtype)  # a stencil point's forces, one column per source
    motions = wp.types.matrix((3, MOTIONS), dtype)  # the same point's forces of the six basis loads
    coupling = wp.types.matrix((MOTIONS, SOURCES), dtype)
    greens = make_green_functions(dtype, wall)

    @wp.kernel(enable_backward=False)
    def pair_couplings(first: int, points: wp.array2d(dtype=vec3), source_weights: wp.array2d(dtype=sources),
                       motion_weights: wp.array2d(dtype=motions), set_a: wp.array(dtype=int),
                       set_b: wp.array(dtype=int), offset: wp.array(dtype=vec3), inverse_viscosity: dtype,
                       out: wp.array(dtype=coupling), out_reverse: wp.array(dtype=vec3),
                       out_reverse_angular: wp.array(dtype=vec3)):
        k = first + wp.tid()
        a = set_a[k]
        b = set_b[k]
        shift = offset[k]
        n_points = points.shape[1]
        total = coupling()
        reverse = wp.vector(dtype(0.0), length=MOTIONS)
        unused = vec3()
        for p in range(n_points):
            x = points[b, p] + shift
            w = source_weights[b, p]
            flow_b = vec3(w[0, SOURCES - 1], w[1, SOURCES - 1], w[2, SOURCES - 1])  # b's flow column at x_p
            at_x = sources()
            for q in range(n_points):
                g = greens.stokeslet(x, unused, points[a, q])
                at_x += g * source_weights[a, q]
                # b's flow column onto a's motions: the velocity at y_q is G(y_q, x_p) w = G^T w
                reverse += wp.transpose(motion_weights[a, q]) * (wp.transpose(g) * flow_b)
            total += wp.transpose(motion_weights[b, p]) * at_x
        out[k] = total * inverse_viscosity
        out_reverse[k] = vec3(reverse[0], reverse[1], reverse[2]) * inverse_viscosity
        out_reverse_angular[k] = vec3(reverse[3], reverse[4], reverse[5]) * inverse_viscosity

    return SimpleNamespace(dtype=dtype, vec3=vec3, sources=sources, motions=motions, coupling=coupling,
                           pair_couplings=pair_couplings)


def pair_couplings(kernels, device, points, source_weights, motion_weights, set_a, set_b, offset,
                   viscosity: float):
    """(couplings (K, 6, 7), reverse flow motions (K, 6)) of the K pair keys (module docstring):
    host arrays in (``points`` (S, P, 3), ``source_weights`` (S, P, 3, 7), ``motion_weights``
    (S, P, 3, 6) of S cells; ``set_a``, ``set_b`` (K,) and ``offset`` (K, 3) of b from a), host
    arrays out; on the CPU a long launch is split over the thread pool."""
    n = len(set_a)
    if n == 0:
        return np.zeros((0, MOTIONS, SOURCES)), np.zeros((0, MOTIONS))
    arguments = [wp.array(points, dtype=kernels.vec3, device=device),
                 wp.array(source_weights, dtype=kernels.sources, device=device),
                 wp.array(motion_weights, dtype=kernels.motions, device=device),
                 wp.array(np.asarray(set_a, dtype=np.int32), dtype=int, device=device),
                 wp.array(np.asarray(set_b, dtype=np.int32), dtype=int, device=device),
                 wp.array(offset, dtype=kernels.vec3, device=device), kernels.dtype(1.0 / viscosity)]
    out = wp.zeros(n, dtype=kernels.coupling, device=device)
    reverse = wp.zeros(n, dtype=kernels.vec3, device=device)
    reverse_angular = wp.zeros(n, dtype=kernels.vec3, device=device)
    arguments += [out, reverse, reverse_angular]
    if device.is_cpu and n >= SPLIT_THREADS:
        launch_rows(kernels.pair_couplings, n, lambda start, stop: [start, *arguments], device)
    else:
        wp.launch(kernels.pair_couplings, dim=n, inputs=[0, *arguments], device=device)
        if not device.is_cpu:
            wp.synchronize_device(device)
    return out.numpy(), np.concatenate([reverse.numpy(), reverse_angular.numpy()], axis=1)
