"""HDF5 output that describes itself: units on every dataset, the scene, package versions,
device and seed as attributes; rows appended and flushed one by one, so an interrupted run
keeps everything written so far."""

from __future__ import annotations

import json
import platform
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np


def versions() -> dict:
    import scipy
    import warp

    from . import __version__

    return {"warpbem": __version__, "warp": warp.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "h5py": h5py.__version__, "python": platform.python_version()}


class TableWriter:
    """Append-only table of named columns, each with a unit and a fixed row shape.

    ``columns``: {name: (unit, row_shape)}. Each ``append`` writes one row to every column and
    flushes the file.
    """

    def __init__(self, path, columns: dict, scene: dict, device: str, seed=None, title: str = "",
                 resume: bool = False):
        self.path = Path(path)
        self.columns = columns
        if resume:  # append to the frames already there
            self.file = h5py.File(self.path, "a")
            missing = [name for name in columns if name not in self.file]
            if missing:
                raise ValueError(f"{self.path}: cannot resume, the file has no dataset {missing[0]!r}")
            self.rows = min(self.file[name].shape[0] for name in columns)
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.file = h5py.File(self.path, "w")
        attrs = self.file.attrs
        attrs["title"] = title
        attrs["scene"] = json.dumps(scene, sort_keys=True)
        attrs["versions"] = json.dumps(versions(), sort_keys=True)
        attrs["device"] = device
        attrs["seed"] = "none (deterministic)" if seed is None else int(seed)
        attrs["created"] = datetime.now(timezone.utc).isoformat()
        attrs["units"] = "SI"
        for name, (unit, shape) in columns.items():
            ds = self.file.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype="f8",
                                          chunks=(1, *shape) if shape else (64,))
            ds.attrs["unit"] = unit
        self.rows = 0

    def append(self, **values):
        for name in self.columns:
            ds = self.file[name]
            ds.resize(self.rows + 1, axis=0)
            ds[self.rows] = np.asarray(values[name], dtype=float)
        self.rows += 1
        self.file.flush()

    def close(self):
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
