"""Launching kernels: the rows of a kernel split over a small CPU thread pool.

A Warp launch on the CPU runs on one core but releases the GIL, so ``launch_rows`` splits the
rows of a kernel into blocks launched from a small thread pool; on CUDA it launches once. Rows
cost unequal amounts (near contact the refined elements, whose rows need the adaptive
quadrature most, are appended at the end of their body), so there are CHUNKS_PER_THREAD blocks
per thread, taken by the threads as they come free, rather than one block per thread. Every
launch of the package goes through the launchers of ``kernels/`` (this module's functions and
the thin ones beside each kernel family), so ``warpbem/`` holds no launch code.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

_POOL: ThreadPoolExecutor | None = None
CHUNKS_PER_THREAD = 8
MIN_CHUNK_ROWS = 16  # fewer rows per launch would cost more in launch overhead than they balance


def cpu_threads() -> int:
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1, 8))


def row_blocks(n_rows: int, device) -> list[tuple[int, int]]:
    """Row ranges to launch: CHUNKS_PER_THREAD per CPU thread (at least MIN_CHUNK_ROWS rows
    each, and one per thread at least), or one on a GPU."""
    threads = cpu_threads()
    n_blocks = max(min(threads * CHUNKS_PER_THREAD, n_rows // MIN_CHUNK_ROWS), threads) if device.is_cpu else 1
    edges = np.linspace(0, n_rows, min(n_blocks, max(n_rows, 1)) + 1).astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def launch_rows(kernel, n_rows: int, make_inputs, device, extra_dim: int | None = None, threaded: bool = True):
    """Launch ``kernel`` over ``n_rows`` rows split in blocks.

    ``make_inputs(start, stop)`` returns the input list of one block (its first entry is the
    row offset ``start``); blocks run concurrently on CPU threads. ``extra_dim`` makes the
    launch two-dimensional (rows x extra_dim). ``threaded=False``: one launch, for work too
    light to pay for the thread pool's hand-offs.
    """
    import warp as wp  # here, not at the top: `import warpbem` must not load Warp (tests/unit/test_package.py)

    blocks = row_blocks(n_rows, device) if threaded else [(0, n_rows)]

    def run(block):
        start, stop = block
        dim = (stop - start, extra_dim) if extra_dim is not None else stop - start
        wp.launch(kernel, dim=dim, inputs=make_inputs(start, stop), device=device)

    # compile/load before the threads start, so they never race on the module
    wp.load_module(kernel.module, device=device)
    threads = cpu_threads()
    if len(blocks) == 1 or threads == 1:
        for block in blocks:
            run(block)
    else:
        global _POOL
        if _POOL is None or _POOL._max_workers != threads:  # a pool of the size asked for
            _POOL = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="warpbem")
        list(_POOL.map(run, blocks))
    if not device.is_cpu:
        wp.synchronize_device(device)
