"""Lone and pair mobility snapshots kept on disk across runs (``hydrodynamics.py``): a second seed
of a scene, another scene of the same cells, or a resumed run reads the snapshots an earlier run
solved instead of solving them again (a 64-cell rolling patch solves 324 of them, most of its run).

The store is a diskcache ``Cache`` (one SQLite database and a folder of files): pure Python,
capped in size with least-recently-used eviction, and safe when several processes (two runs, a
sweep's workers) read and write it at once. A file format of our own would need all three.

Where: the folder ``WARPBEM_SNAPSHOT_STORE`` names, else ``snapshots/`` in the kernel cache's
folder (``runtime.cache_dir()``: ``.warp_cache/`` in a source checkout, ``~/.cache/warpbem``
otherwise, or ``WARPBEM_CACHE``); Warp's kernels stay where they are. Deleting the folder clears it.

The key of an entry is a sha256 over everything a snapshot's numbers depend on, over-inclusive
(a false miss costs a solve, a false hit is a wrong answer):

* FORMAT (the layout of an entry), warpbem's version and a digest of the source a snapshot's
  numbers come from (SOLVING_SOURCES: the kernels, the solver's layers ``hydro/`` and
  ``surfaces/``, ``dynamics/hydrodynamics.py`` that builds a snapshot from its solves,
  ``dynamics/far_field.py`` that compresses the far field's tractions, also kept here, and the
  options and runtime they read): the version stays the same from one commit to the next while the
  numerics change, so in a checkout an edit of their code starts the store afresh; an edit of
  their comments and docstrings (the digest is over the syntax tree without them), or of any
  other module (the pairs' assembly, the app), keeps it;
* the snapshot's key in the run (its kind, the mesh's index in the model, the lattice heights,
  spacing and offset): which snapshot of the model it is;
* the bodies it is solved at: each mesh's node coordinates and connectivity (the index names a
  mesh only within one model, and a deformed cell's surface changes), its subdivisions and
  whether it has a recipe (an accuracy target rebuilds library meshes at other subdivisions),
  position, orientation, fixed flag and prescribed motion;
* the bodies' outer radii: the basis's torques are 1 N times them;
* every field of the model's ``SolverOptions`` with the context defaults resolved (the store's own
  two fields left out: they change no number), and of the ``Flow``;
* PROBE_FORCE (the scale of the basis's solves) and the float dtype;
* the solver's form as it reports it: the operator (dense, matrix-free, treecode) and the near-far
  split, which solves the loads one by one instead of batched (the last bits differ);
* the device (CPU and CUDA results differ in the last bits; the CUDA device's name and
  architecture), the BLAS library and the kernels it picked for this CPU, and the versions of
  Warp, NumPy and SciPy.

Not in it: the run's history. A pair's flow solve starts GMRES from the previous solve's solution
and its preconditioner may take the factors of an equal block of another position
(``hydro/block_factors.py``), so the same pair snapshot solved after others differs from a fresh
one by about 1e-11 of the flow's motion (within the GMRES tolerance). A run that reads a snapshot
gets the numbers of the run that solved it: a scene whose hydrodynamics all come from lone and pair
snapshots gives the same frames bit for bit when run again; one whose other solves start GMRES from
a snapshot's solution (the whole system's snapshots) repeats them to round-off.

An entry is a header (MAGIC, FORMAT, the key's digest, the payload's sha256 and length) and a
payload: the snapshot's arrays as NumPy's .npz, read without pickle. An entry that is truncated,
foreign (another magic or another key's digest), of another format, or whose checksum fails is
deleted and the snapshot solved again, never used: ``rejected`` counts them, warned once per
store. A value that another program pickled under a key is never unpickled (``_BytesOnly``).
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import hashlib
import io
import json
import os
import platform
import sqlite3
import struct
import warnings
import zipfile
from pathlib import Path

import diskcache
import numpy as np

from .. import runtime
from ..hydro.options import DEFAULT_SNAPSHOT_STORE_SIZE

FORMAT = 1  # raise it when the header or the payload's layout changes: older entries are then refused
MAGIC = b"warpbem snapshot\0"
HEADER = struct.Struct(">I32s32sQ")  # FORMAT, the key's sha256, the payload's sha256, its length in bytes
# the options that say where and how large the store is: they change no number, so not in the key
STORE_FIELDS = ("snapshot_store", "snapshot_store_size")
ENVIRONMENT = "WARPBEM_SNAPSHOT_STORE"
# the sources a snapshot's numbers come from (module docstring): folders and files of the package,
# "kernels" the kernels' package
SOLVING_SOURCES = ("kernels", "hydro", "surfaces", "dynamics/hydrodynamics.py", "dynamics/far_field.py", "options.py",
                   "runtime.py", "units.py")
NOT_BYTES = b"not bytes"  # what an entry that is not bytes reads as (_BytesOnly): no MAGIC, so foreign


class SnapshotStoreWarning(UserWarning):
    """An entry of the snapshot store was unusable (truncated, foreign, of another format, or
    corrupted): deleted and solved again."""


class SnapshotStoreError(OSError):
    """The snapshot store's folder cannot be opened or written."""


def store_folder() -> Path:
    """The store's folder: ``WARPBEM_SNAPSHOT_STORE`` if set, else ``snapshots`` beside the kernels."""
    return Path(os.environ[ENVIRONMENT]) if os.environ.get(ENVIRONMENT) else runtime.cache_dir() / "snapshots"


class _BytesOnly(diskcache.Disk):
    """diskcache's Disk that returns stored bytes and nothing else: an entry another program wrote
    as a pickle (diskcache's default for objects other than bytes, strings and numbers) or a number
    reads as NOT_BYTES, refused as foreign, where unpickling it could run its code."""

    def fetch(self, mode, filename, value, read):
        if mode not in (diskcache.core.MODE_RAW, diskcache.core.MODE_BINARY):
            return NOT_BYTES
        value = super().fetch(mode, filename, value, read)
        return value if isinstance(value, bytes) else NOT_BYTES


def snapshot_digest(key: tuple, bodies, radii, options, flow, probe_force: float, solver_form: str, device) -> str:
    """The store's key (hex sha256) of the snapshot ``key`` of a model, solved at ``bodies`` with
    outer ``radii``, the model's ``options`` (``SolverOptions``, resolved) and ``flow``, basis
    loads of ``probe_force``, by a solver of ``solver_form`` on ``device`` (module docstring)."""
    context = dict(format=FORMAT, software=_software(), device=_device_identity(device), key=repr(key),
                   radii=[float(r) for r in radii], flow=dataclasses.asdict(flow), probe_force=float(probe_force),
                   options={name: value for name, value in dataclasses.asdict(options).items()
                            if name not in STORE_FIELDS},
                   dtype=options.dtype, solver=solver_form)
    digest = hashlib.sha256(json.dumps(context, sort_keys=True, default=repr).encode())
    for body in bodies:
        mesh = body.mesh
        digest.update(json.dumps([mesh.subdivisions, mesh.recipe is not None, bool(body.fixed),
                                  body.surface_velocity is None]).encode())
        for array in (mesh.nodes, mesh.elements, body.position, body.orientation, body.velocity,
                      body.angular_velocity, body.surface_velocity):
            if array is not None:
                array = np.ascontiguousarray(array)
                digest.update(f"{array.dtype.str}{array.shape}".encode())
                digest.update(array.tobytes())
    return digest.hexdigest()


class SnapshotStore:
    """Snapshots (tuples of frozen dataclasses of ``kinds``, in order, whose fields are arrays,
    ints and floats) kept in the folder ``folder`` (default ``store_folder()``), at most
    ``size_limit`` bytes. Opened at the first look-up. ``hits``, ``misses`` and ``writes`` count
    this store's look-ups and writes; ``rejected`` the entries found unusable (counted among the
    misses too)."""

    def __init__(self, kinds: tuple, folder: Path | None = None, size_limit: float = DEFAULT_SNAPSHOT_STORE_SIZE):
        self.kinds = tuple(kinds)
        self.folder = Path(folder) if folder is not None else store_folder()
        self.size_limit = int(size_limit)
        self.hits = self.misses = self.writes = self.rejected = 0
        self._cache = None

    def get(self, digest: str):
        """The snapshot kept under ``digest``, or None (absent, or rejected and deleted)."""
        blob = self._opened().get(digest, retry=True)
        if blob is None:
            self.misses += 1
            return None
        why, payload = self._checked(digest, blob)
        if why is None:
            try:
                snapshot = self._decoded(payload)
            except (ValueError, KeyError, TypeError, OSError, zipfile.BadZipFile) as error:
                why = f"unreadable ({type(error).__name__}: {error})"
        if why is not None:
            self._reject(digest, why)
            self.misses += 1
            return None
        self.hits += 1
        return snapshot

    def put(self, digest: str, snapshot) -> None:
        """Keep ``snapshot`` under ``digest``, evicting the least recently used entries beyond the cap."""
        buffer = io.BytesIO()
        np.savez(buffer, **{f"{p}.{f.name}": np.asarray(getattr(part, f.name)) for p, part in enumerate(snapshot)
                            for f in dataclasses.fields(part)})
        payload = buffer.getvalue()
        header = HEADER.pack(FORMAT, bytes.fromhex(digest), hashlib.sha256(payload).digest(), len(payload))
        # beyond the cap, set() evicts up to 10 least recently used entries (diskcache's cull_limit)
        self._opened().set(digest, MAGIC + header + payload, retry=True)
        self.writes += 1

    def volume(self) -> int:
        """Bytes the store takes on disk (its database and files)."""
        return self._opened().volume()

    def _opened(self) -> diskcache.Cache:
        if self._cache is None:
            try:
                self._cache = diskcache.Cache(str(self.folder), size_limit=self.size_limit, disk=_BytesOnly,
                                              eviction_policy="least-recently-used")
            except (OSError, sqlite3.Error, diskcache.Timeout) as error:
                raise SnapshotStoreError(
                    f"the snapshot store {self.folder} cannot be opened ({type(error).__name__}: {error}); set"
                    f" {ENVIRONMENT} to a writable folder, or [solver] snapshot_store = \"off\"") from error
        return self._cache

    @staticmethod
    def _checked(digest: str, blob: bytes) -> tuple[str | None, bytes]:
        """(why the entry ``blob`` under ``digest`` is unusable or None, its payload)."""
        start = len(MAGIC) + HEADER.size
        if blob[:len(MAGIC)] != MAGIC[:len(blob)]:
            return "foreign (not a warpbem snapshot)", b""
        if len(blob) < start:
            return "truncated (in its header)", b""
        version, key, checksum, length = HEADER.unpack_from(blob, len(MAGIC))
        payload = blob[start:]
        if version != FORMAT:
            return f"of store format {version}, not {FORMAT}", b""
        if key != bytes.fromhex(digest):
            return "foreign (another snapshot's entry)", b""
        if len(payload) != length:
            return f"truncated ({len(payload)} of {length} bytes)", b""
        if hashlib.sha256(payload).digest() != checksum:
            return "corrupted (its checksum fails)", b""
        return None, payload

    def _decoded(self, payload: bytes) -> tuple:
        with np.load(io.BytesIO(payload), allow_pickle=False) as arrays:
            if len(arrays.files) != sum(len(dataclasses.fields(kind)) for kind in self.kinds):
                raise ValueError(f"{len(arrays.files)} arrays, not those of {[k.__name__ for k in self.kinds]}")
            return tuple(kind(**{f.name: _value(arrays[f"{p}.{f.name}"]) for f in dataclasses.fields(kind)})
                         for p, kind in enumerate(self.kinds))

    def _reject(self, digest: str, why: str) -> None:
        self._opened().delete(digest, retry=True)
        self.rejected += 1
        if self.rejected == 1:
            warnings.warn(f"snapshot store {self.folder}: an entry was {why}; deleted, and its snapshot solved again"
                          " (further ones this run are counted, not warned)", SnapshotStoreWarning, stacklevel=2)


def _value(array: np.ndarray):
    """An array as the dataclass held it: a number for a 0-d array (iterations, residual)."""
    return array.item() if array.ndim == 0 else array


@functools.cache
def _software() -> dict:
    """The versions and the package source's digest (module docstring), once per process."""
    import scipy
    import threadpoolctl
    import warp

    import warpbem
    import warpbem.kernels

    source = hashlib.sha256()
    package, kernels = Path(warpbem.__file__).parent, Path(warpbem.kernels.__file__).parent
    for root, path in _solving_sources(package, kernels):
        source.update(str(path.relative_to(root)).encode() + b"\0" + _code(path))
    blas = sorted((i["internal_api"], i["version"], str(i.get("architecture"))) for i in threadpoolctl.threadpool_info()
                  if i["user_api"] == "blas")
    return dict(warpbem=warpbem.__version__, source=source.hexdigest(), warp=warp.config.version,
                numpy=np.__version__, scipy=scipy.__version__, blas=blas, machine=platform.machine())


def _solving_sources(package: Path, kernels: Path):
    """(root, path) of the source files a snapshot's numbers come from (SOLVING_SOURCES), sorted."""
    for name in SOLVING_SOURCES:
        root = kernels if name == "kernels" else package
        where = kernels if name == "kernels" else package / name
        files = where.rglob("*") if where.is_dir() else [where]
        for path in sorted(p for p in files if p.suffix in (".py", ".json") and "__pycache__" not in p.parts):
            yield root, path


def _code(path: Path) -> bytes:
    """The code of a source file without its comments and docstrings (the syntax tree of a .py
    file with every docstring removed; a .json file's bytes): an edit of the prose keeps the store."""
    if path.suffix != ".py":
        return path.read_bytes()
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if (isinstance(body, list) and body and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str)):
            node.body = body[1:] or [ast.Pass()]
    return ast.dump(tree).encode()


def _device_identity(device) -> str:
    resolved = runtime.resolve_device(device)
    return f"cuda {resolved.name} sm_{resolved.arch}" if resolved.is_cuda else "cpu"
