"""Warp device code of warpbem (installed as ``warpbem.kernels``).

Only @wp.func / @wp.kernel definitions and array-in/array-out launchers live here; nothing in
this package knows about bodies, scenes or units. Kernels are built by factories for a given
floating-point type and for free space or the half space above a no-slip wall, all from the one
Green's-function signature of ``greens.py``.
"""
