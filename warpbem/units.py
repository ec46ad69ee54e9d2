"""SI units. Every public argument and result of warpbem is in SI; these names make scene
values readable, e.g. ``5 * um``, ``1 * cP``: lengths ``m``, ``um``, ``nm``; times ``s``,
``ms``; forces ``N``, ``pN``; pressures and moduli ``Pa``, ``kPa``; viscosity ``cP``
(centipoise, 1e-3 Pa s); line force and surface tension ``dyn_per_cm`` (1e-3 N/m, a bond
spring's stiffness in thesis Table 4.1); shear stress ``dyn_per_cm2`` (0.1 Pa).

Examples
--------
>>> from warpbem.units import cP, dyn_per_cm, pN, um
>>> radius, viscosity = 5 * um, 1.2 * cP       # m, Pa s
>>> print(f"{radius:g} m, {viscosity:g} Pa s, {100 * pN:g} N, {0.5 * dyn_per_cm:g} N/m")
5e-06 m, 0.0012 Pa s, 1e-10 N, 0.0005 N/m
>>> print(f"{2.5e-7 / um:g} um")               # and back: divide by the unit
0.25 um
"""

m = 1.0
um = 1e-6
nm = 1e-9
s = 1.0
ms = 1e-3
N = 1.0
pN = 1e-12
Pa = 1.0
kPa = 1e3
cP = 1e-3  # centipoise, Pa s
dyn_per_cm = 1e-3  # surface tension / line force, N/m
dyn_per_cm2 = 0.1  # shear stress, Pa

# Plausible magnitudes of a white blood cell problem in SI. A value far outside was most likely
# typed in another unit (a position of 6, meaning 6 um, is 6 m): scene files refuse it unless the
# scene says ``any_scale = true`` (declared by the scene's options, warpbem/options.py).
PLAUSIBLE_SIZE = (1e-8, 1e-3)  # m: a body's radius or a mesh file's size, 10 nm to 1 mm
PLAUSIBLE_POSITION = (0.0, 1e-2)  # m: each coordinate of a position or an array's pitch, up to a flow chamber's 1 cm
PLAUSIBLE_SHEAR_RATE = (0.0, 1e5)  # 1/s: physiological flows reach 1e3-1e4
# Pa s: from a gas's to a hundred times water's; 1 and 1.2 (water and plasma typed in cP) lie above
PLAUSIBLE_VISCOSITY = (1e-5, 0.1)
PLAUSIBLE_FORCE = (0.0, 1e-6)  # N: a cell's loads are pN to nN
PLAUSIBLE_TORQUE = (0.0, 1e-12)  # N m: pN um = 1e-18 N m
# A Body placed farther from the origin than this many of its own sizes has its position and its
# mesh in different units (a 5e-6 m sphere at 6 m); no problem in any units puts a body there.
FARTHEST_IN_SIZES = 1e5
# what a message refusing a value too large says of its unit: (the unit, the smaller unit the value
# was most likely typed in, and its size)
_SMALLER = {"m": ("lengths are in metres", "um", um), "Pa s": ("viscosities are in Pa s", "cP", cP),
            "N": ("forces are in newtons", "pN", pN), "N m": ("torques are in N m", "pN um", pN * um),
            "1/s": ("shear rates are in 1/s", None, None)}


def hint(unit: str, value: float) -> str:
    """What a message refusing ``value`` in ``unit`` as too large says of the unit: "lengths are in
    metres (6 um is 6e-06 m)"; "" for a unit without one."""
    if unit not in _SMALLER:
        return ""
    text, smaller, size = _SMALLER[unit]
    return text if smaller is None else f"{text} ({value:g} {smaller} is {value * size:g} {unit})"
