"""Lone and pair mobility snapshots kept on disk across runs (warpbem/dynamics/snapshot_store.py):
what a read returns, what the key holds, what a bad entry leads to, the size cap, two processes at
once, and a scene run twice."""

import dataclasses
import hashlib
import multiprocessing
import pickle
import re
from pathlib import Path

import diskcache
import h5py
import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.hydrodynamics import PROBE_FORCE, HydrodynamicSolves
from warpbem.dynamics.model import Flow, Model, SolverOptions, build_solver
from warpbem.dynamics.snapshot_store import (ENVIRONMENT, FORMAT, HEADER, MAGIC, SnapshotStore, SnapshotStoreError,
                                             SnapshotStoreWarning, snapshot_digest)
from warpbem.surfaces.body import Body
from tests.unit.test_pairwise import PAIRS_SCENE  # the two cells of the pairs' own resume test

A = 2e-6
MESH = wb.mesh.sphere(A, 2)
HEIGHT = A + 236e-9
SPACING = 2e-9
SNAPSHOT_KEY = ("lone", 0, SPACING, (0.0, 0.0, 1118.0))



def solves(**solver):
    """A fresh HydrodynamicSolves of two free cells of MESH, snapshots on the 2 nm lattice, its
    solver's operator decided when built (as a Simulator's)."""
    model = Model([MESH, MESH], [False, False], Flow(100.0, 1e-3), solver=SolverOptions(reuse_tolerance=SPACING,
                                                                                          **solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, "cpu", unknowns=model.unknowns))


def lone(hydro, height=HEIGHT):
    """The lone snapshot of the first cell at ``height`` (7 one-cell solves)."""
    return hydro._lone(0, Body(MESH, position=(0.0, 0.0, height)), SPACING)


def assert_same(a, b):
    """Two snapshots equal bit for bit, field by field (arrays and numbers alike)."""
    for part_a, part_b in zip(a, b, strict=True):
        assert type(part_a) is type(part_b)
        for field in dataclasses.fields(part_a):
            x, y = getattr(part_a, field.name), getattr(part_b, field.name)
            assert np.array_equal(x, y) and np.asarray(x).dtype == np.asarray(y).dtype, field.name


def test_a_snapshot_read_back_is_the_solved_one_bit_for_bit(snapshot_store):
    """The first lookup misses and writes; a fresh model's (another run's) reads it back equal to
    the last bit, without solving it."""
    first = solves()
    solved = lone(first)
    assert (first.snapshots_solved, first.store.misses, first.store.writes) == (1, 1, 1)
    second = solves()
    assert_same(lone(second), solved)
    assert (second.snapshots_solved, second.store.hits, second.store.misses) == (0, 1, 0)
    assert first.store.folder == snapshot_store  # the test's own store, never the developer's


def test_a_solver_whose_operator_is_still_open_looks_nothing_up_and_keys_by_the_one_it_decides():
    """The operator's form ("auto") is decided at a solver's first solve when it is built without
    the model's unknowns, and it is in the key: such a solver's first snapshot is solved, not looked
    up, and written under the form its solve decided, where a solver decided from the start finds it."""
    first = solves()
    first.mobility = build_solver(first.model.solver, first.model.flow, "cpu")  # no unknowns: "auto" still open
    solved = lone(first)
    assert (first.mobility.mode, first.store.misses, first.store.writes) == ("dense", 0, 1)
    decided = solves()
    assert_same(lone(decided), solved)
    assert decided.store.hits == 1 and decided.snapshots_solved == 0


def digest(key=SNAPSHOT_KEY, mesh=MESH, radii=(A,), options=None, flow=Flow(100.0, 1e-3), probe=PROBE_FORCE,
           form="dense", position=(0.0, 0.0, 1118 * SPACING)):
    options = options or SolverOptions(reuse_tolerance=SPACING).resolved(time_stepping=True, bonds=True)
    return snapshot_digest(key, [Body(mesh, position=position)], radii, options, flow, probe, form, "cpu")


def test_every_input_of_a_snapshot_changes_its_key_and_the_stores_own_options_do_not():
    base = SolverOptions(reuse_tolerance=SPACING)
    resolved = dict(time_stepping=True, bonds=True)
    moved = MESH.nodes.copy()
    moved[0, 0] += 1e-18  # one node by 5e-13 of the radius
    changed = {
        "key": digest(key=("lone", 0, SPACING, (0.0, 0.0, 1119.0))),
        "mesh": digest(mesh=wb.mesh.sphere(A, 3)),
        "one node": digest(mesh=wb.mesh.Mesh(moved, MESH.elements)),
        "radius": digest(radii=(1.01 * A,)),
        "quadrature": digest(options=SolverOptions(reuse_tolerance=SPACING, quadrature_order=3).resolved(**resolved)),
        "tolerance": digest(options=SolverOptions(reuse_tolerance=SPACING, tolerance=1e-9).resolved(**resolved)),
        "density order": digest(options=SolverOptions(reuse_tolerance=SPACING, density_order=2).resolved(**resolved)),
        "grand mobility": digest(options=SolverOptions(reuse_tolerance=SPACING,
                                                       grand_mobility="pairs").resolved(**resolved)),
        "treecode": digest(options=dataclasses.replace(base.resolved(**resolved), treecode=wb.TreecodeOptions(
            tolerance=1e-7))),
        "dtype": digest(options=SolverOptions(reuse_tolerance=SPACING, dtype="float32").resolved(**resolved)),
        "shear rate": digest(flow=Flow(200.0, 1e-3)),
        "viscosity": digest(flow=Flow(100.0, 1.2e-3)),
        "wall": digest(flow=Flow(100.0, 1e-3, wall=False)),
        "probe force": digest(probe=2 * PROBE_FORCE),
        "operator": digest(form="matrix_free"),
        "position": digest(position=(0.0, 0.0, 1118 * SPACING + 1e-15)),
    }
    keys = list(changed.values())
    assert digest() == digest() and digest() not in keys
    assert len(set(keys)) == len(keys), [name for name, k in changed.items() if keys.count(k) > 1]
    store_options = dataclasses.replace(base, snapshot_store="off", snapshot_store_size=1e7).resolved(**resolved)
    assert digest(options=store_options) == digest()


class Unpickled:
    """An object whose unpickling fails loudly (eval of 1/0): a store that unpickled an entry would raise."""

    def __reduce__(self):
        return eval, ("1/0",)


def tampered(how: str, blob: bytes, other: bytes, rng) -> object:
    """The entry ``blob`` spoilt ``how`` (``other``: another snapshot's entry)."""
    start = len(MAGIC) + HEADER.size
    if how == "truncated":
        return blob[:-10]
    if how == "truncated header":
        return blob[:len(MAGIC) + 8]
    if how == "another key's entry":
        return other
    if how == "random bytes":
        return rng.bytes(len(blob))
    if how == "older format":
        _, key, checksum, length = HEADER.unpack_from(blob, len(MAGIC))
        return MAGIC + HEADER.pack(FORMAT - 1, key, checksum, length) + blob[start:]
    if how == "checksum fails":
        spoilt = bytearray(blob)
        spoilt[start + len(spoilt[start:]) // 2] ^= 0x01
        return bytes(spoilt)
    assert how == "a pickle"
    return Unpickled()


@pytest.mark.parametrize("how, why", [("truncated", "truncated"), ("truncated header", "truncated"),
                                      ("another key's entry", "foreign"), ("random bytes", "foreign"),
                                      ("older format", f"of store format {FORMAT - 1}"),
                                      ("checksum fails", "corrupted"), ("a pickle", "foreign")])
def test_a_bad_entry_is_deleted_and_solved_again_never_used(snapshot_store, rng, how, why):
    """Each bad entry is refused with a warning naming why, counted, deleted and solved again: the
    snapshot returned equals a fresh solve bit for bit (both solved by a fresh model), and the
    entry written in its place is read by the next run. A pickled value is refused without being
    unpickled (its unpickling would raise)."""
    fresh = lone(solves())
    with diskcache.Cache(str(snapshot_store)) as cache:  # as another program would open it
        (key,) = cache.iterkeys()
    lone(solves(), HEIGHT + 20 * SPACING)
    with diskcache.Cache(str(snapshot_store)) as cache:
        (other,) = set(cache.iterkeys()) - {key}
        cache.set(key, tampered(how, cache[key], cache[other], rng))
    hydro = solves()
    with pytest.warns(SnapshotStoreWarning, match=f"snapshot store .*: an entry was {why}.*solved again"):
        again = lone(hydro)
    assert_same(again, fresh)
    assert (hydro.store.rejected, hydro.store.hits, hydro.snapshots_solved, hydro.store.writes) == (1, 0, 1, 1)
    reader = solves()
    assert_same(lone(reader), fresh)
    assert (reader.store.hits, reader.store.rejected, reader.snapshots_solved) == (1, 0, 0)



def test_a_store_that_cannot_be_opened_says_where_and_how_to_do_without_it(tmp_path):
    (tmp_path / "a file").write_text("not a folder")
    store = SnapshotStore((), tmp_path / "a file")
    with pytest.raises(SnapshotStoreError, match=r"the snapshot store .*a file cannot be opened .*set"
                                                 r" WARPBEM_SNAPSHOT_STORE to a writable folder, or \[solver\]"
                                                 r' snapshot_store = "off"'):
        store.get(key_of(0))


@dataclasses.dataclass(frozen=True)
class Part:
    """A stand-in snapshot part: an array and a number, as Motion and Responses hold."""

    values: np.ndarray
    count: int


def part(i: int, size: int = 2000) -> tuple:
    """Entry ``i``'s snapshot (16 kB of float64), its values a function of ``i`` alone."""
    return (Part(np.random.default_rng(i).standard_normal(size), i),)


def key_of(i: int) -> str:
    return hashlib.sha256(f"entry {i}".encode()).hexdigest()


def test_the_store_stays_under_its_cap_evicting_the_least_recently_used(tmp_path):
    """100 entries of 16 kB into a 256 kB store: after every write it is under the cap; the entry
    read after each write stays, the one written next to it and never read again is evicted, and
    the last ones written are there."""
    cap = 256e3
    store = SnapshotStore((Part,), tmp_path / "capped", size_limit=cap)
    store.put(key_of(0), part(0))
    for i in range(1, 100):
        store.put(key_of(i), part(i))
        assert store.volume() <= cap
        assert_same(store.get(key_of(0)), part(0))
    assert store.get(key_of(1)) is None
    assert_same(store.get(key_of(99)), part(99))
    assert store.writes == 100 and store.rejected == 0


def write_and_read(folder: str, start: int, count: int) -> tuple[int, int]:
    """A process's share of the two-process test: writes entries start, start + 1, ... (wrapping
    over ``count``) and reads each one the other process writes; (values read, values that
    differed from what was written)."""
    store = SnapshotStore((Part,), Path(folder))
    read = differed = 0
    for k in range(count):
        mine, theirs = (start + k) % count, (count - 1 - start - k) % count
        store.put(key_of(mine), part(mine, 200))
        found = store.get(key_of(theirs))
        if found is not None:
            read += 1
            differed += not (np.array_equal(found[0].values, part(theirs, 200)[0].values) and found[0].count == theirs)
    assert store.rejected == 0
    return read, differed


def test_two_processes_write_and_read_one_store_at_once(tmp_path):
    """Two processes (spawned, as a sweep's workers) write the same 300 keys in opposite orders
    and read each other's: no error, every value read is the one written, and all are there."""
    count = 300
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        results = pool.starmap(write_and_read, [(str(tmp_path / "shared"), 0, count),
                                                (str(tmp_path / "shared"), count // 2, count)])
    assert sum(read for read, _ in results) > 0 and sum(differed for _, differed in results) == 0
    store = SnapshotStore((Part,), tmp_path / "shared")
    for i in range(count):
        assert_same(store.get(key_of(i)), part(i, 200))


def test_whole_system_snapshots_stay_in_memory_and_the_store_can_be_off(tmp_path, monkeypatch):
    """Two cells on the whole system's snapshot: its lone snapshots go to the store, the whole
    system's does not (keyed by every cell, seldom seen again); snapshot_store = "off" keeps
    nothing on disk."""
    bodies = [Body(MESH, position=(0.0, 0.0, HEIGHT)), Body(MESH, position=(12e-6, 0.0, HEIGHT + 40e-9))]
    hydro = solves()
    hydro._snapshot(bodies)
    assert hydro.snapshots_solved == hydro.store.writes + 1 and hydro.store.writes > 0
    monkeypatch.setenv(ENVIRONMENT, str(tmp_path / "unused"))
    off = solves(snapshot_store="off")
    off._snapshot(bodies)
    assert off.store is None and off.snapshots_solved == hydro.snapshots_solved
    assert not (tmp_path / "unused").exists()


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_a_scene_run_twice_reads_every_snapshot_and_repeats_its_frames_bit_for_bit(tmp_path):
    """Two adhesive cells on pair snapshots (grand_mobility = "pairs"), 3 ms: the second run solves
    no snapshot, reads them all from the store (its progress line says so), and writes the first
    run's frames to the last bit (every number it steps with comes from the snapshots)."""
    from warpbem.app import run

    path = tmp_path / "pairs.toml"
    path.write_text(PAIRS_SCENE)
    lines = {}
    for name in ("first", "second"):
        lines[name] = []
        run.run(path, tmp_path / f"{name}.h5", progress=lines[name].append)
    solved, read = (re.search(r"snapshots (\d+) \(store (\d+) read\)", lines[name][-2]).groups() for name in lines)
    assert int(solved[0]) > 0 and solved[1] == "0" and int(read[1]) >= int(solved[0])
    with h5py.File(tmp_path / "first.h5") as f, h5py.File(tmp_path / "second.h5") as g:
        names = [name for name in f if isinstance(f[name], h5py.Dataset)]
        assert {"position", "velocity", "bond_receptor", "bond_count"} <= set(names)
        assert f["bond_count"][-1].sum() > 0  # the runs reach the bonds they compare
        for name in names:
            assert np.array_equal(f[name][:], g[name][:]), name


def test_the_source_digest_follows_the_code_not_its_prose(tmp_path):
    """The key holds a digest of the solving sources' code (snapshot_store._code): a changed
    docstring or comment keeps every entry, a changed number in the code starts afresh."""
    from warpbem.dynamics.snapshot_store import _code

    texts = {"plain": 'def f(x):\n    return 2.0 * x\n',
             "prose": '"""A module."""\n\n\ndef f(x):\n    """Twice x."""\n    return 2.0 * x  # doubled\n',
             "code": 'def f(x):\n    return 3.0 * x\n'}
    codes = {}
    for name, text in texts.items():
        (tmp_path / f"{name}.py").write_text(text)
        codes[name] = _code(tmp_path / f"{name}.py")
    assert codes["plain"] == codes["prose"]
    assert codes["plain"] != codes["code"]
