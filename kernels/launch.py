"""Launching kernels: the rows of a kernel split over a small CPU thread pool.

A Warp launch on the CPU runs on one core but releases the GIL, so ``launch_rows`` splits the
rows of a kernel into blocks launched from a small thread pool; on CUDA it launches once. Rows
cost unequal amounts (near contact the refined elements, whose rows need the adaptive
quadrature most, are appended at the end of their body), so there are CHUNKS_PER_THREAD blocks
per thread, taken by the threads as they come free, rather than one block per thread. Every
launch of the package goes through the launchers of ``kernels/`` (this module's functions and
the thin ones beside each kernel family), so ``warpbem/`` holds no launch code.

BLAS threads: NumPy's and SciPy's OpenBLAS keep their worker threads spinning for a while after
each call, and beside a thread pool that already uses every core they slow the launches that
follow. So the first threaded CPU launch limits BLAS to one thread for the rest of the process
(threadpoolctl), and only the calls large enough to repay their threads' spin run on every core
(``blas_on_all_cores``: the LU factors of large body blocks, the dense operator's apply and
its self blocks' row sums).
``benchmarks/blas_threads.py`` (docs/benchmarks.md): a mobility solve of four spheres near the
wall 1.08 against 1.23 s, its spread (90th over 10th percentile) 1.03 against 1.13.
"""

from __future__ import annotations

import contextlib
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

_POOL: ThreadPoolExecutor | None = None
CHUNKS_PER_THREAD = 8
MIN_CHUNK_ROWS = 16  # fewer rows per launch would cost more in launch overhead than they balance
# A BLAS call on a matrix of at least this many rows gets every core: an LU factorization runs 1.6
# times faster on 2 cores than on one (2 000 rows: 0.078 against 0.124 s); below 1 000 rows 1.2-1.3
# times, which the spin that follows takes back.
BLAS_ALL_CORES_ROWS = 2000
_BLAS = None  # threadpoolctl's controller, once the first threaded CPU launch has limited BLAS


def cpu_threads() -> int:
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1, 8))


def quiet_blas() -> None:
    """Limit BLAS to one thread for the rest of the process (module docstring), once."""
    global _BLAS
    if _BLAS is None:
        from threadpoolctl import ThreadpoolController

        _BLAS = ThreadpoolController()
        _BLAS.limit(limits=1, user_api="blas")  # not used as a context: it stays for the process


def blas_on_all_cores(rows: int):
    """A context in which BLAS uses every core, for a factorization of ``rows`` rows large
    enough to repay it; otherwise (or before BLAS was limited) a context that changes nothing."""
    if _BLAS is None or rows < BLAS_ALL_CORES_ROWS:
        return contextlib.nullcontext()
    return _BLAS.limit(limits=cpu_threads(), user_api="blas")


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
    if device.is_cpu and threads > 1:
        quiet_blas()
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
