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
from .io import RunFileError, TableWriter, complete_rows, open_result

# what may change when a run is resumed: nothing that would make the stored scene a false
# account of the frames already written
RESUMABLE_KEYS = ("time.end", "time.frame_every")


def read_state(f, model, row: int) -> State:
    """The state of frame ``row`` of an open run file (``model``: the run's)."""
    parts = {}
    for x in model.bound_interactions:
        if x.state_columns():
            parts[x.name] = {name: f[f"{x.name}_{name}"][row] for name in x.state_columns()}
    return State(float(f["time"][row]), f["position"][row], f["orientation"][row], int(f["steps"][row]), parts)


def _resumed(output: Path, overrides):
    """(scene, state of the last complete frame) of the run in ``output``, with ``overrides``
    (RESUMABLE_KEYS only) applied to its stored scene."""
    for item in overrides:
        key = item.split("=", 1)[0]
        if key not in RESUMABLE_KEYS:
            raise scenes.SceneError(f"--set {key}: a resumed run cannot change {key!r} (the frames already"
                                    f" written were simulated without it); on resume only"
                                    f" {', '.join(RESUMABLE_KEYS)} may be set")
    with open_result(output, needs=("scene", "scene_folder", "time", "steps")) as f:
        stored = json.loads(f.attrs["scene"])
        scene = scenes.parse(scenes.apply_overrides(stored, overrides), Path(f.attrs["scene_folder"]))
        columns = frame_columns(scene.model)
        missing = [name for name in columns if name not in f]
        if missing:
            raise RunFileError(f"{output}: the run has no column {missing[0]!r} that this version of warpbem writes"
                               f" for its scene (written by an older version?); it cannot be resumed")
        rows = complete_rows(f, columns)
        if rows == 0:
            raise RunFileError(f"{output}: the run has no complete frame to resume from")
        state = read_state(f, scene.model, rows - 1)
    if scene.end < state.time:
        raise scenes.SceneError(f"time.end: {scene.end:g} s is before the run's last frame (t = {state.time:g} s)")
    return scene, state


def run(scene_path, output, overrides=(), device="cpu", resume=False, progress=print, overwrite=False) -> State:
    """Run a scene to its end time; returns the final state. With ``resume``, ``output`` must be
    an earlier run: its stored scene is used (``overrides`` may only extend it, RESUMABLE_KEYS)
    and stepping continues from its last frame complete in every column. An existing
    ``output`` is replaced only with ``overwrite`` (nothing written is lost by mistake)."""
    output = Path(output)
    if resume:
        scene, state = _resumed(output, overrides)
    else:
        if output.exists() and not overwrite:
            raise scenes.SceneError(f"{output} exists: --resume continues it, --overwrite replaces it")
        scene = scenes.load(scene_path, overrides)
        state = scene.initial_state()
    sim = Simulator(scene.model, device)
    writer = TableWriter(output, frame_columns(scene.model), scene.raw, device, title=f"warpbem run: {scene_path}",
                         resume=resume)
    attrs = writer.file.attrs
    if resume:
        attrs["scene"] = json.dumps(scene.raw, sort_keys=True)
        attrs["resumed"] = json.dumps(json.loads(attrs.get("resumed", "[]")) + [
            {"time": state.time, "overrides": list(overrides), "at": datetime.now(timezone.utc).isoformat()}])
    else:
        attrs["scene_folder"] = str(Path(scene_path).resolve().parent)
        attrs["body_names"] = json.dumps(list(scene.model.names))
        attrs["near_far_split"] = sim.near_far_split
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
                eta = (scene.end - state.time) / rate if rate > 0 else float("inf")
                progress(f"t = {state.time:.6g} / {scene.end:g} s  steps {state.steps}  {steps / elapsed:.2f} steps/s"
                         f"  dt {frame.dt:.2e} s  GMRES {frame.gmres_iterations} ({sim.mobility.operator_description})"
                         f"  snapshots {sim.hydro.snapshots_solved}  ETA {eta:.0f} s")
    return state
