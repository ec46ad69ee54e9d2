"""Hydrodynamics layer: per-solve surface geometry, the double-layer operator (dense or
matrix-free), GMRES and the Completed Double Layer mobility problem."""
