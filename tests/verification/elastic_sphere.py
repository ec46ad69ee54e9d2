"""An isotropic elastic solid sphere under an axisymmetric surface traction, by Legendre series
(Love 1927, A Treatise on the Mathematical Theory of Elasticity, ch. XI: the sphere under
given surface tractions): pure NumPy reference values for the flattening tests of deformable
cells (``test_deformable.py``), independent of the package's boundary elements.

The sphere has radius a, shear modulus G, Poisson ratio nu; theta is the polar angle from the
load's axis. The traction s_rr(theta) = sum S_n P_n(cos theta), s_rtheta(theta) = sum T_n
dP_n/dtheta is met, mode by mode, by the two regular solutions of Navier's equation

    u_r = n r^(n-1) P_n,                      u_theta = r^(n-1) dP_n/dtheta    (grad of r^n P_n)
    u_r = (n + 1)(n - 2 + 4 nu) r^(n+1) P_n,  u_theta = (n + 5 - 4 nu) r^(n+1) dP_n/dtheta,

the second from the power ansatz in the (r, theta) components of (lambda + 2G) grad div u -
G curl curl u = 0 (its exponent n + 1 and ratio follow from the two components; n = 0 is the
uniform dilatation u_r = A r). Their tractions at r = a, s_rr = lambda div u + 2G du_r/dr and
s_rtheta = G (du_r/dtheta / r + du_theta/dr - u_theta / r), give A_n, B_n. n = 1 is the net force
along the axis: its first solution is the rigid translation, left at zero (the caller fixes
the gauge), and the load must balance (S_1 = -2 T_1). The helper reproduces the uniform
pressure (u_r = -p a / 3K) and the uniaxial stress (u = eps x) exactly, and a small cap's
centre displacement approaches the half-space's under a uniform pressure p on a circle of
radius c, (1 - nu) p c / G (Johnson 1985, Contact Mechanics, ch. 3), less the sphere's
O((1 - nu) F / 2 pi G a) offset (3 % at c = 0.04 a).
"""

import numpy as np


def _legendre(n_max, mu):
    """P_n(mu) and dP_n/dtheta (rows n = 0..n_max) by the three-term recurrence."""
    mu = np.asarray(mu, dtype=float)
    sin = np.sqrt(np.clip(1.0 - mu**2, 0.0, None))
    p = np.zeros((n_max + 1, mu.size))
    p[0] = 1.0
    p[1] = mu
    for n in range(1, n_max):
        p[n + 1] = ((2 * n + 1) * mu * p[n] - n * p[n - 1]) / (n + 1)
    dp = np.zeros_like(p)
    n = np.arange(1, n_max + 1)[:, None]
    safe = np.where(sin > 1e-12, sin, 1.0)
    dp[1:] = np.where(sin > 1e-12, n * (mu * p[1:] - p[:-1]) / safe, 0.0)  # -sin P_n'(mu)
    return p, dp


def displacement(radius, shear_modulus, poisson_ratio, traction, breaks, theta, n_max=400, points=600):
    """(u_r, u_theta) (m) at the polar angles ``theta`` of the sphere under the axisymmetric
    surface traction ``traction(theta) -> (s_rr, s_rtheta)`` (Pa), smooth between the angles
    ``breaks`` (0 to pi; Gauss-Legendre with ``points`` per piece), modes up to ``n_max``; the
    rigid translation along the axis is zero."""
    g, nu = shear_modulus, poisson_ratio
    x, w = np.polynomial.legendre.leggauss(points)
    angles, weights = [], []
    for lo, hi in zip(breaks[:-1], breaks[1:]):
        angles.append(0.5 * (lo + hi) + 0.5 * (hi - lo) * x)
        weights.append(0.5 * (hi - lo) * w)
    angles = np.concatenate(angles)
    weights = np.concatenate(weights) * np.sin(angles)
    s_rr, s_rt = traction(angles)
    p, dp = _legendre(n_max, np.cos(angles))
    n = np.arange(n_max + 1)
    s = (2 * n + 1) / 2 * ((p * s_rr) @ weights)
    t = np.zeros(n_max + 1)
    t[1:] = (2 * n[1:] + 1) / (2 * n[1:] * (n[1:] + 1)) * ((dp[1:] * s_rt) @ weights)
    lam = 2 * g * nu / (1 - 2 * nu)
    # at r = a = 1 (lengths over the radius: u comes out over a)
    f, h = (n + 1) * (n - 2 + 4 * nu), n + 5 - 4 * nu
    second_rr, second_rt = lam * ((n + 3) * f - n * (n + 1) * h) + 2 * g * (n + 1) * f, g * (f + n * h)
    first_rr, first_rt = 2 * g * n * (n - 1), 2 * g * (n - 1)
    first, second = np.zeros(n_max + 1), np.zeros(n_max + 1)
    second[0] = s[0] / (3 * lam + 2 * g)  # u_r = A r
    second[1] = s[1] / second_rr[1]
    if abs(second[1] * second_rt[1] - t[1]) > 1e-8 * (abs(s[1]) + abs(t[1])) + 1e-12 * np.abs(s).max():
        raise ValueError("the traction does not balance: no elastic solution")
    det = first_rr[2:] * second_rt[2:] - second_rr[2:] * first_rt[2:]
    first[2:] = (s[2:] * second_rt[2:] - second_rr[2:] * t[2:]) / det
    second[2:] = (first_rr[2:] * t[2:] - s[2:] * first_rt[2:]) / det
    radial, polar = first * n + second * f, first + second * h
    radial[0], polar[0] = second[0], 0.0
    pe, dpe = _legendre(n_max, np.cos(np.asarray(theta, dtype=float)))
    return radius * (radial @ pe), radius * (polar @ dpe)


def on_mesh(mesh, axis, shear_modulus, poisson_ratio, traction, breaks, n_max=400):
    """The sphere's displacement (n_nodes, 3) (m) on a sphere ``mesh`` centred at the origin
    whose load's axis is the unit vector ``axis``: sampled at the element centres (the
    collocation points of the package's elastic solve), less their area-weighted mean (the
    solve's gauge: no mean translation; the load's axial symmetry leaves no mean rotation), and
    carried to the nodes by the mesh's linear fit (``warpbem.elastic.shape.nodal_weights``) as
    the package's displacements are."""
    from warpbem.elastic.shape import nodal_weights
    from warpbem.surfaces.quad9 import CENTRE_NODE

    centres = mesh.element_nodes()[:, CENTRE_NODE]
    areas = mesh.element_areas()
    radial = centres / np.linalg.norm(centres, axis=1)[:, None]
    cos = np.clip(radial @ axis, -1.0, 1.0)
    theta = np.arccos(cos)
    u_r, u_theta = displacement(mesh.equivalent_radius(), shear_modulus, poisson_ratio, traction, breaks, theta,
                                n_max)
    sin = np.sin(theta)
    polar = np.where(sin[:, None] > 1e-12, (radial * cos[:, None] - axis) / np.where(sin > 1e-12, sin, 1.0)[:, None],
                     0.0)
    u = u_r[:, None] * radial + u_theta[:, None] * polar
    u -= areas @ u / areas.sum()
    return nodal_weights(mesh) @ u
