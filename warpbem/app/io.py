"""HDF5 output that describes itself: units (and what each column holds) on every dataset, the
scene, package versions, device and seed as attributes; rows appended and flushed one by one,
so an interrupted run keeps everything written so far. A row is complete once every column
has it: a process killed between two column writes leaves a partial row, which readers ignore
and a resumed writer overwrites."""

from __future__ import annotations

import json
import platform
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

from ..dynamics.frame import Column
from ..surfaces.mesh import Mesh

MESHES = "meshes"  # the group of a run file holding its bodies' meshes (write_meshes)


class RunFileError(ValueError):
    """A file given to warpbem that is missing, unreadable or not what the command needs; the
    message names the file and the problem."""


def open_result(path, mode: str = "r", needs=()) -> h5py.File:
    """Open a warpbem HDF5 file, or raise RunFileError naming it. ``needs``: datasets and
    attributes it must have. Read-only opens take no lock, so a run still being written (whose
    writer holds HDF5's lock) can be read."""
    path = Path(path)
    if not path.is_file():
        raise RunFileError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    try:
        f = h5py.File(path, mode, locking=False) if mode == "r" else h5py.File(path, mode)
    except OSError as err:
        raise RunFileError(f"{path}: not a readable HDF5 file ({err})") from err
    missing = [k for k in needs if k not in f and k not in f.attrs]
    if missing:
        f.close()
        raise RunFileError(f"{path}: not a warpbem run file (no {missing[0]!r}); expected a file written by"
                           " warpbem run or warpbem sweep")
    return f


def complete_rows(f: h5py.File, names=None) -> int:
    """Rows present in every column (``names``, default every dataset of the file's root)."""
    names = [k for k, v in f.items() if isinstance(v, h5py.Dataset)] if names is None else names
    return min((f[k].shape[0] for k in names), default=0)


def versions() -> dict:
    import scipy
    import warp

    from .. import __version__

    return {"warpbem": __version__, "warp": warp.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "h5py": h5py.__version__, "python": platform.python_version()}


class TableWriter:
    """Append-only table of named columns, each with a unit and a fixed row shape.

    ``columns``: {name: Column(unit, row_shape, description)}. Each ``append`` writes one row
    to every column and flushes the file. ``resume``: reopen the file, drop any partial row and
    append after the complete ones.
    """

    def __init__(self, path, columns: dict, scene: dict, device: str, seed=None, title: str = "",
                 resume: bool = False):
        self.path = Path(path)
        self.columns = {name: Column(*spec) for name, spec in columns.items()}
        if resume:  # append to the frames already there
            self.file = open_result(self.path, "a")
            missing = [name for name in columns if name not in self.file]
            if missing:
                self.file.close()
                raise RunFileError(f"{self.path}: cannot resume, the file has no column {missing[0]!r}")
            self.rows = complete_rows(self.file, columns)
            for name in columns:  # a partial row of a process killed mid-append
                self.file[name].resize(self.rows, axis=0)
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
        for name, column in self.columns.items():
            shape = tuple(column.shape)
            ds = self.file.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype="f8",
                                          chunks=(1, *shape) if shape else (64,))
            ds.attrs["unit"] = column.unit
            if column.description:
                ds.attrs["description"] = column.description
        self.rows = 0

    def append(self, **values):
        for name in self.columns:
            ds = self.file[name]
            ds.resize(self.rows + 1, axis=0)
            ds[self.rows] = np.asarray(values[name], dtype=float)
            # flushed column by column: a process killed in between leaves whole columns on disk,
            # one row longer than others, never a half-written file
            self.file.flush()
        self.rows += 1

    def close(self):
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def write_meshes(f: h5py.File, meshes) -> None:
    """The bodies' meshes in the group MESHES of an open run file: each distinct mesh once
    (``nodes`` m in its body frame, ``elements``; an array of alike cells shares one), and per body
    the index of its mesh (``body_mesh``), so that the file alone draws its bodies (plot,
    animate, xdmf), whether its scene came from a file or a script."""
    group = f.create_group(MESHES)
    distinct, index = {}, []
    for mesh in meshes:
        if id(mesh) not in distinct:
            distinct[id(mesh)] = len(distinct)
            sub = group.create_group(str(distinct[id(mesh)]))
            sub.create_dataset("nodes", data=mesh.nodes).attrs["unit"] = "m"
            sub.create_dataset("elements", data=mesh.elements)
        index.append(distinct[id(mesh)])
    group.create_dataset("body_mesh", data=np.array(index, dtype=np.int64))


def read_meshes(f: h5py.File) -> list[Mesh] | None:
    """The bodies' meshes of an open run file (write_meshes), or None in a file without them."""
    if MESHES not in f:
        return None
    group = f[MESHES]
    index = group["body_mesh"][:]
    distinct = {j: Mesh(group[str(j)]["nodes"][:], group[str(j)]["elements"][:]) for j in set(index.tolist())}
    return [distinct[j] for j in index.tolist()]
