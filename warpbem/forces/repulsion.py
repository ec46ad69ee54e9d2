"""Electrostatic repulsion between cells and between a cell and the wall (thesis eq. 3.1):

    F(eps) = F0 tau exp(-tau eps) / (1 - exp(-tau eps)) = F0 tau / expm1(tau eps),

the force of the potential U(eps) = -F0 ln(1 - exp(-tau eps)) (F = -dU/d eps), with eps the
separation of the roughness tips: the surface gap minus the roughness of both surfaces
(thesis ch. 3.1, fig. 1.4: cell 175 nm of microvilli, wall 50 nm of steric layer).

Units. The thesis gives tau = 2000 um^-1 and F0 = 1e6 - 1e9 "pN". Since tau eps is a pure
number, F0 tau must be a force: F0 is the energy scale of U, and we read the thesis's values in
the adhesive-dynamics convention of Hammer & Apte (1992, Biophys. J. 63:35) and King & Hammer
(2001, Biophys. J. 81:799), who take this law from Bell, Dembo & Bongrand (1984) with lengths
in um and forces in pN: F0 in pN um, so that F0 tau is in pN. In SI F0 = 1e6 pN um = 1e-12 J
(the default), and the thesis's range is 1e-12 - 1e-9 J. The choice matters little: the
separation where F balances a load W is ln(1 + F0 tau / W) / tau, which moves by
ln(10) / tau = 1.15 nm per decade of F0 (about 8 nm at W = 100 pN over the whole range),
against roughness layers of 225 nm (cell-wall) and 350 nm (cell-cell).

For two cells the force acts along the line of the closest points (the line of centres for
spheres, as in the thesis) and is applied at the closest points, so non-spherical cells also
feel its torque; for the wall it acts along the wall normal.

Stiffness. The force changes e-fold over 1/tau = 0.5 nm; with the squeeze mobility of a 5 um
cell 0.25 um from a surface an explicit step would have to stay below ~1e-5 s (the seed's
limit). The step instead takes the contact forces at the end of the step (backward Euler for
the separations, with the exact contact mobilities from the BEM solver, jointly with any other
stiff law: ``dynamics/implicit.py``), which is stable for any step and keeps eps > 0, since the
energy U is a barrier: +inf once the layers touch. As an interaction
(``forces/interaction.py``) its coordinates are the separations of the contacts within reach,
each with the unit loads of a repulsive force along the contact normal, applied at the closest
points; the law is the configuration's, the search of the contacts its binding's
(``BoundRepulsion``), which derives nothing from the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..options import option, validate
from ..surfaces.gaps import WALL
from ..surfaces.placement import PlacementError, body_label
from .interaction import BoundInteraction, ImplicitCoordinates, Interaction

NEGLIGIBLE_FORCE = 1e-18  # N: contacts whose force would be smaller are left out


@dataclass(frozen=True)
class Repulsion(Interaction):
    """Thesis eq. 3.1 in SI: ``coefficient`` F0 (J), ``inverse_length`` tau (1/m), roughness (m).
    Acts between each free body and every other body and the wall.

    Examples
    --------
    >>> import warpbem as wb
    >>> repulsion = wb.Repulsion()             # thesis eq. 3.1 with its F0 and tau
    >>> eps = repulsion.separation(300e-9, to_wall=True)   # m: a 300 nm gap less both roughness layers
    >>> round(eps * 1e9, 6), round(float(repulsion.force(10e-9)) * 1e12, 2)   # nm; pN at 10 nm
    (75.0, 4.12)
    """

    name = "repulsion"
    implicit = True

    coefficient: float = option(1e-12, "F0 of thesis eq. 3.1 (the thesis's 1e6 pN um; module docstring: units)",
                                "J", low=0.0, high=1.0, low_open=True)
    inverse_length: float = option(2e9, "tau of thesis eq. 3.1: the force changes e-fold over 1/tau", "1/m",
                                   low=0.0, high=1e12, low_open=True)
    cell_roughness: float = option(175e-9, "roughness layer of a cell (microvilli): the gap eps is measured"
                                   " from its top", "m", low=0.0, high=1e-5)
    wall_roughness: float = option(50e-9, "roughness layer of the wall (glycocalyx)", "m", low=0.0, high=1e-5)

    def __post_init__(self):
        validate(self)

    def separation(self, gap, to_wall):
        """Roughness-tip separation eps (m) of a surface gap (m), or of an array of gaps with
        ``to_wall`` an array of flags alike."""
        if np.ndim(to_wall) == 0:
            return gap - self.cell_roughness - (self.wall_roughness if to_wall else self.cell_roughness)
        return gap - self.cell_roughness - np.where(to_wall, self.wall_roughness, self.cell_roughness)

    def force(self, eps):
        """F(eps) in N (eq. 3.1); eps > 0."""
        eps = np.asarray(eps, dtype=float)
        with np.errstate(over="ignore"):  # far contacts: expm1 overflows to inf, the force to 0
            return self.coefficient * self.inverse_length / np.expm1(self.inverse_length * eps)

    def slope(self, eps):
        """dF/d eps in N/m (negative)."""
        x = self.inverse_length * np.asarray(eps, dtype=float)
        with np.errstate(over="ignore"):  # far contacts: sinh overflows to inf, the slope to -0
            return -self.coefficient * self.inverse_length**2 / (4.0 * np.sinh(0.5 * x) ** 2)

    def potential(self, eps):
        """U(eps) = -F0 ln(1 - exp(-tau eps)) in J."""
        return -self.coefficient * np.log1p(-np.exp(-self.inverse_length * np.asarray(eps, dtype=float)))

    @property
    def reach(self) -> float:
        """Separation (m) beyond which the force is below NEGLIGIBLE_FORCE."""
        return np.log1p(self.coefficient * self.inverse_length / NEGLIGIBLE_FORCE) / self.inverse_length

    def balance_separation(self, load: float) -> float:
        """The separation at which the force equals ``load`` (N): ln(1 + F0 tau / load) / tau."""
        return np.log1p(self.coefficient * self.inverse_length / load) / self.inverse_length

    def law(self, s):
        """U, F and dF/d(-eps) >= 0 at separations s (m); U = +inf where the layers touch."""
        s = np.asarray(s, dtype=float)
        inside = s > 0
        eps = np.where(inside, s, 1.0 / self.inverse_length)
        energy = np.where(inside, self.potential(eps), np.inf)
        return energy, np.where(inside, self.force(eps), 0.0), np.where(inside, -self.slope(eps), 0.0)

    def bound(self, model, device=None) -> "BoundRepulsion":
        return BoundRepulsion(self, model)


class BoundRepulsion(BoundInteraction):
    """The repulsion's contacts at a state (its law: the configuration's, ``Repulsion.law``)."""

    def implicit_coordinates(self, bodies, contacts, part, velocity, angular_velocity, dt):
        """The contacts whose separation can come within ``reach`` over a step of at most dt:
        searched out to reach + both roughness layers + twice the distance the fastest surface
        point travels in dt; a contact stays if its separation, closing at its current rate, gets
        within reach. Roughness layers that touch already are a PlacementError (the step retries
        shorter)."""
        rep = self.interaction
        speed = np.abs(velocity).max() + np.abs(angular_velocity).max() * contacts.outer_radii.max()
        search = rep.reach + 2.0 * rep.cell_roughness + 2.0 * speed * dt
        gaps = contacts.within(search)
        if not gaps:
            return None
        pairs = np.array([(gap.body, gap.other) for gap in gaps])
        eps = rep.separation(np.array([gap.distance for gap in gaps]), pairs[:, 1] == WALL)
        if np.any(eps <= 0.0):
            gap = gaps[int(np.flatnonzero(eps <= 0.0)[0])]
            other = "the wall" if gap.other == WALL else f"body {body_label(bodies[gap.other].name, gap.other)}"
            raise PlacementError(f"the roughness layers of body {body_label(bodies[gap.body].name, gap.body)}"
                                 f" and {other} touch"
                                 f" (gap {gap.distance:.4g} m)")
        # the unit force along each contact's normal on its body, minus it on the other (none on the wall)
        present = (pairs != WALL)[:, :, None]
        on = np.maximum(pairs, 0)
        points = np.stack([[gap.point for gap in gaps], [gap.other_point for gap in gaps]], axis=1)
        normal = np.array([gap.normal for gap in gaps])[:, None, :] * np.array([1.0, -1.0])[:, None]
        positions = np.array([body.position for body in bodies])
        force = np.where(present, normal, 0.0)
        torque = np.where(present, np.cross(points - positions[on], normal), 0.0)
        points = np.where(present, points, np.nan)
        rate = (np.einsum("cki,cki->c", force, np.where(present, velocity[on], 0.0))
                + np.einsum("cki,cki->c", torque, np.where(present, angular_velocity[on], 0.0)))
        kept = eps + dt * np.minimum(rate, 0.0) < rep.reach
        if not np.any(kept):
            return None
        eps, pairs, force, torque, points = (x[kept] for x in (eps, pairs, force, torque, points))
        return ImplicitCoordinates(eps, pairs, force, torque, len(bodies), points)
