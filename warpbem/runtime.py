"""Warp start-up and devices.

``init()`` points Warp's kernel cache at an ignored project folder (``.warp_cache`` beside
``pyproject.toml`` in a source checkout, else ``~/.cache/warpbem``; ``WARPBEM_CACHE`` overrides)
before ``wp.init()``, so tests and CI reuse compiled kernels. Nothing here runs at import.

Warp's native start-up probes the CUDA driver and, on a machine without one, prints "Warp CUDA
warning: Could not find or load the NVIDIA CUDA driver" on the process's stderr: noise to a run on
the CPU. ``init()`` keeps the lines Warp prints about CUDA back and hands them to whoever asks for a
CUDA device (``resolve_device``: the ``DeviceError`` when it is missing, stderr when it is there);
any other line Warp prints at start-up goes to stderr as before.

Launching kernels (and splitting CPU launches over threads) is ``kernels/launch.py``'s job.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys
import tempfile
import time
from pathlib import Path


class DeviceError(ValueError):
    """A device that this machine does not have; the message lists those it has."""


_INITIALISED = False
_CUDA_NOTES: list[str] = []  # what Warp printed about CUDA at start-up, held back (module docstring)
# glibc keeps the pages of freed NumPy arrays in its heap for the next allocation, so a long run's
# resident memory climbs to the largest mix of arrays any step needed: a deformable free cell
# passing an adherent one (k = 4, scenes/fig5_14_18_deformable_free.toml) held 1.04-1.08 GB from
# step 60 to 200, against 0.74-0.75 GB with malloc_trim after each step. A trim took 1.6 ms beside
# that run's 354 ms step but would add a third to a 5 ms rolling step, so it runs at most once per
# TRIM_INTERVAL of wall time (docs/dynamics.md, "Memory of long runs").
TRIM_INTERVAL = 1.0  # s
_last_trim = 0.0
_malloc_trim = None  # glibc's malloc_trim, looked up at the first call (None elsewhere: nothing to do)


def cache_dir() -> Path:
    if os.environ.get("WARPBEM_CACHE"):
        return Path(os.environ["WARPBEM_CACHE"])
    root = Path(__file__).resolve().parent.parent
    if (root / "pyproject.toml").exists():
        return root / ".warp_cache"
    return Path.home() / ".cache" / "warpbem"


def release_freed_memory() -> None:
    """Hand the C heap's free pages back to the system (glibc's malloc_trim), at most once per
    TRIM_INTERVAL seconds; elsewhere (no glibc) nothing (comment above)."""
    global _last_trim, _malloc_trim
    now = time.monotonic()
    if now - _last_trim < TRIM_INTERVAL:
        return
    _last_trim = now
    if _malloc_trim is None:
        library = ctypes.util.find_library("c")
        _malloc_trim = getattr(ctypes.CDLL(library), "malloc_trim", False) if library else False
    if _malloc_trim:
        _malloc_trim(0)


def init():
    """Import and initialise Warp once; returns the ``warp`` module."""
    global _INITIALISED
    import logging

    import warp as wp

    if not _INITIALISED:
        wp.config.kernel_cache_dir = str(cache_dir())
        wp.config.log_level = logging.WARNING  # no start-up banner or per-module load lines
        wp.config.enable_backward = False  # no adjoint code: half the compile time
        printed = _native_stderr_of(wp.init)
        _CUDA_NOTES.extend(line for line in printed if line.startswith("Warp CUDA"))
        for line in printed:
            if not line.startswith("Warp CUDA"):
                print(line, file=sys.stderr)
        _INITIALISED = True
    return wp


def _native_stderr_of(call) -> list[str]:
    """The lines ``call()`` writes on file descriptor 2 (native code's stderr, which Python's
    ``sys.stderr`` does not see), kept from the terminal."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all (a detached process): nothing to keep back
        call()
        return []
    with tempfile.TemporaryFile(mode="w+b") as capture:
        os.dup2(capture.fileno(), 2)
        try:
            call()
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
        capture.seek(0)
        return capture.read().decode(errors="replace").splitlines()


def dtype_of(name: str):
    wp = init()
    types = {"float64": wp.float64, "float32": wp.float32}
    if name not in types:
        raise ValueError(f"dtype must be 'float64' or 'float32', got {name!r}")
    return types[name]


def resolve_device(device):
    """The Warp device named ``device`` ("cpu", "cuda", "cuda:0", or a Warp device); DeviceError
    naming the devices there are otherwise. Asking for CUDA shows what Warp said about it at
    start-up (module docstring)."""
    wp = init()
    try:
        resolved = wp.get_device(device)
    except (RuntimeError, ValueError, TypeError):
        names = ", ".join(d.alias for d in wp.get_devices())
        # what Warp said, to its first full stop: "Could not find or load the NVIDIA CUDA driver"
        notes = [note.split(": ", 1)[-1].split(". ")[0].rstrip(".") for note in _CUDA_NOTES]
        why = f" (Warp: {'; '.join(notes)})" if notes and str(device).startswith("cuda") else ""
        raise DeviceError(f"device {device!r} is not available; this machine has: {names}{why}") from None
    if resolved.is_cuda and _CUDA_NOTES:  # CUDA asked for and there: what Warp said about it, once
        print("\n".join(_CUDA_NOTES), file=sys.stderr)
        _CUDA_NOTES.clear()
    return resolved


def total_memory(device) -> int:
    """Bytes of memory of ``device``: the host's physical memory, the GPU's on CUDA. A run's
    operator mode is decided from this, not from what happens to be free at the moment (the run's
    own kept systems would otherwise flip it part-way)."""
    if not device.is_cpu:
        return int(device.total_memory)
    return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
