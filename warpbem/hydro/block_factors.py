"""The LU factors of free bodies' own blocks, kept by a solver across systems and shared by every
body of the same shape at the same height (the block-Jacobi preconditioner of
``CompletedDoubleLayer.preconditioner``).

A free body's own block, D (I - Pi) + Pi in the completed double layer, depends on its elements
relative to its reference point and on its height above the wall alone: the wall's image and the
rigid modes (about the reference point) do not change when the body moves along the wall. The
pairs' snapshots (``dynamics/pairwise.py``) solve two cells at one lattice point after another, at
the few heights of the pair lattice, and factored both blocks anew each time: py-spy put the LU at
24 % of a two-cell capture run on k = 2 meshes and 13 % on k = 3 (``scenes/rolling_capture.toml``).
A body whose contact refinement differs (a neighbour near it) has other elements, so another key.

The key is a digest of the body's element nodes with its reference point's lateral position
subtracted, rounded to KEY_ROUNDING scaled units (the subtraction leaves round-off that would
otherwise split equal blocks), with its density order and the scale. Blocks equal to that rounding
share one factorisation; it preconditions GMRES, whose answer holds to the solver's tolerance
whatever the preconditioner, so a reused factor moves a solution by less than that tolerance.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict

import numpy as np

# scaled units (the bodies' mean radius): nodes equal to this are the same block
KEY_ROUNDING = 1e-10
# bytes of factors kept per solver: 4 blocks of a refined k = 3 cell (3663 unknowns, 107 MB each),
# about 40 of a k = 2 cell
DEFAULT_BUDGET = 512e6


def block_key(element_nodes, centre, density_order: int, length_scale: float) -> bytes:
    """The digest of a free body's own block: its ``element_nodes`` ((E, 9, 3), scaled) less its
    reference point's lateral position ``centre[:2]``, rounded to KEY_ROUNDING."""
    shifted = np.asarray(element_nodes, dtype=np.float64) - np.array([centre[0], centre[1], 0.0])
    rounded = np.round(shifted / KEY_ROUNDING).astype(np.int64)
    digest = hashlib.blake2b(rounded.tobytes(), digest_size=20)
    digest.update(np.array([density_order, length_scale, *rounded.shape], dtype=np.float64).tobytes())
    return digest.digest()


class BlockFactors:
    """The least recently used LU factors (scipy.linalg.lu_factor's (lu, piv)) by block key, up
    to ``budget`` bytes; ``hits`` and ``misses`` count the look-ups."""

    def __init__(self, budget: float = DEFAULT_BUDGET):
        self.budget = float(budget)
        self._factors: OrderedDict = OrderedDict()
        self._bytes = 0
        self.hits = 0
        self.misses = 0

    def get(self, key):
        """The factors kept under ``key``, or None."""
        factors = self._factors.get(key)
        if factors is None:
            self.misses += 1
            return None
        self._factors.move_to_end(key)
        self.hits += 1
        return factors

    def put(self, key, factors) -> None:
        """Keep ``factors`` under ``key``, dropping the least recently used beyond the budget (a
        block larger than the whole budget is not kept)."""
        size = sum(a.nbytes for a in factors)
        if size > self.budget:
            return
        self._factors[key] = factors
        self._bytes += size
        while self._bytes > self.budget:
            _, dropped = self._factors.popitem(last=False)
            self._bytes -= sum(a.nbytes for a in dropped)
