"""SI units. Every public argument and result of warpbem is in SI; these names make scene
values readable, e.g. ``5 * um``, ``1 * cP``."""

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
