"""Green's functions of Stokes flow, free space and above a no-slip wall (z = 0).

Convention (thesis appendix A; Pozrikidis 1992 with the 1/(8 pi) folded in): with viscosity mu,
a point force F at the pole X drives the velocity u_i(x) = G_ij(x, X) F_j / mu and the stress
sigma_ik(x) = Sigma_ijk(x, X) F_j, where r = x - X and, free space,

    G_ij = (delta_ij / r + r_i r_j / r^3) / (8 pi),   Sigma_ijk = -3 r_i r_j r_k / (4 pi r^5).

Above the wall (Blake 1971) both gain the image at X* = (X1, X2, -X3), R = x - X*, h = X3:

    G     = G(r) - G(R) + G^E,      Sigma = Sigma(r) - Sigma(R) + Sigma^E,

with G^E and Sigma^E as in the thesis's appendix A (there G^E lacks the 1/(8 pi) that makes the
wall velocity vanish; ``tests/unit/test_greens.py`` checks no slip, continuity, momentum
balance and that Sigma is the stress of G).

Every function here has the one signature ``f(x, n, pole) -> mat33`` used by the kernel
factories of ``assembly.py``: the 3x3 matrix that maps a strength to a velocity,

* ``stokeslet``: velocity at x per unit point force at ``pole`` (n unused), M_ij = G_ij(x, pole);
* ``double_layer``: velocity at ``pole`` per unit double-layer density at x on a surface with
  outward normal n, M_ji = Sigma_ijk(x, pole) n_k (thesis eq. 2.5-2.6 without its factor 2).
"""


import functools
from types import SimpleNamespace

import warp as wp


@functools.lru_cache(maxsize=None)
def make_green_functions(dtype, wall: bool) -> SimpleNamespace:
    """Green's functions for floating type ``dtype`` (wp.float32 / wp.float64), with the
    no-slip wall images when ``wall`` is true (a compile-time switch)."""
    vec3 = wp.types.vector(3, dtype)
    mat33 = wp.types.matrix((3, 3), dtype)

    @wp.func
    def image_offset(x: vec3, pole: vec3):
        # R = x - X*, X* = (X1, X2, -X3) the mirror image of the pole in the wall, and 1/|R|
        big_r = vec3(x[0] - pole[0], x[1] - pole[1], x[2] + pole[2])
        return big_r, dtype(1.0) / wp.length(big_r)

    @wp.func
    def stokeslet(x: vec3, n: vec3, pole: vec3):
        zero = dtype(0.0)
        one = dtype(1.0)
        r = x - pole
        inv_r = one / wp.length(r)
        g = (wp.identity(3, dtype) + wp.outer(r, r) * (inv_r * inv_r)) * inv_r
        if wall:
            e3 = vec3(zero, zero, one)
            h = pole[2]
            big_r, inv_rr = image_offset(x, pole)
            inv_rr2 = inv_rr * inv_rr
            g -= (wp.identity(3, dtype) + wp.outer(big_r, big_r) * inv_rr2) * inv_rr
            # G^E (appendix A): w_j = R_j - 2 delta_j3 R_3
            w = vec3(big_r[0], big_r[1], -big_r[2])
            g += (dtype(2.0) * h * inv_rr2 * inv_rr) * (
                wp.outer(big_r, e3)
                + wp.outer(e3, big_r)
                - dtype(2.0) * big_r[2] * wp.outer(e3, e3)
                + x[2]
                * (
                    dtype(2.0) * wp.outer(e3, e3)
                    - wp.identity(3, dtype)
                    + dtype(3.0) * inv_rr2 * wp.outer(big_r, w)
                )
            )
        return g * dtype(0.039788735772973836)  # 1 / (8 pi)

    @wp.func
    def double_layer(x: vec3, n: vec3, pole: vec3):
        zero = dtype(0.0)
        one = dtype(1.0)
        r = x - pole
        inv_r = one / wp.length(r)
        inv_r2 = inv_r * inv_r
        # free space: Sigma_ijk n_k = -3 r_i r_j (r.n) / (4 pi r^5), symmetric in i, j
        m = wp.outer(r, r) * (-wp.dot(r, n) * inv_r2 * inv_r2 * inv_r)
        if wall:
            e3 = vec3(zero, zero, one)
            h = pole[2]
            big_r, inv_rr = image_offset(x, pole)
            inv_rr2 = inv_rr * inv_rr
            rn = wp.dot(big_r, n)
            m += wp.outer(big_r, big_r) * (rn * inv_rr2 * inv_rr2 * inv_rr)
            # Sigma^E_ijk n_k (appendix A) as E_ij, with w_j = 2 delta_j3 R_3 - R_j;
            # the factor 3 h / (2 pi R^5) is written as 2 h / R^5 times the 3 / (4 pi) below.
            w = vec3(-big_r[0], -big_r[1], big_r[2])
            e = (
                -rn * wp.outer(big_r, e3)
                + big_r[2] * wp.outer(n, w)
                + x[2]
                * (
                    rn * wp.identity(3, dtype)
                    + wp.outer(big_r, n)
                    - dtype(2.0) * rn * wp.outer(e3, e3)
                    - dtype(2.0) * n[2] * wp.outer(big_r, e3)
                    + wp.outer(dtype(5.0) * rn * inv_rr2 * big_r - n, w)
                )
            )
            m += wp.transpose(e) * (dtype(2.0) * h * inv_rr2 * inv_rr2 * inv_rr)
        return m * dtype(0.238732414637843)  # 3 / (4 pi)

    return SimpleNamespace(
        dtype=dtype, vec3=vec3, mat33=mat33, wall=wall, stokeslet=stokeslet, double_layer=double_layer
    )
