"""``warpbem run``: time-step a scene file, writing HDF5 frames (every ``frame_every`` steps, or
every ``frame_interval`` seconds with the steps landing on the frame times, and at the end),
flushed as written, so an interrupted run keeps its frames; ``resume`` continues a run from its
last complete frame.
"""

from __future__ import annotations

import json
import time
from datetime import datetime, timezone
from pathlib import Path

from ..dynamics.frame import frame_columns
from ..dynamics.simulator import Simulator
from ..dynamics.state import State
from . import scene as scenes
from .io import RunFileError, TableWriter, complete_rows, open_result, write_meshes
from .progress import eta_text
from .scene import Scene

# what may change when a run is resumed: nothing that would make the stored scene a false
# account of the frames already written
RESUMABLE_KEYS = ("time.end", "time.frame_every")


def stored(store) -> str:
    """The progress line's note of the snapshots read from the disk store (``snapshot_store.py``):
    " (store 40 read)"; "" with the store off or not looked in yet."""
    return "" if store is None or not store.hits + store.misses else f" (store {store.hits} read)"


def coupling_solves(hydro) -> str:
    """The progress line's note of the many-body remainders and close clusters solved
    (``many_body.py``, ``close_clusters.py``), which the snapshots' count leaves out:
    "  clusters 12"; "" on the whole system's snapshots or with neither."""
    pairwise = hydro.pairwise
    if pairwise is None:
        return ""
    parts = (("remainders", pairwise.remainder), ("clusters", pairwise.clusters))
    return "".join(f"  {label} {part.solved}" for label, part in parts if part is not None)


def read_state(f, model, row: int) -> State:
    """The state of frame ``row`` of an open run file (``model``: the run's)."""
    parts = {}
    for x in model.bound_interactions:
        if x.state_columns():
            parts[x.name] = {name: f[f"{x.name}_{name}"][row] for name in x.state_columns()}
    return State(float(f["time"][row]), f["position"][row], f["orientation"][row], int(f["steps"][row]), parts)


def _resumed(output: Path, overrides, given: Scene | None):
    """(scene, state of the last complete frame) of the run in ``output``: ``given`` (a scene
    built in Python, which must be the one the file holds) or the file's stored scene with
    ``overrides`` (RESUMABLE_KEYS only) applied."""
    for item in overrides:
        key = item.split("=", 1)[0]
        if key not in RESUMABLE_KEYS:
            raise scenes.SceneError(f"--set {key}: a resumed run cannot change {key!r} (the frames already"
                                    f" written were simulated without it); on resume only"
                                    f" {', '.join(RESUMABLE_KEYS)} may be set")
    with open_result(output, needs=("scene", "scene_folder", "time", "steps")) as f:
        stored = json.loads(f.attrs["scene"])
        if given is not None:
            if _unresumable(stored) != _unresumable(given.table()):
                raise RunFileError(f"{output} holds a run of another scene than the one given; resume it with the"
                                   " scene that wrote it, or start afresh with overwrite=True")
            scene = given
        elif "built_in" in stored:
            raise RunFileError(f"{output} was run from a Python script (warpbem.Scene.of); resume it there with"
                               " warpbem.run(scene, output, resume=True)")
        else:
            scene = scenes.parse(scenes.apply_overrides(stored, overrides), Path(f.attrs["scene_folder"]))
        columns = frame_columns(scene.model)
        missing = [name for name in columns if name not in f]
        if missing:
            raise RunFileError(f"{output}: the run has no column {missing[0]!r} that this version of warpbem writes"
                               f" for its scene (written by an older version?); it cannot be resumed")
        rows = complete_rows(f, columns)
        if rows == 0:
            raise RunFileError(f"{output}: the run was stopped before its first frame, so there is nothing to resume;"
                               " start it afresh with --overwrite (Python: overwrite=True)")
        state = read_state(f, scene.model, rows - 1)
    if scene.end < state.time:
        raise scenes.SceneError(f"time.end: {scene.end:g} s is before the run's last frame (t = {state.time:g} s)")
    return scene, state


def _unresumable(table: dict) -> dict:
    """A scene table less what a resumed run may change (RESUMABLE_KEYS)."""
    table = json.loads(json.dumps(table))  # a deep copy, tuples as lists as the file has them
    for key in RESUMABLE_KEYS:
        section, name = key.split(".")
        table.get(section, {}).pop(name, None)
    return table


def run(scene, output, overrides=(), device="cpu", resume=False, progress=print, overwrite=False) -> State:
    """Run a scene to its end time, writing its frames to the HDF5 file ``output``; returns the
    final state. ``scene``: a scene file (TOML, changed by ``overrides``, "key=value" strings) or
    a ``Scene`` (``load_scene``, ``Scene.of``). ``progress``: called with a line per frame
    (simulated time, steps/s, step, GMRES iterations, ETA) and a summary line at the end (print
    by default; None: silent). With ``resume``, ``output`` must be an earlier run: its stored
    scene is used (a Scene built in Python must be given again, the same one), ``overrides``
    may only extend it (RESUMABLE_KEYS), and stepping continues from its last frame complete in
    every column; a finished run says so and returns its last state. An existing ``output`` is
    replaced only with ``overwrite`` (nothing written is lost by mistake).

    Examples
    --------
    A cell settling for two steps, built in Python (``Scene.of``; ``load_scene`` reads a scene file):

    >>> import warpbem as wb
    >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> model = wb.Model([cell], [False], wb.Flow(shear_rate=0.0), interactions=[wb.Gravity([1070.0])])
    >>> scene = wb.Scene.of(model, [[0.0, 0.0, 6e-6]], end=2e-4)
    >>> final = wb.run(scene, "settle.h5")
    t = 0.0001 / 0.0002 s  steps 1  ... steps/s  dt 1.00e-04 s  GMRES ... (dense)  snapshots 0  ETA ...
    t = 0.0002 / 0.0002 s  steps 2  ...
    done: 2 steps, t = 0 -> 0.0002 s simulated in ... s; 3 frames in settle.h5
    >>> final = wb.run(scene, "settle.h5", resume=True)
    settle.h5: finished already (t = 0.0002 s = time.end); nothing to run. To run it on, resume with a later end (--set time.end=...)
    """
    output, report = Path(output), progress or (lambda line: None)
    given, path = (scene, None) if isinstance(scene, Scene) else (None, scene)
    if given is not None and overrides:
        raise ValueError("overrides change a scene file as it is read; for a Scene, build it with the values wanted")
    if resume:
        scene, state = _resumed(output, overrides, given)
        if state.time >= scene.end:
            report(f"{output}: finished already (t = {state.time:g} s = time.end); nothing to run. To run it on,"
                   f" resume with a later end (--set time.end=...)")
            return state
    else:
        if output.exists() and not overwrite:
            raise scenes.SceneError(f"{output} exists: --resume continues it, --overwrite replaces it (Python:"
                                    " resume=True, overwrite=True)")
        scene = given or scenes.load(path, overrides)
        state = scene.initial_state()
    sim = Simulator(scene.model, device)
    source = path if given is None else "a Python script" if given.raw is None else f"a scene of {given.folder}"
    writer = TableWriter(output, frame_columns(scene.model), scene.table(), device, title=f"warpbem run: {source}",
                         resume=resume)
    attrs = writer.file.attrs
    if resume:
        attrs["scene"] = json.dumps(scene.table(), sort_keys=True)
        attrs["resumed"] = json.dumps(json.loads(attrs.get("resumed", "[]")) + [
            {"time": state.time, "overrides": list(overrides), "at": datetime.now(timezone.utc).isoformat()}])
    else:
        attrs["scene_folder"] = "" if scene.folder is None else str(Path(scene.folder).resolve())
        attrs["body_names"] = json.dumps(list(scene.model.names))
        attrs["near_far_split"] = sim.near_far_split
        write_meshes(writer.file, scene.model.meshes)
        bonds = scene.model.interaction("bond")
        if bonds is not None:
            attrs["seed"] = bonds.seed  # the bond Monte Carlo's stream (kernels/bonds.py)
    start, steps, t0 = time.perf_counter(), 0, state.time
    with writer:
        if not resume:  # frame 0: the initial state
            writer.append(**sim.frame(state).columns())
        while state.time < scene.end:
            stop = scene.next_stop(state.time)
            state, frame = sim.step(state, stop)
            steps += 1
            if steps == 1:  # decided when the solver was built (or, with the near-far split, at its first solve)
                attrs["operator"] = sim.mobility.operator_description
            if scene.frame_due(state, stop):
                writer.append(**frame.columns())
                elapsed = time.perf_counter() - start
                rate = (state.time - t0) / elapsed
                eta = eta_text((scene.end - state.time) / rate) if rate > 0 else "ETA -"
                report(f"t = {state.time:.6g} / {scene.end:g} s  steps {state.steps}  {steps / elapsed:.2f} steps/s"
                       f"  dt {frame.dt:.2e} s  GMRES {frame.gmres_iterations} ({sim.mobility.operator_description})"
                       f"  snapshots {sim.hydro.snapshots_solved}{stored(sim.hydro.store)}"
                       f"{coupling_solves(sim.hydro)}  {eta}")
        frames = writer.rows
    report(f"done: {steps} steps, t = {t0:g} -> {state.time:g} s simulated in {time.perf_counter() - start:.1f} s;"
           f" {frames} frames in {output}")
    return state
