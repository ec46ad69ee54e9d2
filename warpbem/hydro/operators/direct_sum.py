"""The direct sum ("matrix_free"): Warp recomputes every element integral in every product
(kernel ``apply_matrix_free`` over one list holding every element), in O(N^2) work and O(N)
memory, for operators whose matrix does not fit."""

from __future__ import annotations

import numpy as np

from ...kernels import integrals
from .dense import assembled_alone
from .discrete import DiscreteOperator


class DirectSumOperator(DiscreteOperator):
    """``description`` applied by the direct sum on ``device``."""

    mode = "matrix_free"

    def __init__(self, description, device, point_sources=None):
        super().__init__(description, device, point_sources)
        self.device_lists("direct", integrals.every_item(self.geometry.n_points, self.geometry.n_elements))

    def apply(self, density: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        self._refuse_pole_forces(pole_forces)
        return self._listed_sum(density, self._lists["direct"])

    def diagonal_blocks(self, bodies) -> dict:
        """{p: body p's own block}, each assembled for the body alone."""
        return {p: assembled_alone(self, p) for p in bodies}
