"""The normal load behind each of the thesis's Hertz contact areas (issue 24 item 3): eq. 4.9,
a_s = (3 F a / (4 E*))^(1/3) with E* = E / (1 - nu^2) (thesis L801-L804; a the cell radius, F
"the sum of the normal components of all surviving bonds", L807), solved for F from the average
areas the thesis reports, pi a_s^2, under both readings of its modulus eta (Table 4.1 calls it
the shear modulus, eq. 4.9 a Young's modulus): E = eta, or E = 2 eta (1 + nu). Beside them the
contact angle omega = asin(a_s / a) (eq. 4.10; the thesis reports about 11 degrees for figs.
4.10-4.11), the mean force per surviving bond where the thesis gives their number, and the
stretch that force takes at the bond's spring constant. Line numbers: the thesis text file
(docs/reference/adhesion-anchors.md).

    python scenes/thesis_ch4_contact.py
"""

from __future__ import annotations

import numpy as np

NU = 0.33  # Table 4.1, L828
THESIS = [  # (what, mean contact area m^2, eta Pa, cell radius m, surviving bonds, sigma N/m, line)
    ("figs. 4.4-4.5, highly deformable", 6.2e-12, 508.0, 5e-6, None, 0.1, "L836"),
    ("figs. 4.4-4.5, moderately deformable", 1.9e-12, 1000.0, 5e-6, None, 0.1, "L836"),
    ("fig. 4.11, a = 5 um", 3.19e-12, 4000.0, 5e-6, 39, 5e-4, "L888"),
    ("fig. 4.11, a = 4 um", 1.87e-12, 4000.0, 4e-6, 33, 5e-4, "L888"),
]


def implied_load(area: float, young: float, radius: float, nu: float = NU) -> float:
    """F (N) of eq. 4.9 that gives the contact area ``area`` (m^2) for Young's modulus ``young``."""
    contact_radius = np.sqrt(area / np.pi)
    return 4.0 * young / (1.0 - nu**2) * contact_radius**3 / (3.0 * radius)


def rows() -> list[dict]:
    out = []
    for what, area, eta, radius, bonds, sigma, line in THESIS:
        a_s = np.sqrt(area / np.pi)
        for reading, young in (("E = eta", eta), ("E = 2 eta (1 + nu)", 2.0 * eta * (1.0 + NU))):
            force = implied_load(area, young, radius)
            per_bond = force / bonds if bonds else float("nan")
            out.append(dict(case=what, line=line, area_um2=area * 1e12, eta_kPa=eta / 1e3, radius_um=radius * 1e6,
                            contact_radius_um=a_s * 1e6, angle_deg=np.degrees(np.arcsin(a_s / radius)),
                            modulus=reading, load_nN=force * 1e9, per_bond_pN=per_bond * 1e12,
                            stretch_nm=per_bond / sigma * 1e9))
    return out


def main():
    table = rows()
    keys = list(table[0])
    print(" | ".join(keys))
    for r in table:
        print(" | ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in r.values()))


if __name__ == "__main__":
    main()
