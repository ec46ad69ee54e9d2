"""Hertz contact of elastic spheres (thesis ch. 4.2, eq. 4.8-4.9; Johnson 1985, Contact
Mechanics, ch. 3-4): the formulas the bonds' contact patch (``adhesion.py``), the deformable
cells' spread contact loads (``elastic/deformable.py``) and the charts share, written once.

Two bodies of radii R_1, R_2 pressed together by a normal force F touch on a disc of radius

    a = (3 F R* / (4 E*))^(1/3),    1/R* = 1/R_1 + 1/R_2,    1/E* = c_1 + c_2    (eq. 4.9)

with each body's compliance c = (1 - nu^2) / E, E = 2 G (1 + nu) from its shear modulus G and
Poisson ratio nu. A rigid body (the wall, a rigid cell) adds nothing to 1/E*, a flat one (the
wall) nothing to 1/R*; F <= 0 (a pull) makes no contact, a = 0. On the disc the normal traction
is the Hertz pressure t = t0 sqrt(1 - r^2 / a^2), t0 = -3 F / (2 pi a^2) (eq. 4.8), whose
integral is -F; ``hydro/traction.py`` spreads contact loads over the elements with that profile.

Pressed on a rigid plane, a sphere's centre comes down by the approach delta = a^2 / R; its
surface lies flat on the disc, and outside it at the height rho^2 / (2 R) - delta + u(rho) above
the plane, u Johnson's surface displacement of the Hertz pressure (eq. 3.42):

    u(rho) = [(2 a^2 - rho^2) asin(a / rho) + a sqrt(rho^2 - a^2)] / (pi R),    rho > a,

continuous at rho = a (u = a^2 / 2R) and decaying as a point load's, 4 a^3 / (3 pi R rho), far
from it. The device copy of that profile lowers the receptor tips in the patch
(``kernels/bonds.py``, ``hertz_lowering``); ``surface_height`` is its host form for the charts.
All of it is the small-strain, frictionless, half-space theory: a << R.
"""

from __future__ import annotations

import numpy as np


def compliance(shear_modulus, poisson_ratio):
    """(1 - nu^2) / E (1/Pa), E = 2 G (1 + nu): a body's share of 1 / E* in Hertz's contact."""
    return (1.0 - poisson_ratio**2) / (2.0 * shear_modulus * (1.0 + poisson_ratio))


def contact_radius(normal_force, effective_radius, total_compliance):
    """a = (3 F R* / (4 E*))^(1/3) (m; thesis eq. 4.9), 1 / E* the sum of the bodies'
    compliances; 0 for F <= 0."""
    return np.cbrt(3.0 * np.maximum(normal_force, 0.0) * effective_radius * total_compliance / 4.0)


def contact_traction(normal_force, contact_radius):
    """The normal traction of thesis eq. 4.8 at the patch centre, t0 = -3 F / (2 pi a^2) (Pa),
    the Hertz pressure's peak."""
    return -3.0 * normal_force / (2.0 * np.pi * contact_radius**2)


def surface_height(rho, contact_radius, radius):
    """Height (m) above the patch plane of a sphere of radius R pressed to Hertz contact radius
    a_s, at lateral distance rho, its centre brought down by the approach delta = a_s^2 / R
    (Johnson 1985, Contact Mechanics, eq. 3.42; the lowering of kernels/bonds.py): zero inside
    the patch, the undeformed sphere less delta far from it."""
    rho = np.abs(np.asarray(rho, float))
    a2, sphere = contact_radius**2, rho**2 / (2 * radius)
    if contact_radius <= 0:
        return sphere
    outside = ((2 * a2 - rho**2) * np.arcsin(np.minimum(contact_radius / np.maximum(rho, 1e-300), 1.0))
               + contact_radius * np.sqrt(np.maximum(rho**2 - a2, 0.0))) / (np.pi * radius)
    return np.where(rho <= contact_radius, 0.0, sphere + outside - a2 / radius)
