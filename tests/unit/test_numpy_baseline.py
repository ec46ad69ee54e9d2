"""The NumPy baseline of benchmarks/scale.py computes the same operator as the Warp kernels, so
the Warp/NumPy speed ratios compare like with like."""

import sys
from pathlib import Path

import numpy as np

from warpbem import Body, mesh
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, QuadratureOptions, discrete_form

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import numpy_baseline  # noqa: E402


def test_numpy_baseline_matches_warp_operator(rng):
    s = mesh.sphere(1.0, 2)
    for wall in (False, True):
        bodies = [Body(s, position=(0, 0, 1.6)), Body(s, position=(2.4, 0.3, 1.3))]
        geometry = SurfaceGeometry.from_bodies(bodies, 3, 1.0, wall)
        op = discrete_form(BoundaryOperator(geometry, wall, QuadratureOptions(adaptive=False)), "matrix_free")
        q = rng.standard_normal(op.size)
        np.testing.assert_allclose(numpy_baseline.apply(geometry, q, wall), op.matvec(q), rtol=0, atol=1e-12)
