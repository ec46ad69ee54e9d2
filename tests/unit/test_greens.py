"""Green's functions of kernels/greens.py: free-space values and the properties that pin down
the Blake (1971) wall solution (thesis appendix A): no slip on z = 0, continuity, momentum
balance, Sigma being the stress of G, reciprocity, and the free-space limit far from the wall."""

import numpy as np

from warpbem import runtime

wp = runtime.init()
from warpbem.kernels.greens import make_green_functions  # noqa: E402


def _evaluator(dtype, wall):
    g = make_green_functions(dtype, wall)

    @wp.kernel(enable_backward=False, module="unique")
    def evaluate(x: wp.array(dtype=g.vec3), poles: wp.array(dtype=g.vec3),
                 stokeslet: wp.array(dtype=g.mat33), stress: wp.array3d(dtype=dtype)):
        i = wp.tid()
        stokeslet[i] = g.stokeslet(x[i], g.vec3(), poles[i])
        for k in range(3):
            n = g.vec3()
            n[k] = dtype(1.0)
            m = g.double_layer(x[i], n, poles[i])  # m[j, i'] = Sigma_{i' j k}
            for j in range(3):
                for a in range(3):
                    stress[i, a * 3 + j, k] = m[j, a]

    def run(x, poles, device="cpu"):
        x, poles = np.broadcast_arrays(np.atleast_2d(x), np.atleast_2d(poles))
        n = len(x)
        s = wp.zeros(n, dtype=g.mat33, device=device)
        sig = wp.zeros((n, 9, 3), dtype=dtype, device=device)
        wp.launch(evaluate, dim=n, inputs=[wp.array(x, dtype=g.vec3, device=device),
                                           wp.array(poles, dtype=g.vec3, device=device), s, sig], device=device)
        # G[p, i, j]; Sigma[p, i, j, k]
        return s.numpy().astype(float), sig.numpy().reshape(n, 3, 3, 3).astype(float)

    return run


free64 = _evaluator(wp.float64, False)
wall64 = _evaluator(wp.float64, True)
wall32 = _evaluator(wp.float32, True)

POLE = np.array([0.3, -0.2, 1.3])
POINTS = np.array([[1.1, 0.4, 0.7], [-0.8, 1.5, 2.9], [0.2, -0.1, 0.05], [2.0, 2.0, 1.3]])


def test_free_space_values(device):
    # Oseen tensor and stress, thesis appendix A / Pozrikidis (1992) eq. 2.2.8, 2.2.10
    r = POINTS - POLE
    d = np.linalg.norm(r, axis=1)[:, None, None]
    g_ref = (np.eye(3) / d + np.einsum("pi,pj->pij", r, r) / d**3) / (8 * np.pi)
    s_ref = -3 * np.einsum("pi,pj,pk->pijk", r, r, r) / (4 * np.pi * d[..., None] ** 5)
    g, s = free64(POINTS, POLE, device)
    np.testing.assert_allclose(g, g_ref, rtol=1e-14, atol=0)
    np.testing.assert_allclose(s, s_ref, rtol=1e-13, atol=1e-16)


def test_wall_velocity_vanishes_on_the_wall():
    on_wall = np.array([[1.0, 2.0, 0.0], [-3.0, 0.5, 0.0], [0.3, -0.2, 0.0]])
    g, _ = wall64(on_wall, POLE)
    assert np.abs(g).max() < 1e-15


def _gradient(run, x, pole, h=1e-5):
    grads = []
    for k in range(3):
        dx = np.zeros(3)
        dx[k] = h
        gp, sp = run(x + dx, pole)
        gm, sm = run(x - dx, pole)
        grads.append(((gp - gm) / (2 * h), (sp - sm) / (2 * h)))
    dg = np.stack([g for g, _ in grads], axis=-1)  # dG_ij / dx_k
    ds = np.stack([s for _, s in grads], axis=-1)  # dSigma_ijk / dx_l
    return dg, ds


def test_wall_solution_satisfies_stokes_equations():
    dg, ds = _gradient(wall64, POINTS, POLE)
    # continuity: dG_ij/dx_i = 0
    assert np.abs(np.einsum("piji->pj", dg)).max() < 1e-8
    # momentum: dSigma_ijk/dx_k = 0
    assert np.abs(np.einsum("pijkk->pij", ds)).max() < 1e-7
    # Sigma is the stress of G: Sigma_ijk = -P_j delta_ik + dG_ij/dx_k + dG_kj/dx_i
    _, s = wall64(POINTS, POLE)
    deviation = s - (dg + np.transpose(dg, (0, 3, 2, 1)))
    pressure = -np.einsum("piji->pj", deviation) / 3
    np.testing.assert_allclose(deviation, -np.einsum("pj,ik->pijk", pressure, np.eye(3)), atol=1e-8)


def test_wall_stokeslet_is_reciprocal_and_free_space_far_from_wall():
    # Lorentz reciprocity: G_ij(x, X) = G_ji(X, x)
    g_xX, _ = wall64(POINTS, POLE)
    g_Xx, _ = wall64(POLE, POINTS)
    np.testing.assert_allclose(g_xX, np.transpose(g_Xx, (0, 2, 1)), rtol=1e-13, atol=1e-16)
    # far from the wall the images vanish like 1/h (relative to the free part at distance ~1)
    lift = np.array([0.0, 0.0, 1e4])
    gw, sw = wall64(POINTS + lift, POLE + lift)
    gf, sf = free64(POINTS + lift, POLE + lift)
    np.testing.assert_allclose(gw, gf, atol=1e-4 * np.abs(gf).max())
    np.testing.assert_allclose(sw, sf, atol=1e-4 * np.abs(sf).max())


def test_float32_matches_float64():
    g64, s64 = wall64(POINTS, POLE)
    g32, s32 = wall32(POINTS, POLE)
    np.testing.assert_allclose(g32, g64, rtol=0, atol=2e-6 * np.abs(g64).max())
    np.testing.assert_allclose(s32, s64, rtol=0, atol=2e-6 * np.abs(s64).max())


def test_float64_path_keeps_double_precision_constants():
    # A float32-truncated 1/(8 pi) (NVIDIA/warp#485) would show at the 1e-8 level here.
    g, _ = free64(np.array([[1.0, 0.0, 0.0]]), np.zeros(3))
    assert abs(g[0, 0, 0] - 2.0 / (8.0 * np.pi)) < 1e-16
