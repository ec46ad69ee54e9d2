"""The dense form: the matrix assembled by Warp (kernel ``assemble_entries``, the rows split over
the CPU threads), its self blocks from the identity (``description.py``) or the single layers'
Duffy integrals, applied by NumPy BLAS on the CPU and by the Warp kernel ``dense_matvec`` on
CUDA. With a ``KeptBlocks`` store the blocks of unmoved bodies come from the solver's last
matrix and only the moving bodies' rows and columns are assembled."""

from __future__ import annotations

import numpy as np

from ...kernels import integrals
from ...kernels.launch import blas_on_all_cores
from .description import IDENTITY_KINDS, BoundaryOperator
from .discrete import DiscreteOperator
from .kept_blocks import KeptBlocks, new_buffer, square


class DenseOperator(DiscreteOperator):
    """The assembled matrix of ``description`` on ``device``, assembled at its first use;
    ``kept``: the store it takes unmoved bodies' blocks from and leaves its matrix in.
    ``reused_bodies``: per body, whether its blocks came from the store (set when it assembles)."""

    mode = "dense"

    def __init__(self, description: BoundaryOperator, device, point_sources=None, kept: KeptBlocks | None = None):
        super().__init__(description, device, point_sources)
        self._store = kept
        self._signature = description.signature(self.device)
        self._lease = None  # of the store's matrix while this operator's is held there
        self._buffer = None  # its own matrix, when not in a store

    def _held_buffer(self):
        if self._store is not None and self._store.holds(self._lease):
            return self._store.buffer(self._lease)
        return self._buffer

    def matrix(self):
        """The matrix (a Warp 2-D array on the device), self blocks included: held by the store,
        or this operator's own. An operator whose matrix another took from the store assembles
        it again, on its own and afresh, if it is asked again."""
        buffer = self._held_buffer()
        if buffer is not None:
            return square(buffer, self.size)
        in_store = self._store is not None and self._lease is None  # not held and taken before
        kept = (self._store.reusable_bodies(self._signature, self.geometry) if in_store
                else np.zeros(len(self.geometry.body_ranges), dtype=bool))
        self.reused_bodies = kept
        if kept.any():
            buffer, matrix = self._store.take(self._signature, self.geometry, kept, self.kernels, self.device)
        else:
            buffer = new_buffer(self.size, self.kernels, self.device)
            matrix = square(buffer, self.size)
        moved = np.flatnonzero(~kept)
        kept_rows, moved_rows = self.geometry.points_of(np.flatnonzero(kept)), self.geometry.points_of(moved)
        # rows: collocation points; columns: elements, each filling the columns of its points
        every_element = np.arange(self.geometry.n_elements)
        for rows, cols in ((moved_rows, every_element), (kept_rows, self.geometry.elements_of(moved))):
            if len(rows) and len(cols):
                integrals.assemble_entries(self.kernels, self.device, self.surface, rows, cols, matrix)
        if self.device.is_cpu:
            self._host_self_blocks(matrix.numpy(), moved)
        else:  # on the device: the matrix never goes through the host
            self._device_self_blocks(matrix, moved)
        if in_store:
            self._lease = self._store.hold(self._signature, self.geometry, buffer)
        else:
            self._buffer = buffer
        return matrix

    def _host_self_blocks(self, host: np.ndarray, moved) -> None:
        """The moved bodies' self blocks written into the host matrix (a view of it on the CPU):
        from the identity by a BLAS product, or the single layers' Duffy blocks."""
        if self.kind not in IDENTITY_KINDS:
            a = self.geometry.points_of(moved)[:, None, None]
            k = np.arange(3)
            host[3 * a + k[None, :, None], 3 * a + k[None, None, :]] = self.self_blocks().numpy()[a[:, 0, 0]]
            return
        for p in moved:  # kept bodies brought theirs along
            start, stop = self.geometry.body_ranges[p]
            n = stop - start
            block = host[3 * start : 3 * stop, 3 * start : 3 * stop]  # a view: only its diagonal is written
            # row 3a + j, component i: sum over the body's elements b of (I_ab)_ji, the zero self block
            # included; as a product with stacked identities, so BLAS does it (a strided reduction
            # took as long as the whole threaded assembly of a refined sphere)
            with blas_on_all_cores(len(block)):
                row_sums = (block @ np.tile(np.eye(3, dtype=block.dtype), (n, 1))).reshape(n, 3, 3)
            a, k = np.arange(n)[:, None, None], np.arange(3)
            block[3 * a + k[None, :, None], 3 * a + k[None, None, :]] = -row_sums

    def _device_self_blocks(self, matrix, moved) -> None:
        """The same with Warp kernels on the matrix where it is (identity_self_blocks,
        write_self_blocks), for CUDA; on the CPU the BLAS product above is faster."""
        points = self.geometry.points_of(moved)
        if not len(points):
            return
        if self.kind in IDENTITY_KINDS:
            integrals.identity_self_blocks(self.kernels, self.device, self.surface, points, matrix)
        else:
            integrals.write_self_blocks(self.kernels, self.device, points, self.self_blocks(), matrix)

    def apply(self, density: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        self._refuse_pole_forces(pole_forces)
        density = np.asarray(density, dtype=self.np_dtype)
        matrix = self.matrix()
        if self.device.is_cpu:
            with blas_on_all_cores(self.size):  # memory-bound: two cores read faster than one
                return np.asarray(matrix.numpy() @ density, dtype=np.float64)
        return self.device_matvec(density).numpy().astype(np.float64)

    def device_matvec(self, density):
        """The matrix times ``density`` by the Warp kernel ``dense_matvec`` where the matrix
        lives (one thread block per row): the product on CUDA; on the CPU it checks the kernel
        against BLAS (tests). A device array."""
        self.matrix()
        entries = self._held_buffer()[: self.size**2]  # the matrix, flat (row-major, no gaps)
        return integrals.dense_matvec(self.kernels, self.device, entries, self.size,
                                      np.asarray(density, dtype=self.np_dtype))

    def to_dense(self) -> np.ndarray:
        return np.array(self.matrix().numpy(), dtype=np.float64)

    def diagonal_blocks(self, bodies) -> dict:
        """{p: body p's own block}, cut from the matrix (one copy off a GPU)."""
        bodies = list(bodies)
        if not bodies:
            return {}
        host = self.matrix().numpy()
        ranges = self.geometry.body_ranges
        return {p: np.array(host[3 * ranges[p][0] : 3 * ranges[p][1], 3 * ranges[p][0] : 3 * ranges[p][1]],
                            dtype=np.float64) for p in bodies}


def assembled_alone(form: DiscreteOperator, body: int) -> np.ndarray:
    """Body ``body``'s own block of ``form`` (``DiscreteOperator.diagonal_blocks``), the dense
    matrix of the operator on its elements alone: the matrix-free forms' preconditioner blocks
    (one body's block fits where the whole matrix does not)."""
    return DenseOperator(form.body_alone(body), form.device).to_dense()
