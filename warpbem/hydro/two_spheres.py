"""Exact hydrodynamic resistance of two equal rigid spheres in unbounded Stokes flow: the ten
scalar functions of Jeffrey & Onishi (1984) that couple forces and torques to velocities and
angular velocities, the 12 x 12 resistance matrix of the pair built from them, and its singular
lubrication part alone. A reference for the boundary-element two-cell solves near contact
(benchmarks/two_spheres.py), and the part that diverges at contact, to be taken out of two-cell
snapshots so that the smooth rest interpolates.

Conventions (Jeffrey & Onishi 1984, J. Fluid Mech. 139:261, §1; Kim & Karrila 1991, §11.3)
-------------------------------------------------------------------------------------------
Spheres 1 and 2, radius a, centres x_1, x_2; r = |x_2 - x_1|, d = (x_2 - x_1) / r points from
sphere 1 to sphere 2; s = r / a (JO's s = 2 r / (a_1 + a_2)), xi = s - 2 the surface gap over a.
F_k, T_k are the force and torque (about its centre) that sphere k exerts on the fluid, i.e. the
external load that keeps it moving with U_k, Omega_k (minus the hydrodynamic drag on it), and

    (F_1, T_1, F_2, T_2) = R (U_1, Omega_1, U_2, Omega_2),
    F_k = sum_l mu (A_kl U_l + Bt_kl Omega_l),   T_k = sum_l mu (B_kl U_l + C_kl Omega_l),
    A_kl = 6 pi a   [X^A_kl d d + Y^A_kl (I - d d)],       Bt_kl = B_lk^T,
    B_kl = 4 pi a^2  Y^B_kl eps.d        ((eps.d)_ij = eps_ijk d_k, so (eps.d) U = U x d),
    C_kl = 8 pi a^3 [X^C_kl d d + Y^C_kl (I - d d)].

So X^A is normalised by 6 pi mu a, Y^B by 4 pi mu a^2 and X^C by 8 pi mu a^3 (JO's 3 pi (a_1+a_2),
pi (a_1+a_2)^2 and pi (a_1+a_2)^3 for equal spheres); an isolated sphere has X11A = Y11A = X11C =
Y11C = 1 and the rest 0. Equal spheres: A_22 = A_11, A_21 = A_12, C likewise; Y22B = -Y11B and
Y21B = -Y12B (the pair seen from sphere 2 has d reversed). With this d, Y11B < 0 and Y12B > 0:
sphere 1 sliding at U_1 past a held sphere 2 is dragged most on its gap side, so the torque it
exerts on the fluid, T_1 = 4 pi mu a^2 Y11B (U_1 x d), points along d x U_1 (sources that take
d from 2 to 1, or B as the transpose, print Y^B with the other sign). R is symmetric (Lorentz
reciprocity) and positive definite.

Far and moderate separations: the twin multipole series (JO 1984 §3-7)
---------------------------------------------------------------------
With t = 2/s, each function is a power series with coefficients c_m = f_m(1) / 4^m, f_m the
coefficient polynomials of JO at size ratio lambda = 1:

    X11A = sum_{m even} c^XA_m t^m,   X12A = -sum_{m odd} c^XA_m t^m     (f_m: JO eq. 3.15)
    Y11A, Y12A likewise with c^YA,      Y11B =  sum_{m odd} c^YB_m t^m,  Y12B = -sum_{m even} c^YB_m t^m
    X11C = sum_{m even} c^XC_m t^m,   X12C = -sum_{m odd} c^XC_m t^m
    Y11C = sum_{m even} c^YC_m t^m,   Y12C = +sum_{m odd} c^YC_m t^m

``twin_multipole_coefficients`` computes them from the recurrences of JO 1984 for the multipole
coefficients P_npq, V_npq, Q_npq, as corrected by Townsend (2023, Phys. Fluids 35:127126,
arXiv:1802.08226; his eq. 5-9 for X^A, JO eq. 4.6-4.11 with his eq. 18 for Y^A, his eq. 21 for
Y^B, JO eq. 7.3-7.5 with his eq. 29 for Y^C); f_m = 2^m sum_q P_1(m-q)q (Q for Y^B, times 2,
and Y^C) at lambda = 1. X^C, whose flow is azimuthal, comes from the rotlet reflections written
out below. Their values to m = 200 are stored in ``two_spheres_series.py`` (written by running
this module). The series is used for s >= SWITCH = 2.5, where its truncation, ~ t^200 / 4, is
1e-20: from s = 2.4 to 6 it and the lubrication form below agree to 5e-15 (relative; the series
alone is off by 4e-13 at s = 2.3, 3.5e-9 at 2.2), so the switch sits in the middle of that band.

X^C: the flow of rotation about the line of centres is u = grad(psi) x d with psi harmonic and
axisymmetric. Each sphere carries psi_k = sum_n A^k_n a^(n+2) r_k^-(n+1) P_n(cos theta_k)
(theta_k from d); on its surface the condition u = Omega_k x (x - x_k) gives, mode by mode,
A^k_n = (Omega_k . d) a delta_n0 - a^(n+1) (regular coefficient n+2 of the other sphere's
field), and the axial re-expansion r_2^-(j+1) P_j(cos theta_2) = sum_n (-1)^j binom(n+j, n)
r_1^n P_n(cos theta_1) / r^(n+j+1) (sign (-1)^n for the field of sphere 1 about sphere 2) closes
the reflections. In powers of 1/s: A^1_n(k) = delta_n0 delta_k0 - sum_j (-1)^j binom(n+j+2, n+2)
A^2_j(k-n-j-3), A^2_n(k) = -(-1)^n sum_j binom(n+j+2, n+2) A^1_j(k-n-j-3), and the torques are
T_k = 8 pi mu a^2 A^k_0 d: in units of a Omega_1, X11C = sum_k A^1_0(k) s^-k and X12C =
sum_k A^2_0(k) s^-k. They give
X11C = 1 + s^-6 + 3 s^-8 + ..., X12C = -s^-3 - ..., JO's f_k; the tests compare them with the
exact solution of Jeffery (1915) and with Jeffrey's (1992) contact values.

Near contact: the lubrication form (JO 1984 §3-7)
-------------------------------------------------
As xi -> 0 each function is (JO 1984 eq. 3.17 and 4.15-4.16, their §5 and §7 for Y^B and Y^C,
g's in their eq. 5.6 and 7.10; Jeffrey 1992, Phys. Fluids A 4:16, for X^C; Townsend 2023 eq.
16-34, which correct JO's misprints)

    F = h_1 / xi + h_2 ln(1/xi) + const + h_3 xi ln(1/xi) + O(xi),

    (h_1, h_2, h_3)      XA: (1/4, 9/40, 3/112)   YA: (0, 1/6, 0)      YB: (0, -1/4, -1/8)
    for 11 and -12:      XC: (0, 0, -1/8)         YC 11: (0, 1/5, 47/250)  YC 12: (0, 1/20, 31/500)

(-12 for A, B, X^C, +12 for Y^C: the sign of the series above; JO's g_1, g_2, g_3 at lambda = 1).
The series converges ever more slowly as s -> 2 (its coefficients tend to h_1 + 2 h_2 / m + ...).
Below SWITCH the singular behaviour is summed in closed form instead, as JO do to obtain their
constants: with u = 1 - t^2 = xi (4 + xi) / (2 + xi)^2 and w = ln((s + 2) / (s - 2)),

    sum_{m even} c_m t^m = c_0 + h_1 t^2/u - h_2 ln u - h_3 u ln u + sum_{m even >= 2} e_m t^m
    sum_{m odd}  c_m t^m =       h_1 t/u   + h_2 w   + h_3 (u w + 2 t) + sum_{m odd} e_m t^m

where e_m = c_m - h_1 - 2 h_2 / m + 4 h_3 / (m (m - 2)) (for m = 2: - h_3 instead of the last
term) are the Taylor coefficients the closed forms take out. The rest's coefficients fall like
m^-3 (about 10 / m^3, of changing sign), so the form holds down to contact: as xi -> 0 it tends
to the asymptotic form above, with JO's constants (X11A 0.995419, X12A -0.350153, Y11A 0.998317,
Y12A -0.273652, Y11B 0.23892, Y12B -0.00162, Y11C 0.702834, Y12C -0.027464, as the lubrication
code of RigidMultiblobsWall quotes them) to 7e-5, and Jeffrey's exact X11C = 7 zeta(3)/8, X12C =
-zeta(3)/8 to 1.5e-5 (tests; JO's own X^A constants miss the exact contact value of X11A + X12A,
0.6451414 from the Stimson-Jeffery series, by 1.3e-4, these by 6e-6). Its error is that of the
truncated rest: 1e-5 of X11A + X12A (the pair moving together, where the singular terms cancel)
at contact, 1.2e-8 of the squeeze X11A - X12A, both against the exact bispherical series, and
below 1e-9 for xi >= 0.1 (X^A, and X^C against Jeffery's series).

The singular part
-----------------
``singular_functions`` returns the terms that diverge at contact, h_1/xi + h_2 ln(1/xi) of each
function with the sign of the function (nothing for X^C, which stays bounded), and
``singular_resistance_matrix`` assembles them like R, so that R - R_singular is bounded as
xi -> 0 (it keeps the O(1) constants and the xi ln(1/xi) terms).
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.special import comb

SWITCH = 2.5  # s at and above which the plain series is used (its truncation there: ~1e-20)

# function: (family of coefficients, parity of its powers, sign, (h_1, h_2, h_3) of sign * function)
_FORMS = {
    "X11A": ("XA", 0, 1.0, (1 / 4, 9 / 40, 3 / 112)),
    "X12A": ("XA", 1, -1.0, (1 / 4, 9 / 40, 3 / 112)),
    "Y11A": ("YA", 0, 1.0, (0.0, 1 / 6, 0.0)),
    "Y12A": ("YA", 1, -1.0, (0.0, 1 / 6, 0.0)),
    "Y11B": ("YB", 1, 1.0, (0.0, -1 / 4, -1 / 8)),
    "Y12B": ("YB", 0, -1.0, (0.0, -1 / 4, -1 / 8)),
    "X11C": ("XC", 0, 1.0, (0.0, 0.0, -1 / 8)),
    "X12C": ("XC", 1, -1.0, (0.0, 0.0, -1 / 8)),
    "Y11C": ("YC", 0, 1.0, (0.0, 1 / 5, 47 / 250)),
    "Y12C": ("YC", 1, 1.0, (0.0, 1 / 20, 31 / 500)),
}
FUNCTIONS = tuple(_FORMS)


def _gap_ratio(s) -> np.ndarray:
    s = np.asarray(s, dtype=float)
    if not np.all(s > 2.0):
        raise ValueError(f"two equal spheres need s = r / a > 2 (apart), got {s!r}")
    return s


@functools.cache
def _coefficients() -> dict:
    from . import two_spheres_series  # generated data, loaded on first use

    return {name: np.array(getattr(two_spheres_series, name)) for name in ("XA", "YA", "YB", "XC", "YC")}


def _series(c: np.ndarray, parity: int, t: np.ndarray) -> np.ndarray:
    m = np.arange(parity, len(c), 2)
    return (c[m] * t[..., None] ** m).sum(axis=-1)


def _taken_out(m: np.ndarray) -> tuple:
    """Taylor coefficients in t^m of the three closed forms (1/xi-, ln- and xi ln-like)."""
    third = -4.0 / np.where(m == 2, -4.0, m * (m - 2.0))  # m = 2 (even only): -u ln u starts with +t^2
    return np.ones_like(m, dtype=float), 2.0 / m, third


def _lubrication(c: np.ndarray, parity: int, h: tuple, s: np.ndarray) -> np.ndarray:
    xi = s - 2.0
    t = 2.0 / s
    u = xi * (4.0 + xi) / (2.0 + xi) ** 2  # 1 - t^2 without the cancellation near contact
    if parity == 0:
        closed = (c[0] + h[0] * t * t / u - h[1] * np.log(u) - h[2] * u * np.log(u))
    else:
        w = np.log((s + 2.0) / xi)
        closed = h[0] * t / u + h[1] * w + h[2] * (u * w + 2.0 * t)
    m = np.arange(2 - parity, len(c), 2)
    k1, k2, k3 = _taken_out(m)
    rest = c[m] - h[0] * k1 - h[1] * k2 - h[2] * k3
    return closed + (rest * t[..., None] ** m).sum(axis=-1)


def resistance_functions(s) -> dict:
    """The ten scalar functions (dimensionless, JO normalisation, see the module docstring) at
    s = r / a > 2 (scalar or array): {"X11A": ..., ..., "Y12C": ...}."""
    s = _gap_ratio(s)
    coefficients = _coefficients()
    far = s >= SWITCH
    t = 2.0 / s
    values = {}
    for name, (family, parity, sign, h) in _FORMS.items():
        c = coefficients[family]
        near = _lubrication(c, parity, h, np.where(far, 3.0, s))  # 3.0: a placeholder where unused
        values[name] = sign * np.where(far, _series(c, parity, t), near)
    return values


def singular_functions(s) -> dict:
    """The terms of each function that diverge at contact, h_1 / xi + h_2 ln(1/xi), with its
    sign (zero for X11C and X12C), at s = r / a > 2."""
    xi = _gap_ratio(s) - 2.0
    return {name: sign * (h[0] / xi + h[1] * np.log(1.0 / xi)) for name, (_, _, sign, h) in _FORMS.items()}


def _assemble(f: dict, viscosity: float, radius: float, line) -> np.ndarray:
    """The 12 x 12 matrix of the functions ``f`` (module docstring), rows (F_1, T_1, F_2, T_2),
    columns (U_1, Omega_1, U_2, Omega_2)."""
    d = np.asarray(line, dtype=float) / np.linalg.norm(line)
    along = np.outer(d, d)
    across = np.eye(3) - along
    cross = np.array([[0.0, d[2], -d[1]], [-d[2], 0.0, d[0]], [d[1], -d[0], 0.0]])  # eps_ijk d_k
    mu, a = viscosity, radius
    A = {kl: 6 * np.pi * mu * a * (f[f"X{kl}A"] * along + f[f"Y{kl}A"] * across) for kl in ("11", "12")}
    C = {kl: 8 * np.pi * mu * a**3 * (f[f"X{kl}C"] * along + f[f"Y{kl}C"] * across) for kl in ("11", "12")}
    B11, B12 = (4 * np.pi * mu * a**2 * f[f"Y{kl}B"] * cross for kl in ("11", "12"))
    B = [[B11, B12], [-B12, -B11]]  # B_21 = -Y12B eps.d, B_22 = -Y11B eps.d: d reversed for sphere 2
    R = np.zeros((12, 12))
    for k in range(2):
        for l in range(2):
            rows, cols = slice(6 * k, 6 * k + 3), slice(6 * l, 6 * l + 3)
            spin_rows, spin_cols = slice(6 * k + 3, 6 * k + 6), slice(6 * l + 3, 6 * l + 6)
            same = "11" if k == l else "12"
            R[rows, cols] = A[same]
            R[spin_rows, spin_cols] = C[same]
            R[spin_rows, cols] = B[k][l]
            R[rows, spin_cols] = B[l][k].T
    return R


def _checked(viscosity, radius, line) -> float:
    if not (viscosity > 0 and radius > 0):
        raise ValueError(f"viscosity and radius must be positive, got {viscosity!r}, {radius!r}")
    line = np.asarray(line, dtype=float)
    if line.shape != (3,):
        raise ValueError(f"the line of centres must be a 3-vector, got shape {line.shape}")
    return float(np.linalg.norm(line)) / radius


def resistance_matrix(viscosity: float, radius: float, line) -> np.ndarray:
    """R (SI) of two spheres of ``radius`` (m) in fluid of ``viscosity`` (Pa s), ``line`` =
    x_2 - x_1 (m, |line| > 2 radius): (F_1, T_1, F_2, T_2) = R (U_1, Omega_1, U_2, Omega_2), the
    loads (N, N m) the spheres exert on the fluid from their velocities (m/s, rad/s)."""
    s = _checked(viscosity, radius, line)
    return _assemble(resistance_functions(s), viscosity, radius, line)


def singular_resistance_matrix(viscosity: float, radius: float, line) -> np.ndarray:
    """The part of ``resistance_matrix`` that diverges at contact (``singular_functions``
    assembled the same way); the difference of the two is bounded as the gap closes."""
    s = _checked(viscosity, radius, line)
    return _assemble(singular_functions(s), viscosity, radius, line)


# ------------------------------------------------------------------ the twin multipole recurrences
def _at(X: np.ndarray, n, p, q) -> np.ndarray:
    """X[n, p, q], zero where p or q < 0 (a multipole the reflections have not reached)."""
    inside = (p >= 0) & (q >= 0)
    return np.where(inside, X[n, np.maximum(p, 0), np.maximum(q, 0)], 0.0)


def _reflections(order: int, start: str) -> tuple:
    """sum_q P_1(m-q)q and sum_q Q_1(m-q)q, m = 0..order, at lambda = 1: the recurrences of
    JO 1984 as corrected by Townsend 2023. ``start``: "XA" (axisymmetric translation, his eq.
    5-8), "YA" (translation across the line, JO eq. 4.6-4.11 and his eq. 18) or "YC" (rotation
    about an axis across the line, JO eq. 7.3-7.5: the same recurrence from Q_100 = 1)."""
    shape = (order + 2, order + 1, order + 1)
    P, V, Q = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    if start == "YC":
        Q[1, 0, 0] = 1.0
    else:
        P[1, 0, 0] = V[1, 0, 0] = 1.0
    for k in range(1, order + 1):  # total degree p + q: the right sides are of lower degree
        for p in range(k):  # q = 0 leaves empty sums (zero)
            q = k - p
            n = np.arange(1, p + 2, dtype=float)[:, None]  # n > p + 1 stays zero
            s = np.arange(1, q + 1, dtype=float)[None, :]
            ni, si = n.astype(int), s.astype(int)
            if start == "XA":
                c = comb(n + s, n)
                P[1:p + 2, p, q] = (c * (n * (2 * n + 1) * (2 * n * s - n - s + 2) / (2 * (n + 1) * (2 * s - 1) * (n + s))
                                         * _at(P, si, q - si, p - ni + 1)
                                         - n * (2 * n - 1) / (2 * (n + 1)) * _at(P, si, q - si, p - ni - 1)
                                         - n * (4 * n**2 - 1) / (2 * (n + 1) * (2 * s + 1)) * _at(V, si, q - si - 2, p - ni + 1))
                                    ).sum(axis=1)
                V[1:p + 2, p, q] = P[1:p + 2, p, q] - (2 * n / ((n + 1) * (2 * n + 3)) * c
                                                       * _at(P, si, q - si, p - ni - 1)).sum(axis=1)
                continue
            c = comb(n + s, n + 1)
            P[1:p + 2, p, q] = (c * ((2 * n + 1) / (2 * (n + 1)) * (3 * (n + s) - (n * s + 1) * (2 * n * s - s - n + 2))
                                     / (s * (n + s) * (2 * s - 1)) * _at(P, si, q - si, p - ni + 1)
                                     + n * (2 * n - 1) / (2 * (n + 1)) * _at(P, si, q - si, p - ni - 1)
                                     + n * (4 * n**2 - 1) / (2 * (n + 1) * (2 * s + 1)) * _at(V, si, q - si - 2, p - ni + 1)
                                     - 2 * (4 * n**2 - 1) / (3 * (n + 1)) * _at(Q, si, q - si - 1, p - ni + 1))
                                ).sum(axis=1)
            Q[1:p + 2, p, q] = (c * (s / (n + 1) * _at(Q, si, q - si - 1, p - ni)
                                     - 3 / (2 * n * s * (n + 1)) * _at(P, si, q - si, p - ni))).sum(axis=1)
            V[1:p + 2, p, q] = P[1:p + 2, p, q] + (2 * n / ((n + 1) * (2 * n + 3)) * c
                                                   * _at(P, si, q - si, p - ni - 1)).sum(axis=1)
    m = np.arange(order + 1)
    return tuple(np.array([X[1, k - np.arange(k + 1), np.arange(k + 1)].sum() for k in m]) for X in (P, Q))


def _torsion(order: int) -> np.ndarray:
    """The X^C family from the rotlet reflections (module docstring): A^1_0(m) for even m and
    -A^2_0(m) for odd m, with Omega_1 = d, Omega_2 = 0."""
    one, two = np.zeros((order + 1, order + 1)), np.zeros((order + 1, order + 1))  # [n, power of 1/s]
    one[0, 0] = 1.0
    for k in range(3, order + 1):
        for n in range(k - 2):
            j = np.arange(k - n - 2)
            b = comb(n + j + 2, n + 2)
            one[n, k] = -np.sum((-1.0) ** j * b * two[j, k - n - j - 3])
            two[n, k] = -(-1.0) ** n * np.sum(b * one[j, k - n - j - 3])
    return np.where(np.arange(order + 1) % 2 == 0, one[0], -two[0])


def twin_multipole_coefficients(order: int) -> dict:
    """c_m = f_m(1) / 4^m, m = 0..order, of the families XA, YA, YB, XC, YC (module docstring)."""
    xa, _ = _reflections(order, "XA")
    ya, yb = _reflections(order, "YA")
    _, yc = _reflections(order, "YC")
    two_m = 2.0 ** np.arange(order + 1)  # sum_q P_1(m-q)q = f_m / 2^m at lambda = 1
    return {"XA": xa / two_m, "YA": ya / two_m, "YB": 2 * yb / two_m, "XC": _torsion(order) / two_m,
            "YC": yc / two_m}


def _write_series(order: int = 200) -> None:
    """Write two_spheres_series.py beside this module (about 30 s at order 200)."""
    from pathlib import Path

    coefficients = twin_multipole_coefficients(order)
    lines = ['"""Twin multipole coefficients c_m = f_m(1) / 4^m (m = 0..ORDER) of two equal spheres,',
             "written by ``python -m warpbem.hydro.two_spheres`` (twin_multipole_coefficients); do not",
             'edit. two_spheres.py says what they are."""', "", f"ORDER = {order}"]
    for name, c in coefficients.items():
        lines.append(f"{name} = (")
        lines += [f"    {value!r}," for value in c.tolist()]
        lines.append(")")
    Path(__file__).with_name("two_spheres_series.py").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    _write_series()
