"""Warp start-up and devices.

``init()`` points Warp's kernel cache at an ignored project folder (``.warp_cache`` beside
``pyproject.toml`` in a source checkout, else ``~/.cache/warpbem``; ``WARPBEM_CACHE`` overrides)
before ``wp.init()``, so tests and CI reuse compiled kernels. Nothing here runs at import.

Launching kernels (and splitting CPU launches over threads) is ``kernels/launch.py``'s job.
"""

from __future__ import annotations

import os
from pathlib import Path


_INITIALISED = False


def cache_dir() -> Path:
    if os.environ.get("WARPBEM_CACHE"):
        return Path(os.environ["WARPBEM_CACHE"])
    root = Path(__file__).resolve().parent.parent
    if (root / "pyproject.toml").exists():
        return root / ".warp_cache"
    return Path.home() / ".cache" / "warpbem"


def init():
    """Import and initialise Warp once; returns the ``warp`` module."""
    global _INITIALISED
    import logging

    import warp as wp

    if not _INITIALISED:
        wp.config.kernel_cache_dir = str(cache_dir())
        wp.config.log_level = logging.WARNING  # no start-up banner or per-module load lines
        wp.config.enable_backward = False  # no adjoint code: half the compile time
        wp.init()
        _INITIALISED = True
    return wp


def dtype_of(name: str):
    wp = init()
    types = {"float64": wp.float64, "float32": wp.float32}
    if name not in types:
        raise ValueError(f"dtype must be 'float64' or 'float32', got {name!r}")
    return types[name]


def resolve_device(device):
    wp = init()
    try:
        return wp.get_device(device)
    except (RuntimeError, ValueError) as err:
        names = [d.alias for d in wp.get_devices()]
        raise ValueError(f"device {device!r} is not available; this machine has {names}") from err


def total_memory(device) -> int:
    """Bytes of memory of ``device``: the host's physical memory, the GPU's on CUDA. A run's
    operator mode is decided from this, not from what happens to be free at the moment (the run's
    own kept systems would otherwise flip it part-way)."""
    if not device.is_cpu:
        return int(device.total_memory)
    return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
