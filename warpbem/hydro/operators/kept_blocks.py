"""The store of a solver's last dense matrix, from which the next dense operator takes the blocks
of bodies whose elements did not change (fixed adherent cells: "model no more than a scene
needs"), so that a time-stepping run reassembles only the rows and columns of its moving cells
and holds one matrix, not two.

A ``DenseOperator`` built with a store asks it, when it assembles, which bodies it can keep
(``reusable_bodies``: same elements, same kernel, quadrature, precision and device, the
``BoundaryOperator.signature``), ``take``s the held matrix with those
bodies' blocks placed for its own layout, fills in the rest and ``hold``s the result. The held
matrix is placed, cheapest first:

* "in place": the same layout (the moving cells kept their element counts): the held buffer
  as it is;
* "moved": on the CPU, kept bodies contiguous and the matrix not growing against the block's
  shift: the kept block moved within the held buffer (``_move_block``), which has
  DENSE_HEADROOM room to grow;
* "gathered": a new buffer, the kept blocks copied into it (kernel ``gather_entries``), then the
  old one released.

The store holds one matrix at a time and one holder: an operator whose matrix another took
reassembles on its own, afresh, if it is asked again (``DenseOperator.matrix``).
"""

from __future__ import annotations

import numpy as np

from ... import runtime
from ...kernels import integrals

DENSE_HEADROOM = 0.03  # a dense matrix's buffer (CPU) has room for this share more unknowns


def new_buffer(size: int, kernels, device):
    """An uninitialised flat buffer for a (size, size) matrix: every entry is written by its
    operator (gathered, assembled or a self block), so no zero fill, which on the CPU cost as
    much as the assembly itself for 1632 elements (192 MB); on the CPU with DENSE_HEADROOM room
    for the moves of ``KeptBlocks``."""
    wp = runtime.init()
    capacity = int((size * (1.0 + DENSE_HEADROOM)) ** 2) if device.is_cpu else size**2
    return wp.empty(capacity, dtype=kernels.green.dtype, device=device)


def square(buffer, size: int):
    """The (size, size) matrix at the start of a flat ``buffer``."""
    return buffer[: size**2].reshape((size, size))


class Lease:
    """The token of a held matrix: its holder compares it with the store's (no reference cycle
    between the store and its holder)."""


class KeptBlocks:
    """The last dense matrix of a solver (module docstring), empty at first."""

    def __init__(self):
        self.release()
        self.placement = ""  # how the last taken matrix was placed: "in place", "moved", "gathered"

    def release(self) -> None:
        """Drop the held matrix (its memory goes when no operator view of it remains)."""
        self._lease = self._buffer = self._geometry = self._signature = None

    @property
    def holding(self) -> bool:
        return self._buffer is not None

    @property
    def _size(self) -> int:
        """Rows of the held matrix: three per collocation point of its geometry."""
        return 3 * self._geometry.n_points

    def holds(self, lease) -> bool:
        """Whether the held matrix is the one of ``lease``'s holder."""
        return lease is not None and lease is self._lease

    def buffer(self, lease):
        if not self.holds(lease):
            raise ValueError("this store holds another operator's matrix")
        return self._buffer

    def reusable_bodies(self, signature: tuple, geometry) -> np.ndarray:
        """Per body of ``geometry``: whether its blocks can be taken from the held matrix."""
        if not self.holding or signature != self._signature:
            return np.zeros(len(geometry.body_ranges), dtype=bool)
        return geometry.unchanged_bodies(self._geometry)

    def take(self, signature: tuple, geometry, kept: np.ndarray, kernels, device):
        """(buffer, matrix) for ``geometry``'s layout with the blocks of the ``kept`` bodies
        (``reusable_bodies``) in place, the rest unwritten; the store is empty after it."""
        if not self.holding or signature != self._signature:
            raise ValueError("the store holds no matrix for this operator")
        kept_bodies = np.flatnonzero(kept)
        size = 3 * geometry.n_points
        old_ranges, new_ranges = self._geometry.body_ranges[kept_bodies], geometry.body_ranges[kept_bodies]
        if self._geometry.n_points == geometry.n_points and np.array_equal(old_ranges, new_ranges):
            placement, buffer = "in place", self._buffer
        elif self._move_block(kept_bodies, old_ranges, new_ranges, size, device):
            placement, buffer = "moved", self._buffer
        else:
            placement, buffer = "gathered", new_buffer(size, kernels, device)
            integrals.gather_entries(kernels, device, square(self._buffer, self._size),
                                     self._geometry.points_of(kept_bodies), square(buffer, size),
                                     geometry.points_of(kept_bodies))
        self.release()  # the old buffer, if not taken, goes now: a run holds one matrix, not two
        self.placement = placement
        return buffer, square(buffer, size)

    def hold(self, signature: tuple, geometry, buffer) -> Lease:
        """Hold the matrix of an operator of ``signature`` over ``geometry`` in ``buffer``; its
        lease, which the previous holder's no longer matches."""
        self._lease, self._buffer, self._geometry, self._signature = Lease(), buffer, geometry, signature
        return self._lease

    def _move_block(self, kept, old, new, size: int, device) -> bool:
        """Move the held matrix's kept block (the bodies ``kept``, rows ``old``) to where the new
        layout puts it (``new``), within the held buffer; False where that cannot be done in
        place: on a GPU, kept bodies not contiguous, no room, or the block moving one way while
        the matrix grows the other. Each entry moves at most as far as the block's shift, all
        the same way, so rows copied in that order never overwrite one not yet read."""
        if not device.is_cpu or len(kept) == 0 or not np.array_equal(kept, np.arange(kept[0], kept[-1] + 1)):
            return False
        shift = 3 * int(new[0, 0] - old[0, 0])
        before = self._size
        if size**2 > self._buffer.shape[0] or (shift > 0 and size < before) or (shift < 0 and size > before):
            return False
        first, last = 3 * int(old[0, 0]), 3 * int(old[-1, 1])
        flat = self._buffer.numpy()
        rows = range(first, last) if size <= before and shift <= 0 else range(last - 1, first - 1, -1)
        for r in rows:  # NumPy copies through a buffer where a row overlaps itself
            start = (r + shift) * size + first + shift
            flat[start : start + last - first] = flat[r * before + first : r * before + last]
        return True
