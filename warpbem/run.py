"""``warpbem run``: time-step a scene file, writing one HDF5 frame every ``frame_every`` steps
(flushed as written, so an interrupted run keeps its frames) and resuming from the last frame.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import h5py
import numpy as np

from . import scene as scenes
from .integrate import State
from .io import TableWriter
from .mobility import MobilitySolver
from .simulator import STANDARD_GRAVITY, Simulator, StepPolicy


def _columns(n):
    return {
        "time": ("s", ()), "dt": ("s", ()),
        "position": ("m", (n, 3)), "orientation": ("1 (unit quaternion w, x, y, z)", (n, 4)),
        "velocity": ("m/s", (n, 3)), "angular_velocity": ("rad/s", (n, 3)),
        "force": ("N (given on free bodies, holding load on fixed ones)", (n, 3)), "torque": ("N m", (n, 3)),
        "gmres_iterations": ("1", ()), "gmres_residual": ("1", ()),
        "closest_gap": ("m (smallest surface gap of a free body to another body or the wall)", ()),
    }


def _write_frame(writer, sim, state, motion, dt):
    """One HDF5 frame: the state, the motion that led to it and the latest solve's loads
    (external and repulsive on free bodies, holding loads on fixed ones)."""
    solution = sim.last_solution
    writer.append(time=state.time, dt=dt, position=state.positions, orientation=state.orientations,
                  velocity=motion[0], angular_velocity=motion[1], force=solution.force, torque=solution.torque,
                  gmres_iterations=solution.iterations, gmres_residual=solution.residual,
                  closest_gap=sim.closest_gap(state))


def build(scene: scenes.Scene, device="cpu") -> Simulator:
    solver = MobilitySolver(scene.shear_rate, scene.viscosity, scene.wall, device,
                            quadrature_order=scene.quadrature_order, tolerance=scene.tolerance,
                            contact_refinement=scene.contact_refinement,
                            refine_fixed_at_wall=scene.refine_fixed_at_wall)
    _, _, densities, forces, torques = scenes.body_arrays(scene)
    return Simulator([b[1] for b in scene.bodies], [b[4] for b in scene.bodies], solver,
                     densities=densities, fluid_density=scene.fluid_density, forces=forces, torques=torques,
                     repulsion=scene.repulsion,
                     gravity=STANDARD_GRAVITY if scene.gravity else 0.0, scheme=scene.scheme,
                     policy=StepPolicy(scene.dt_max, scene.dt_min, scene.contact_gap))


def run(scene_path, output, overrides=(), device="cpu", resume=False, progress=print, overwrite=False):
    """Run a scene to its end time. With ``resume``, ``output`` must be an earlier run of the
    same scene: the scene stored in it is used and stepping continues from its last frame. An
    existing ``output`` is replaced only with ``overwrite`` (nothing written is lost by mistake)."""
    output = Path(output)
    if output.exists() and not resume and not overwrite:
        raise scenes.SceneError(f"{output} exists: --resume continues it, --overwrite replaces it")
    if resume:
        with h5py.File(output, "r") as f:
            stored = json.loads(f.attrs["scene"])
            folder = Path(f.attrs["scene_folder"])
            state = State(float(f["time"][-1]), f["position"][-1], f["orientation"][-1])
        scene = scenes.parse(stored, folder)
    else:
        scene = scenes.load(scene_path, overrides)
        positions, orientations = scenes.body_arrays(scene)[:2]
        state = State(0.0, positions, orientations)
    sim = build(scene, device)
    n = len(scene.bodies)
    writer = TableWriter(output, _columns(n), scene.raw, device, title=f"warpbem run: {scene_path}", resume=resume)
    if not resume:
        writer.file.attrs["scene_folder"] = str(Path(scene_path).resolve().parent)
        writer.file.attrs["body_names"] = json.dumps([b[0] for b in scene.bodies])
    start, steps, t0 = time.perf_counter(), 0, state.time
    with writer:
        if not resume:  # frame 0: the initial state and its velocities
            _write_frame(writer, sim, state, sim.velocities(state), 0.0)
        while state.time < scene.end * (1 - 1e-12):
            state, motion, dt = sim.step(state)
            steps += 1
            if steps % scene.frame_every == 0 or state.time >= scene.end * (1 - 1e-12):
                sol = sim.last_solution
                _write_frame(writer, sim, state, motion, dt)
                elapsed = time.perf_counter() - start
                rate = (state.time - t0) / elapsed
                eta = (scene.end - state.time) / rate if rate > 0 else float("inf")
                progress(f"t = {state.time:.6g} / {scene.end:g} s  steps {steps}  {steps / elapsed:.2f} steps/s"
                         f"  dt {dt:.2e} s  GMRES {sol.iterations}  ETA {eta:.0f} s")
    return state
