"""Plain NumPy (vectorised, no Warp) apply of the same double-layer operator, the baseline the
scale benchmark measures Warp against. Regular Gauss points only (no adaptive subdivision), so
compare it with the Warp operator built with ``adaptive=False``; the self element enters through
the constant-density identity exactly as in warpbem/hydro/operators/description.py:

    ((1/2 + D) q)_a = sum_{b in body(a)} I_ab (q_b - q_a) + sum_{b not in body(a)} I_ab q_b,

with I_ab q = int_{E_b} Sigma_ijk(x, xi_a) n_k q_i dS: free space -3/(4 pi) r_j (r.q)(r.n)/r^5
plus, above the wall, the Blake image and Sigma^E of thesis appendix A contracted with n and q.
"""

import numpy as np

THREE_OVER_FOUR_PI = 3.0 / (4.0 * np.pi)


def _kernel_times_density(x, area, dens, pole, wall):
    """sum over points of Sigma(x, pole).n dS applied to dens; x, area, dens (M, 3), pole (c, 3)."""
    r = x[None] - pole[:, None]
    with np.errstate(divide="ignore"):
        inv_r = 1.0 / np.sqrt(np.einsum("cmi,cmi->cm", r, r))
    inv_r[~np.isfinite(inv_r)] = 0.0  # the collocation point itself (weight zero by the identity)
    rn = np.einsum("cmi,mi->cm", r, area)
    rq = np.einsum("cmi,cmi->cm", r, np.broadcast_to(dens, r.shape))
    u = -np.einsum("cmj,cm->cj", r, rq * rn * inv_r**5)
    if wall:
        h = pole[:, None, 2]
        big_r = r.copy()
        big_r[..., 2] = x[None, :, 2] + h
        inv = 1.0 / np.sqrt(np.einsum("cmi,cmi->cm", big_r, big_r))
        rn = np.einsum("cmi,mi->cm", big_r, area)
        rq = np.einsum("cmi,cmi->cm", big_r, np.broadcast_to(dens, big_r.shape))
        nq = np.einsum("mi,cmi->cm", area, np.broadcast_to(dens, big_r.shape))
        q3 = np.broadcast_to(dens[..., 2], rq.shape)
        n3 = area[None, :, 2]
        x3 = x[None, :, 2]
        w = big_r * np.array([-1.0, -1.0, 1.0])
        u += np.einsum("cmj,cm->cj", big_r, rq * rn * inv**5)  # image Stokeslet stress
        # Sigma^E_ijk n_k q_i (appendix A), term by term, times 2 h / R^5
        e3_part = -rn * rq - 2 * x3 * rn * q3 - 2 * x3 * n3 * rq
        w_part = big_r[..., 2] * nq + x3 * (5 * rn * inv**2 * rq - nq)
        ej = (w * w_part[..., None] + x3[..., None] * (rn[..., None] * np.broadcast_to(dens, big_r.shape)
                                                       + rq[..., None] * area[None]))
        ej[..., 2] += e3_part
        u += np.einsum("cmj,cm->cj", ej, 2 * h * inv**5)
    return u * THREE_OVER_FOUR_PI


def apply(geometry, q, wall, chunk=32):
    """(1/2 + D) q on a warpbem SurfaceGeometry (scaled units), NumPy only."""
    n_qp = geometry.qp_positions.shape[1]
    x = geometry.qp_positions.reshape(-1, 3)
    area = geometry.qp_area_vectors.reshape(-1, 3)
    q = q.reshape(-1, 3)
    dens = np.repeat(q, n_qp, axis=0)
    out = np.zeros_like(q)
    for p, (start, stop) in enumerate(geometry.body_ranges):
        own = slice(start * n_qp, stop * n_qp)
        for a0 in range(start, stop, chunk):
            a1 = min(a0 + chunk, stop)
            poles = geometry.collocation[a0:a1]
            out[a0:a1] = _kernel_times_density(x, area, dens, poles, wall)
            # minus the same-body row sums applied to q_a (the identity replaces the self element)
            for i, a in enumerate(range(a0, a1)):
                out[a] -= _kernel_times_density(x[own], area[own], q[a][None], poles[i : i + 1], wall)[0]
    return out.ravel()
