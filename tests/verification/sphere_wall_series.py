"""Exact bipolar (bispherical) coordinate series for a rigid sphere near a plane no-slip wall.

Pure NumPy/SciPy reference values for the wall verification tests (see
``/work/shared/reference/validation.md`` for the notation).  A sphere of radius ``a`` has
its centre at height ``h`` above the wall ``z = 0``; viscosity ``mu``; Stokes flow.

Public functions (``h_over_a`` is a float > 1, every result is a float):

* :func:`brenner_lambda` -- Brenner (1961), motion normal to the wall.
* :func:`parallel_resistance` -- O'Neill (1964) / Goldman, Cox & Brenner (1967a) translation
  parallel to the wall and Dean & O'Neill (1963) / GCB (1967a) rotation about an axis
  parallel to the wall.
* :func:`fixed_sphere_in_shear` -- GCB (1967b) / O'Neill (1968): sphere held fixed in the
  wall-bounded shear flow ``u = gdot z e_x``.
* :func:`free_sphere_in_shear` -- GCB (1967b): force- and torque-free sphere in that flow.

References
----------
H. Brenner, Chem. Eng. Sci. 16 (1961) 242-251.
W. R. Dean & M. E. O'Neill, Mathematika 10 (1963) 13-24.
M. E. O'Neill, Mathematika 11 (1964) 67-74.
A. J. Goldman, R. G. Cox & H. Brenner, Chem. Eng. Sci. 22 (1967) 637-651 (GCB 1967a)
  and 653-660 (GCB 1967b).
M. E. O'Neill & K. Stewartson, J. Fluid Mech. 27 (1967) 705-724 (near-contact asymptotics).
M. E. O'Neill, Chem. Eng. Sci. 23 (1968) 1293-1298.
M. Chaoui & F. Feuillebois, Q. J. Mech. Appl. Math. 56 (2003) 381-410.

Numerical method (overview; details in the comments next to the code)
---------------------------------------------------------------------
Bispherical coordinates (xi, eta, phi) with focal length c = a sinh(alpha),
alpha = arccosh(h/a):  rho = c sin(eta)/(cosh xi - cos eta),  z = c sinh(xi)/(cosh xi - cos eta).
The wall is xi = 0 and the sphere xi = alpha.  Every harmonic function is expanded as
(cosh xi - mu)^(1/2) sum_n [A_n cosh((n+1/2) xi) + B_n sinh((n+1/2) xi)] P_n^m(mu),
mu = cos(eta).  The boundary conditions and the continuity equation turn into linear
recurrences between neighbouring n (three-term / block-tridiagonal), which are truncated
at n <= n_terms and solved with a banded LU (scipy.linalg.solve_banded).  The truncation
error decays like exp(-2 n_terms alpha), so the default is n_terms = ceil(30/alpha) + 10
(106 terms at h/a = 1.05, 2132 at h/a = 1.0001).  Doubling it changes no result by more
than ~1e-14 relative for 1 + 1e-6 <= h/a <= 30 (and beyond, except for the caveat below);
halving it changes results by < 3e-9.

Accuracy caveat: for h/a >~ 30 the coupling coefficients Tt and Fr (which fall off like
(3/32)(a/h)^4, resp. (1/8)(a/h)^4) come out of a cancellation, so they are accurate only to
~1e-14 absolute (relative error ~1e-5 at h/a = 100, meaningless beyond ~300); everything else
keeps ~1e-13 relative accuracy.

Two independent formulations are implemented and agree to ~1e-12 (h/a <= 30):

1. The classical single three-term recurrence for the coefficients A_n of O'Neill (1964)
   (translation) and Dean & O'Neill (1963) (rotation), with the force and torque sums in
   the form quoted by GCB (1967a) -> ``parallel_resistance(method="oneill")`` (default).
2. A direct "general" formulation written for this file (derivation in the comments of
   ``_general_solve``): the O'Neill-type representation v = x p/(2 mu) + w with four
   harmonic functions, the wall and sphere conditions and the continuity equation imposed
   exactly as block-tridiagonal recurrences, and closed-form force/torque sums obtained from
   the far field of the part of the solution that is singular inside the sphere.  It
   handles any boundary data on the sphere, and is what the shear problem (3) uses
   (``parallel_resistance(method="general")`` runs problems (1)-(2) through it as a check).

No tabulated or target value is used anywhere in the computations.
"""

import math

import numpy as np
from scipy.linalg import solve_banded

__all__ = [
    "brenner_lambda",
    "parallel_resistance",
    "fixed_sphere_in_shear",
    "free_sphere_in_shear",
]

_SQRT2 = math.sqrt(2.0)


# ----------------------------------------------------------------------------- helpers
def _alpha(h_over_a):
    h = float(h_over_a)
    if not h > 1.0 or not math.isfinite(h):
        raise ValueError(f"h_over_a must be a finite float > 1 (got {h_over_a!r})")
    return math.acosh(h)


def _n_terms(alpha, n_terms):
    """Default truncation: the coefficients decay like exp(-2 n alpha); 2 n alpha ~ 60."""
    if n_terms is None:
        return int(math.ceil(30.0 / alpha)) + 10
    n = int(n_terms)
    if n < 4:
        raise ValueError("n_terms must be >= 4")
    return n


def _csch(x):
    """1/sinh(x) for x > 0 without overflow (underflows to 0 for huge x)."""
    x = np.asarray(x, dtype=float)
    e = np.exp(-x)
    return 2.0 * e / (1.0 - e * e)


def _coth(x):
    x = np.asarray(x, dtype=float)
    e = np.exp(-2.0 * x)
    return (1.0 + e) / (1.0 - e)


def _axisymmetric_series(h_over_a, n_terms, bracket):
    """(4/3) sinh(alpha) sum_{n>=1} n(n+1)/((2n-1)(2n+3)) * bracket(m, E, sinh a, sinh 2a), the
    common form of the Stimson-Jeffery stream-function solutions below, with m = 2n + 1 and
    E = exp(-m alpha) (each bracket is written in E so that nothing overflows)."""
    al = _alpha(h_over_a)
    n = np.arange(1, _n_terms(al, n_terms) + 1, dtype=float)
    m = 2.0 * n + 1.0
    terms = n * (n + 1.0) / ((2.0 * n - 1.0) * (2.0 * n + 3.0)) * bracket(m, np.exp(-m * al), math.sinh(al),
                                                                          math.sinh(2.0 * al))
    return float(4.0 / 3.0 * math.sinh(al) * np.sum(terms))


# ------------------------------------------------------------------ 1. Brenner (1961)
def brenner_lambda(h_over_a, n_terms=None):
    """Brenner (1961) drag correction for a sphere translating normal to a plane wall.

    H. Brenner, Chem. Eng. Sci. 16 (1961) 242, eq. (2.19): for a sphere moving with velocity
    U e_z (towards or away from the wall) the hydrodynamic force is
    F_z = -6 pi mu a U lambda with

        lambda = (4/3) sinh(alpha) sum_{n>=1} n(n+1)/((2n-1)(2n+3))
                 * [ (2 sinh((2n+1)alpha) + (2n+1) sinh(2 alpha))
                     / (4 sinh^2((n+1/2)alpha) - (2n+1)^2 sinh^2(alpha)) - 1 ],

    alpha = arccosh(h/a).  lambda -> 1 as h/a -> infinity and lambda ~ a/(h - a) near
    contact.  Exact Stimson-Jeffery stream-function solution in bispherical coordinates.

    Parameters
    ----------
    h_over_a : float > 1, centre height over radius.
    n_terms : number of series terms (default ceil(30/alpha) + 10; terms decay like
        exp(-(2n+1) alpha)).
    """
    # ratio - 1 = E (2 - 2E + m sinh 2a + m^2 sinh^2 a) / ((1 - E)^2 - m^2 sinh^2 a E)
    return _axisymmetric_series(h_over_a, n_terms, lambda m, E, s, s2: E * (2.0 - 2.0 * E + m * s2 + m * m * s * s)
                                / ((1.0 - E) ** 2 - m * m * s * s * E))


def stimson_jeffery_lambda(half_distance_over_a, n_terms=None):
    """Stimson & Jeffery (1926): two equal spheres of radius a, centres 2 h apart, translating
    with the same velocity U along their line of centres in unbounded fluid; each feels
    F = -6 pi mu a U lambda with (Happel & Brenner 1965, eq. 6-3.55)

        lambda = (4/3) sinh(alpha) sum_{n>=1} n(n+1)/((2n-1)(2n+3))
                 * [ 1 - (4 sinh^2((n+1/2)alpha) - (2n+1)^2 sinh^2(alpha))
                         / (2 sinh((2n+1)alpha) + (2n+1) sinh(2 alpha)) ],

    alpha = arccosh(h/a). lambda -> 1 far apart and 0.645 when the spheres touch. Written,
    like ``brenner_lambda``, with E = exp(-(2n+1) alpha) so that nothing overflows:
        1 - Y/X = E (2 - 2E + m sinh 2a + m^2 sinh^2 a) / (1 - E^2 + E m sinh 2a).
    """
    return _axisymmetric_series(half_distance_over_a, n_terms, lambda m, E, s, s2: E * (2.0 - 2.0 * E + m * s2 + m * m * s * s)
                                / (1.0 - E * E + E * m * s2))


def approaching_spheres_lambda(half_distance_over_a, n_terms=None):
    """Two equal spheres, centres 2 h apart, approaching each other along their line of centres
    with speeds U and -U (Maude 1961; Brenner 1961, whose paper treats this case beside the
    wall): each feels F = -6 pi mu a U lambda with

        lambda = (4/3) sinh(alpha) sum_{n>=1} n(n+1)/((2n-1)(2n+3))
                 * [ (4 cosh^2((n+1/2)alpha) + (2n+1)^2 sinh^2(alpha))
                     / (2 sinh((2n+1)alpha) - (2n+1) sinh(2 alpha)) - 1 ],

    alpha = arccosh(h/a); the squeeze flow in the gap makes lambda ~ a / (2 (2h - 2a)) near
    contact. With E = exp(-(2n+1) alpha) the bracket is
        E (2 + 2E + m^2 sinh^2 a + m sinh 2a) / (1 - E^2 - E m sinh 2a).
    """
    return _axisymmetric_series(half_distance_over_a, n_terms, lambda m, E, s, s2: E * (2.0 + 2.0 * E + m * m * s * s + m * s2)
                                / (1.0 - E * E - E * m * s2))


# ------------------------------------- 2a. classical O'Neill / Dean & O'Neill recurrence
def _oneill_classical(al, N):
    """Ft, Tt, Fr, Tr from the classical single three-term recurrence.

    O'Neill (1964) (translation) and Dean & O'Neill (1963) (rotation) reduce the problem to
    one second-order difference equation for coefficients A_n, n >= 1 (A_0 = 0):

      c0_n A_{n-1} + c1_n A_n + c2_n A_{n+1} = R_n ,
        k_n  = (n+1/2) coth((n+1/2) alpha) - coth(alpha)
        ca_n = (2n-1) k_{n-1} - (2n-3) k_n ,   cb_n = (2n+5) k_n - (2n+3) k_{n+1}
        c0_n = ca_n (n-1)/(2n-1),  c1_n = -(n ca_n + (n+1) cb_n)/(2n+1),
        c2_n = cb_n (n+2)/(2n+3)
      R_n (translation) = sqrt2 [2 coth((n+1/2)a) - coth((n-1/2)a) - coth((n+3/2)a)]
      R_n (rotation)    = -sqrt2 e^{-(n+1/2)a} / ((2n+1) sinh a)
                          * [ (2n+1)^2 (e^a/(2n-1) + e^-a/(2n+3)) csch((n+1/2)a)
                              - (2n-1) csch((n-1/2)a) - (2n+3) csch((n+3/2)a) ]

    The remaining coefficients follow from A_{n-1}, A_n, A_{n+1}:
      B_n = (n-1) A_{n-1} - (2n+1) A_n + (n+2) A_{n+1}
      C_n = -2 k_n [ (n-1)/(2n-1) A_{n-1} - A_n + (n+2)/(2n+3) A_{n+1} ]  (n >= 1, C_0 = 0)
            + 4 L_n csch(a) csch((n+1/2)a)                                     (rotation only)
      D_n = [ (n+1)(n+2) A_{n+1} - (n-1) n A_{n-1} ] / 2
      E_n = S_n + k_n [ (n-1)n/(2n-1) A_{n-1} - (n+1)(n+2)/(2n+3) A_{n+1} ]
        S_n = 2 sqrt2 e^{-(n+1/2)a} csch((n+1/2)a)                              (translation)
        S_n = (sqrt2 (2n+1) e^{-(n+1/2)a} - L_n csch a) csch((n+1/2)a)           (rotation)
        L_n = -(1/sqrt2) [e^{-(n-1/2)a}/(2n-1) - e^{-(n+3/2)a}/(2n+3)]
    and the loads (GCB 1967a normalisation):
      sigma = sum_{n>=0} (E_n + n(n+1) C_n)
      G     = sum_{n>=0} (2 + e^{-(2n+1)a}) [n(n+1)(2A_n + C_n coth a) - (2n+1 - coth a) E_n]
                         + (2 - e^{-(2n+1)a}) [n(n+1) B_n coth a - (2n+1 - coth a) D_n]
      translation: Ft = (sqrt2/6) sinh(a) sigma,   Tt = sinh^2(a) G / (12 sqrt2)
      rotation:    Fr = -(sqrt2/6) sinh^2(a) sigma, Tr = (1 - sinh^3(a) G / (4 sqrt2)) / 3
    Truncation: A_n = 0 for n > N; the tridiagonal system (rows n = 1..N) is solved with
    scipy.linalg.solve_banded.  Fr = (4/3) Tt holds to round-off (Lorentz reciprocity).
    """
    n = np.arange(0, N + 3, dtype=float)  # index 0..N+2
    k = (n + 0.5) * _coth((n + 0.5) * al) - _coth(al)
    i = np.arange(1, N + 1, dtype=float)
    ki_m, ki, ki_p = k[0:N], k[1:N + 1], k[2:N + 2]  # k_{i-1}, k_i, k_{i+1}
    ca = (2 * i - 1) * ki_m - (2 * i - 3) * ki
    cb = (2 * i + 5) * ki - (2 * i + 3) * ki_p
    c0 = ca * (i - 1) / (2 * i - 1)
    c1 = -(ca * i + cb * (i + 1)) / (2 * i + 1)
    c2 = cb * (i + 2) / (2 * i + 3)
    band = np.zeros((3, N))
    band[0, 1:] = c2[:-1]
    band[1, :] = c1
    band[2, :-1] = c0[1:]

    sa, ct = math.sinh(al), _coth(al)
    e = lambda x: np.exp(-x * al)  # noqa: E731
    L = -(1.0 / _SQRT2) * (e(n - 0.5) / (2 * n - 1) - e(n + 1.5) / (2 * n + 3))
    rhs_t = _SQRT2 * (2 * _coth((i + 0.5) * al) - _coth((i - 0.5) * al) - _coth((i + 1.5) * al))
    # e^{-(n+1/2)a} csch(x a) products kept in overflow-free form
    rhs_r = -_SQRT2 / ((2 * i + 1) * sa) * (
        (2 * i + 1) ** 2 * (math.exp(al) / (2 * i - 1) + math.exp(-al) / (2 * i + 3))
        * e(i + 0.5) * _csch((i + 0.5) * al)
        - (2 * i - 1) * e(i + 0.5) * _csch((i - 0.5) * al)
        - (2 * i + 3) * e(i + 0.5) * _csch((i + 1.5) * al))

    out = {}
    for rot, rhs in ((False, rhs_t), (True, rhs_r)):
        A_in = solve_banded((1, 1), band, rhs)
        A = np.zeros(N + 2)          # A[n], n = 0..N+1, A_0 = A_{N+1} = 0
        A[1:N + 1] = A_in
        nn = n[:N + 1]               # n = 0..N
        Am = np.concatenate(([0.0], A[0:N]))   # A_{n-1}
        A0 = A[0:N + 1]                         # A_n
        Ap = A[1:N + 2]                         # A_{n+1}
        kn = k[:N + 1]
        csn = _csch((nn + 0.5) * al)
        C = -2 * kn * ((nn - 1) / (2 * nn - 1) * Am - A0 + (nn + 2) / (2 * nn + 3) * Ap)
        C[0] = 0.0
        Ln = L[:N + 1]
        if rot:
            C[1:] += 4 * Ln[1:] / sa * csn[1:]
            S = (_SQRT2 * (2 * nn + 1) * e(nn + 0.5) - Ln / sa) * csn
        else:
            S = 2 * _SQRT2 * e(nn + 0.5) * csn
        En = S + kn * ((nn - 1) * nn / (2 * nn - 1) * Am - (nn + 1) * (nn + 2) / (2 * nn + 3) * Ap)
        B = (nn - 1) * Am - (2 * nn + 1) * A0 + (nn + 2) * Ap
        B[0] = 0.0
        Dn = 0.5 * ((nn + 1) * (nn + 2) * Ap - (nn - 1) * nn * Am)
        sigma = np.sum(En + nn * (nn + 1) * C)
        ea = np.exp(-(2 * nn + 1) * al)
        G = np.sum((2 + ea) * (nn * (nn + 1) * (2 * A0 + C * ct) - (2 * nn + 1 - ct) * En)
                   + (2 - ea) * (nn * (nn + 1) * B * ct - (2 * nn + 1 - ct) * Dn))
        if rot:
            out["Fr"] = float(-_SQRT2 / 6 * sa ** 2 * sigma)
            out["Tr"] = float((1.0 - sa ** 3 * G / (4 * _SQRT2)) / 3.0)
        else:
            out["Ft"] = float(_SQRT2 / 6 * sa * sigma)
            out["Tt"] = float(sa ** 2 * G / (12 * _SQRT2))
    return out


# -------------------------------------------------- 2b. general bipolar formulation
#
# Derivation (lengths in units of the focal length c = a sinh(alpha), mu = 1).
#
# Representation.  Any Stokes flow can be written v = x P/2 + w with P = p/mu harmonic and
# w a harmonic vector (then lap v = grad P and div v = 0 is a separate condition).  For the
# cos(phi)-type problems here (data only in v_x and v_z ~ cos phi on the sphere)
#     P = Q cos(phi),  w_x = U0 + U2 cos(2 phi),  w_y = U2 sin(2 phi),  w_z = W cos(phi),
# with Q, W of order m = 1, U0 of order 0 and U2 of order 2 (the representation used by
# Dean & O'Neill 1963 and O'Neill 1964).  Each is written
#     F = D^(1/2) sum_n f_n(xi) P_n^m(mu),  D = cosh xi - mu,
#     f_n = g_n e^{(n+1/2)xi} + d_n e^{-(n+1/2)xi}
# (P_n^m without the Condon-Shortley phase).  g_n ("growing") terms are singular only at the
# focus inside the sphere, d_n ("decaying") terms only at the image focus below the wall.
#
# Exact operator identities (verified numerically; H_n^m = D^(1/2) e^{+-(n+1/2)xi} P_n^m):
#     x.grad      : H_n^m -> -(n-m+1)/2 H_{n+1}^m - 1/2 H_n^m + (n+m)/2 H_{n-1}^m
#     d/dz        : H_n^m -> +-[-(n-m+1)/2 H_{n+1}^m + (n+1/2) H_n^m - (n+m)/2 H_{n-1}^m]
#     d/drho+m/rho: H_n^m -> (n-m+1)(n-m+2)/2 H_{n+1}^{m-1} - (n+m)(n-m+1) H_n^{m-1}
#                            + (n+m)(n+m-1)/2 H_{n-1}^{m-1}
#     d/drho-m/rho: H_n^m -> -1/2 H_{n+1}^{m+1} + H_n^{m+1} - 1/2 H_{n-1}^{m+1}
# (the exponential index moves with n; +- is the sign of the exponent).  Hence
#     div v / cos(phi) = (3P + x.grad P)/2 + dU0/drho + (d/drho + 2/rho) U2 + dW/dz
# is itself such a series, and div v = 0 <=> for every n >= 1 and separately for the g and
# the d parts:
#     [5 q_n - (n-1) q_{n-1} + (n+2) q_{n+1}]/4 + [-u_{n-1} + 2 u_n - u_{n+1}]/2
#   + (n-2)(n-1)/2 v_{n-1} - (n+2)(n-1) v_n + (n+3)(n+2)/2 v_{n+1}
#   +- [-(n-1)/2 w_{n-1} + (n+1/2) w_n - (n+2)/2 w_{n+1}] = 0          (continuity)
# (q, u, v, w = the g- or d-coefficients of Q, U0, U2, W).
#
# Boundary conditions.  v_y = (U2 + rho Q/4) sin 2phi and
# v_x = (U0 + rho Q/4) + (U2 + rho Q/4) cos 2phi, v_z = (W + z Q/2) cos phi.  Prescribing
# v = G(rho,z) e_x + g(rho,z) cos(phi) e_z on xi = xi_b (G = g = 0 on the wall) gives
#     U2 + rho Q/4 = 0,   U0 + rho Q/4 = G,   W + z Q/2 = g.
# Multiplying by D^(1/2), using rho = s/D, z = sinh(xi)/D (s = sin eta) and the Legendre
# relations  mu P_n^m = [(n-m+1) P_{n+1}^m + (n+m) P_{n-1}^m]/(2n+1),
#            s P_n^1 = [P_{n+1}^2 - P_{n-1}^2]/(2n+1) = n(n+1)[P_{n-1} - P_{n+1}]/(2n+1),
# projection on P_n^2, P_n and P_n^1 gives, with F_n = f_n(xi_b) and C = cosh xi_b:
#  (a) C V_n - (n-2)/(2n-1) V_{n-1} - (n+3)/(2n+3) V_{n+1}
#         + [Q_{n-1}/(2n-1) - Q_{n+1}/(2n+3)]/4 = 0                                      (n>=2)
#  (b) C U_n - n/(2n-1) U_{n-1} - (n+1)/(2n+3) U_{n+1}
#         + [(n+1)(n+2)/(2n+3) Q_{n+1} - (n-1)n/(2n-1) Q_{n-1}]/4 = [G D^(1/2)]_n       (n>=0)
#  (c) C W_n - (n-1)/(2n-1) W_{n-1} - (n+2)/(2n+3) W_{n+1}
#         + sinh(xi_b) Q_n / 2 = [g D^(1/2)]_n^1                                         (n>=1)
# on the wall (xi_b = 0, zero data) and on the sphere (xi_b = alpha).  Data on the sphere
# (e_n = e^{-(n+1/2)alpha}; D^(-1/2) = sqrt2 sum e_n P_n):
#     D^(1/2)   -> L_n = [e_{n+1}/(2n+3) - e_{n-1}/(2n-1)]/sqrt2            (P_n)
#     s D^(-1/2)-> -2 L_n                                                    (P_n^1)
#   translation U e_x        : G = 1,          g = 0
#   rotation Omega e_y       : G = z - h,      g = -rho   (h = coth(alpha))
#   fixed sphere in z e_x    : G = -z,         g = 0      (disturbance flow)
# with z D^(1/2) = sinh(alpha) D^(-1/2) on the sphere.  Per n there are 8 unknowns and 8
# equations; truncating at n <= N gives a block-tridiagonal (bandwidth 15) system.  The
# unknowns are scaled as  g_n = G_n e^{-(n+1/2)alpha}, d_n = D_n (all entries O(1)).
#
# Force and torque.  The continuity equations split into g and d parts, so v = v_g + v_d
# with both Stokes flows.  v_d is regular inside the sphere (xi > alpha) and exerts no
# force or torque on it; v_g is regular everywhere outside the sphere (also below the
# wall) and decays at infinity, so the load on the sphere is read off its far field
# (D^(1/2) ~ sqrt2/r, xi ~ 2z/r^2, eta ~ 2 rho/r^2):  w_x ~ sqrt2 sum g^u_n / r
# + sqrt2 sum (2n+1) g^u_n z/r^3, i.e. a Stokeslet f_x = 8 pi sqrt2 sum g^u_n and a rotlet
# L_y = 8 pi sqrt2 sum (2n+1) g^u_n about the origin.  Therefore (units mu V c, mu V c^2)
#     F_x = -8 sqrt2 pi sum_n g^u_n,
#     T_y (about the centre) = 8 sqrt2 pi sum_n (coth(alpha) - 2n - 1) g^u_n,
# where g^u_n are the growing coefficients of U0.  (The same far field gives the
# consistency relations sum n(n+1) g^q_n = 2 sum g^u_n and
# sum n(n+1) g^w_n = -sum (2n+1) g^u_n; checked to round-off, and F, T agree to ~1e-14
# with direct quadrature of the surface traction.)
def _general_solve(al, case, N):
    """Growing U0 coefficients g^u_n (n = 0..N) for case in {'trans', 'rot', 'shear'}."""
    nun = 8 * (N + 1)
    lo = up = 15
    ab = np.zeros((lo + up + 1, nun))
    rhs = np.zeros(nun)

    def add(i, j, val):
        ab[up + i - j, j] += val

    def col(fam, part, n):  # fam: 0 Q, 1 U0, 2 U2, 3 W ; part: 0 growing, 1 decaying
        return 8 * n + 2 * fam + part

    e = lambda n: math.exp(-(n + 0.5) * al)  # noqa: E731
    sa, ca, ha = math.sinh(al), math.cosh(al), _coth(al)

    def L(n):   # D^(1/2) on the sphere, coefficient of P_n
        return (e(n + 1) / (2 * n + 3) - e(n - 1) / (2 * n - 1)) / _SQRT2

    def gb(n):  # [G D^(1/2)]_n on the sphere
        if case == "trans":
            return L(n)
        if case == "rot":
            return sa * _SQRT2 * e(n) - ha * L(n)
        return -sa * _SQRT2 * e(n)      # shear disturbance

    def gc(n):  # [g D^(1/2)]_n^1 on the sphere
        return 2.0 * L(n) if case == "rot" else 0.0   # g = -rho -> -(s D^-1/2) = +2 L_n

    def bc_row(i, xb, terms):
        """terms: list of (fam, n', coef) multiplying F_{n'} = f_{n'}(xb)."""
        for fam, m, coef in terms:
            if 0 <= m <= N and coef != 0.0:
                if xb == 0.0:
                    add(i, col(fam, 0, m), coef * e(m))
                    add(i, col(fam, 1, m), coef)
                else:
                    add(i, col(fam, 0, m), coef)
                    add(i, col(fam, 1, m), coef * e(m))

    for n in range(N + 1):
        r0 = 8 * n
        for b, (xb, cx, sx) in enumerate(((0.0, 1.0, 0.0), (al, ca, sa))):
            # (b) -> rows r0, r0+1
            i = r0 + b
            bc_row(i, xb, [(1, n, cx),
                           (1, n - 1, -n / (2 * n - 1) if n >= 1 else 0.0),
                           (1, n + 1, -(n + 1) / (2 * n + 3)),
                           (0, n + 1, 0.25 * (n + 1) * (n + 2) / (2 * n + 3)),
                           (0, n - 1, -0.25 * (n - 1) * n / (2 * n - 1) if n >= 1 else 0.0)])
            if b == 1:
                rhs[i] = gb(n)
            # (c) -> rows r0+2, r0+3  (trivial Q_0 = 0 for n = 0)
            i = r0 + 2 + b
            if n >= 1:
                bc_row(i, xb, [(3, n, cx),
                               (3, n - 1, -(n - 1) / (2 * n - 1)),
                               (3, n + 1, -(n + 2) / (2 * n + 3)),
                               (0, n, 0.5 * sx)])
                if b == 1:
                    rhs[i] = gc(n)
            else:
                add(i, col(0, b, 0), 1.0)
            # (a) -> rows r0+6, r0+7  (trivial U2_0 = U2_1 = 0)
            i = r0 + 6 + b
            if n >= 2:
                bc_row(i, xb, [(2, n, cx),
                               (2, n - 1, -(n - 2) / (2 * n - 1)),
                               (2, n + 1, -(n + 3) / (2 * n + 3)),
                               (0, n - 1, 0.25 / (2 * n - 1)),
                               (0, n + 1, -0.25 / (2 * n + 3))])
            else:
                add(i, col(2, b, n), 1.0)
        # continuity -> rows r0+4 (growing), r0+5 (decaying); trivial W_0 = 0 for n = 0
        for part in (0, 1):
            i = r0 + 4 + part
            if n == 0:
                add(i, col(3, part, 0), 1.0)
                continue
            sg = 1.0 if part == 0 else -1.0
            # growing row multiplied by e^{(n+1/2)alpha}: neighbours n-1, n+1 pick up e^{+-alpha}
            fm, fp = (math.exp(al), math.exp(-al)) if part == 0 else (1.0, 1.0)
            for fam, cm, c0, cp in ((0, -(n - 1) / 4, 5 / 4, (n + 2) / 4),
                                    (1, -0.5, 1.0, -0.5),
                                    (2, 0.5 * (n - 2) * (n - 1), -(n + 2) * (n - 1),
                                     0.5 * (n + 3) * (n + 2)),
                                    (3, -0.5 * (n - 1) * sg, (n + 0.5) * sg, -0.5 * (n + 2) * sg)):
                if n - 1 >= 0 and cm != 0.0:
                    add(i, col(fam, part, n - 1), cm * fm)
                if c0 != 0.0:
                    add(i, col(fam, part, n), c0)
                if n + 1 <= N and cp != 0.0:
                    add(i, col(fam, part, n + 1), cp * fp)

    x = solve_banded((lo, up), ab, rhs)
    n = np.arange(N + 1)
    return x[8 * n + 2] * np.exp(-(n + 0.5) * al)   # g^u_n


def _general_loads(al, case, N):
    """(F_x, T_y about the centre) in units mu V c, mu V c^2 (V = U, Omega c or gdot c)."""
    gu = _general_solve(al, case, N)
    n = np.arange(N + 1)
    F = -8.0 * _SQRT2 * math.pi * np.sum(gu)
    T = 8.0 * _SQRT2 * math.pi * np.sum((_coth(al) - 2 * n - 1) * gu)
    return float(F), float(T)


def _general_parallel(al, N):
    sa = math.sinh(al)
    F, T = _general_loads(al, "trans", N)
    out = {"Ft": -F * sa / (6 * math.pi), "Tt": T * sa ** 2 / (8 * math.pi)}
    F, T = _general_loads(al, "rot", N)
    out["Fr"] = F * sa ** 2 / (6 * math.pi)
    out["Tr"] = -T * sa ** 3 / (8 * math.pi)
    return out


# --------------------------------------------------------------- public: parallel motion
def parallel_resistance(h_over_a, n_terms=None, method="oneill"):
    """Resistance of a sphere translating / rotating parallel to a plane wall.

    O'Neill (1964) Mathematika 11:67 (translation) and Dean & O'Neill (1963) Mathematika
    10:13 (rotation), as tabulated by Goldman, Cox & Brenner (1967a) Chem. Eng. Sci.
    22:637.  Convention (wall z = 0, centre at height h, viscosity mu):

    * translating with U e_x (no rotation):  F_x = -6 pi mu a U Ft,   T_y = +8 pi mu a^2 U Tt
    * rotating with Omega e_y (no translation): F_x = +6 pi mu a^2 Omega Fr,
      T_y = -8 pi mu a^3 Omega Tr
    * torques about the sphere centre; Fr = (4/3) Tt by Lorentz reciprocity (computed
      independently here from the rotation problem).

    Limits: Ft, Tr -> 1 and Tt, Fr -> 0 (like (a/h)^4) as h/a -> infinity.  Near contact
    GCB (1967a) quote Ft ~ -(8/15) ln(delta/a) + 0.9588, Tr ~ -(2/5) ln(delta/a) + 0.3817
    (O'Neill & Stewartson 1967), delta = h - a.  The exact series computed here give the
    same slopes but the constants 0.95429 and 0.37089 (Ft + (8/15) ln(delta/a) = 0.95432,
    0.95430 and Tr + (2/5) ln(delta/a) = 0.37096, 0.37090 at delta/a = 1e-5, 1e-6, identical
    with both methods and with doubled n_terms), i.e. the 1967 constants are ~0.5 % / 3 %
    high; use the series, not the asymptotes, as the near-contact reference.
    For h/a >~ 30 Tt and Fr are accurate only to ~1e-14 absolute (see module docstring).

    Parameters
    ----------
    h_over_a : float > 1.
    n_terms : truncation of the series (default ceil(30/alpha) + 10, ~1e-13 relative).
    method : "oneill" (default): the classical three-term recurrence for the O'Neill
        coefficients A_n with the GCB (1967a) force/torque sums (see ``_oneill_classical``);
        "general": the block-tridiagonal formulation of ``_general_solve`` (independent
        cross-check; agrees to ~1e-12 for h/a <= 30).

    Returns
    -------
    dict(Ft=..., Tt=..., Fr=..., Tr=...) of floats.
    """
    al = _alpha(h_over_a)
    N = _n_terms(al, n_terms)
    if method == "oneill":
        r = _oneill_classical(al, N)
    elif method == "general":
        r = _general_parallel(al, N)
    else:
        raise ValueError("method must be 'oneill' or 'general'")
    return {k: float(r[k]) for k in ("Ft", "Tt", "Fr", "Tr")}


# ------------------------------------------------------------ public: shear flow problems
def fixed_sphere_in_shear(h_over_a, n_terms=None):
    """Force and torque on a sphere held fixed in the wall-bounded shear flow u = gdot z e_x.

    Goldman, Cox & Brenner (1967b) Chem. Eng. Sci. 22:653 (see also O'Neill 1968 Chem. Eng.
    Sci. 23:1293 and Chaoui & Feuillebois 2003 QJMAM 56:381, which tabulate f*, t* to many
    digits).  Convention: F_x = 6 pi mu a h gdot f*,  T_y = 4 pi mu a^3 gdot t*  (torque
    about the sphere centre, vorticity of the undisturbed flow is +gdot e_y).
    f*, t* -> 1 as h/a -> infinity (Faxen); f* -> 1.7005, t* -> 0.9440 at contact.

    Solved exactly in bispherical coordinates: the disturbance flow equals -gdot z e_x on
    the sphere and vanishes on the wall; its coefficients satisfy the block-tridiagonal
    recurrences of ``_general_solve`` (wall, sphere and continuity conditions), truncated
    at n_terms (default ceil(30/alpha) + 10), and the loads are the closed-form sums
    F_x = -8 sqrt2 pi sum g^u_n, T_y = 8 sqrt2 pi sum (coth(alpha) - 2n - 1) g^u_n
    (units mu gdot c^2, mu gdot c^3; c = a sinh(alpha)).  The undisturbed shear flow itself
    exerts no force or torque on the (fluid-filled) sphere volume.

    Returns
    -------
    dict(f_star=..., t_star=...) of floats.
    """
    al = _alpha(h_over_a)
    N = _n_terms(al, n_terms)
    F, T = _general_loads(al, "shear", N)
    sa, ca = math.sinh(al), math.cosh(al)
    return {"f_star": float(F * sa ** 2 / (6 * math.pi * ca)),
            "t_star": float(T * sa ** 3 / (4 * math.pi))}


def free_sphere_in_shear(h_over_a, n_terms=None, method="oneill"):
    """Velocity and spin of a force- and torque-free sphere in the shear flow u = gdot z e_x.

    Goldman, Cox & Brenner (1967b) Chem. Eng. Sci. 22:653 (neutrally buoyant sphere; also
    Chaoui & Feuillebois 2003).  Returns U/(gdot h) (translation along +x, U = U_x) and
    Omega/gdot (Omega = Omega_y; +1/2 in unbounded flow).  By linearity the sphere is
    load-free when the shear load of :func:`fixed_sphere_in_shear` balances the resistance
    of :func:`parallel_resistance` to (U, Omega):

        x: 6 pi mu a h gdot f* - 6 pi mu a U Ft + 6 pi mu a^2 Omega Fr = 0
        y: 4 pi mu a^3 gdot t* + 8 pi mu a^2 U Tt - 8 pi mu a^3 Omega Tr = 0

    i.e.  Ft X - (a/h) Fr Y = f*,  -(h/a) Tt X + Tr Y = t*/2  with X = U/(gdot h),
    Y = Omega/gdot.  Limits: X -> 1, Y -> 1/2 as h/a -> infinity.

    Parameters
    ----------
    h_over_a : float > 1;  n_terms : series truncation (default ceil(30/alpha) + 10);
    method : passed to :func:`parallel_resistance`.

    Returns
    -------
    dict(U_over_gdot_h=..., Omega_over_gdot=...) of floats.
    """
    h = float(h_over_a)
    r = parallel_resistance(h, n_terms=n_terms, method=method)
    s = fixed_sphere_in_shear(h, n_terms=n_terms)
    A = np.array([[r["Ft"], -r["Fr"] / h], [-r["Tt"] * h, r["Tr"]]])
    X, Y = np.linalg.solve(A, np.array([s["f_star"], 0.5 * s["t_star"]]))
    return {"U_over_gdot_h": float(X), "Omega_over_gdot": float(Y)}
