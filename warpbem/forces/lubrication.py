"""Lubrication between two equal spheres (thesis ch. 3.2, eq. 3.4-3.8; Nasseri et al. 2000,
after the asymptotics of Jeffrey & Onishi 1984 and O'Neill & Majumdar 1970).

Two spheres of radius a, surface separation eps << a, centres along the unit vector l (from A
to B), moving at u_AB = u_A - u_B relative to each other. The film resists the squeeze and the
sliding of the surfaces with (the force on A, against the relative motion; the thesis writes the
magnitudes)

    F_sq = -(3 pi mu a^2 / (2 eps)) (u_AB . l) l                             (eq. 3.7)
    F_sh = -pi mu a ln(a / eps) (p p + q q) . u_AB                           (eq. 3.8)

p and q (eq. 3.5-3.6) being the two unit vectors normal to l, so that p p + q q = I - l l
(written so here: eq. 3.5-3.6 are undefined for l along z). Both are the leading terms of the
Reynolds film: the gap h(r) = eps + r^2 / a at a distance r from the axis carries the squeeze
pressure p(r) = 3 mu a (u_AB . l) / (2 h^2) and the Couette stress mu u_t / h, whose integrals
over the film are eq. 3.7 and, cut off where h ~ a, eq. 3.8.

Where the boundary element solution resolves the gap the film's pressure and stress are already
in it: the mobility and traction solves of two spheres carry the whole squeeze force (the exact
Maude 1961 / Brenner 1961 series, which eq. 3.7 only approximates as eps -> 0), so adding eq.
3.4-3.8 there would count the film twice (benchmarks/lubrication.py measures where the BEM
stops resolving it; at the separations the repulsion leaves between cells it still does, so no
film force is added to the solves: it is charted beside them, thesis fig. 3.3).
"""

from __future__ import annotations

import numpy as np


def _unit(line):
    line = np.asarray(line, dtype=float)
    norm = np.linalg.norm(line)
    if not norm > 0:
        raise ValueError("the line of centres must be a non-zero vector")
    return line / norm


def _check(radius, viscosity, separation):
    for name, value in (("radius", radius), ("viscosity", viscosity), ("separation", separation)):
        if not np.all(np.asarray(value) > 0):
            raise ValueError(f"{name} must be positive, got {value!r}")
    if np.any(np.asarray(separation) >= radius):
        raise ValueError(f"lubrication needs a separation below the radius ({radius:g} m), got {separation!r}")


def squeeze_force(radius, viscosity, separation, relative_velocity, line) -> np.ndarray:
    """F_sq (N) on sphere A (eq. 3.7): radius (m), viscosity (Pa s), separation eps (m),
    relative_velocity u_A - u_B (m/s), line from A's centre to B's."""
    _check(radius, viscosity, separation)
    l = _unit(line)
    return -1.5 * np.pi * viscosity * radius**2 / separation * (np.dot(relative_velocity, l)) * l


def shear_force(radius, viscosity, separation, relative_velocity, line) -> np.ndarray:
    """F_sh (N) on sphere A (eq. 3.8), arguments as ``squeeze_force``."""
    _check(radius, viscosity, separation)
    l = _unit(line)
    sliding = np.asarray(relative_velocity, dtype=float) - np.dot(relative_velocity, l) * l
    return -np.pi * viscosity * radius * np.log(radius / separation) * sliding
