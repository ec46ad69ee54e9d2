"""Declarative scenes (TOML), validated before any work: every problem is reported with the
field's dotted name and the allowed values or range. Lengths in metres, times in seconds,
viscosity in Pa s, densities in kg/m^3, shear rate in 1/s (SI, like the API).

    [flow]                      shear_rate = 100.0, viscosity = 1.2e-3, wall = true
    [physics]                   gravity = false, fluid_density = 1000.0, repulsion = false
    [repulsion]                 coefficient = 1e-12 (F0, J), inverse_length = 2e9 (tau, 1/m),
                                cell_roughness = 175e-9, wall_roughness = 50e-9 (thesis eq. 3.1;
                                the unit convention of F0 is explained in warpbem/repulsion.py)
    [time]                      end = 0.01, dt_max = 1e-4, dt_min = 1e-5, contact_gap = 5e-7,
                                scheme = "heun", frame_every = 10
    [solver]                    quadrature_order = 2, contact_refinement = 3.0, tolerance = 1e-8,
                                refine_fixed_at_wall = true
    [[bodies]]                  name, position = [x, y, z], orientation = [w, x, y, z],
                                fixed = false, density = 1000.0, force = [0, 0, 0] (N),
                                torque = [0, 0, 0] (N m) on free bodies, and a mesh:
    [bodies.mesh]               shape = "sphere" (radius, subdivisions) | "spheroid" (radius,
                                aspect_ratio, subdivisions) | "file" (path, relative to the scene)

``--set key=value`` overrides use the dotted names, e.g. ``flow.shear_rate=80`` or
``bodies.0.position=[0,0,7.75e-6]``.
"""

from __future__ import annotations

import ast
import copy
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import mesh as meshes
from .body import Body
from .repulsion import Repulsion


class SceneError(ValueError):
    """A scene that cannot run; the message names the field."""


def _number(where, value, low=-math.inf, high=math.inf, low_open=False, integer=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(f"{where}: expected a finite number, got {value!r}")
    if integer and int(value) != value:
        raise SceneError(f"{where}: expected an integer, got {value!r}")
    if value < low or value > high or (low_open and value == low):
        bracket = "(" if low_open else "["
        raise SceneError(f"{where}: {value:g} is outside the allowed range {bracket}{low:g}, {high:g}]")
    return int(value) if integer else float(value)


def _bool(where, value):
    if not isinstance(value, bool):
        raise SceneError(f"{where}: expected true or false, got {value!r}")
    return value


def _vector(where, value, length):
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise SceneError(f"{where}: expected a list of {length} numbers, got {value!r}")
    return tuple(_number(f"{where}[{i}]", v) for i, v in enumerate(value))


def _table(where, value, allowed, required=()):
    if not isinstance(value, dict):
        raise SceneError(f"{where}: expected a table, got {value!r}")
    unknown = sorted(set(value) - set(allowed))
    if unknown:
        raise SceneError(f"{where}: unknown key {unknown[0]!r}; allowed keys: {', '.join(sorted(allowed))}")
    missing = [k for k in required if k not in value]
    if missing:
        raise SceneError(f"{where}: missing required key {missing[0]!r}")
    return value


@dataclass(frozen=True)
class Scene:
    """A validated scene; ``raw`` keeps the checked table for the output file."""

    raw: dict
    bodies: tuple  # (name, Mesh, position, orientation, fixed, density, force, torque)
    shear_rate: float
    viscosity: float
    wall: bool
    gravity: bool
    fluid_density: float
    repulsion: Repulsion | None
    end: float
    dt_max: float
    dt_min: float
    contact_gap: float
    scheme: str
    frame_every: int
    quadrature_order: int
    contact_refinement: float
    tolerance: float
    refine_fixed_at_wall: bool
    sweep: dict  # {axis: {label: [key=value overrides]}}, the cases ``warpbem sweep`` runs

    def initial_bodies(self) -> list[Body]:
        return [Body(b[1], position=b[2], orientation=b[3], fixed=b[4]) for b in self.bodies]


def _mesh(where, spec, folder: Path):
    shape = _table(where, spec, {"shape", "radius", "subdivisions", "aspect_ratio", "path"}, ("shape",))["shape"]
    k = _number(f"{where}.subdivisions", spec.get("subdivisions", 4), 1, 32, integer=True)
    if shape == "sphere":
        return meshes.sphere(_number(f"{where}.radius", spec.get("radius"), 0, 1e-2, low_open=True), k)
    if shape == "spheroid":
        return meshes.spheroid(_number(f"{where}.radius", spec.get("radius"), 0, 1e-2, low_open=True),
                               _number(f"{where}.aspect_ratio", spec.get("aspect_ratio"), 0.05, 20), k)
    if shape == "file":
        if not isinstance(spec.get("path"), str):
            raise SceneError(f"{where}.path: expected the path of a QUAD9 mesh file")
        try:
            return meshes.load(folder / spec["path"])
        except meshes.MeshError as err:
            raise SceneError(f"{where}.path: {err}") from err
    raise SceneError(f"{where}.shape: {shape!r} is not one of 'sphere', 'spheroid', 'file'")


def parse(table: dict, folder: Path = Path(".")) -> Scene:
    """Validate a scene table (as read from TOML) and build the Scene."""
    _table("scene", table, {"flow", "physics", "repulsion", "time", "solver", "bodies", "sweep"},
           ("flow", "time", "bodies"))
    sweep = _sweep_axes(table.get("sweep", {}))
    flow = _table("flow", table["flow"], {"shear_rate", "viscosity", "wall"}, ("shear_rate",))
    physics = _table("physics", table.get("physics", {}), {"gravity", "fluid_density", "repulsion"})
    repulsion = _table("repulsion", table.get("repulsion", {}),
                       {"coefficient", "inverse_length", "cell_roughness", "wall_roughness"})
    time = _table("time", table["time"], {"end", "dt_max", "dt_min", "contact_gap", "scheme", "frame_every"}, ("end",))
    solver = _table("solver", table.get("solver", {}), {"quadrature_order", "contact_refinement", "tolerance",
                                                        "refine_fixed_at_wall"})
    if not isinstance(table["bodies"], list) or not table["bodies"]:
        raise SceneError("bodies: expected at least one [[bodies]] entry")
    bodies = []
    for i, spec in enumerate(table["bodies"]):
        where = f"bodies.{i}"
        _table(where, spec, {"name", "mesh", "position", "orientation", "fixed", "density", "force", "torque"},
               ("mesh", "position"))
        bodies.append((str(spec.get("name", f"body{i}")), _mesh(f"{where}.mesh", spec["mesh"], folder),
                       _vector(f"{where}.position", spec["position"], 3),
                       _vector(f"{where}.orientation", spec.get("orientation", [1.0, 0, 0, 0]), 4),
                       _bool(f"{where}.fixed", spec.get("fixed", False)),
                       _number(f"{where}.density", spec.get("density", 1000.0), 100.0, 1e5),
                       _vector(f"{where}.force", spec.get("force", [0.0, 0.0, 0.0]), 3),
                       _vector(f"{where}.torque", spec.get("torque", [0.0, 0.0, 0.0]), 3)))
    dt_max = _number("time.dt_max", time.get("dt_max", 1e-4), 0, 10, low_open=True)
    dt_min = _number("time.dt_min", time.get("dt_min", min(1e-5, dt_max)), 0, dt_max, low_open=True)
    repulsion_model = Repulsion(  # validated even when switched off, so typos surface early
        _number("repulsion.coefficient", repulsion.get("coefficient", 1e-12), 0, 1, low_open=True),
        _number("repulsion.inverse_length", repulsion.get("inverse_length", 2e9), 0, 1e12, low_open=True),
        _number("repulsion.cell_roughness", repulsion.get("cell_roughness", 175e-9), 0, 1e-5),
        _number("repulsion.wall_roughness", repulsion.get("wall_roughness", 50e-9), 0, 1e-5))
    scheme = time.get("scheme", "heun")
    if scheme not in ("euler", "heun"):
        raise SceneError(f"time.scheme: {scheme!r} is not one of 'euler', 'heun'")
    return Scene(
        raw=copy.deepcopy(table), bodies=tuple(bodies),
        shear_rate=_number("flow.shear_rate", flow["shear_rate"], -1e6, 1e6),
        viscosity=_number("flow.viscosity", flow.get("viscosity", 1.2e-3), 0, 1e3, low_open=True),
        wall=_bool("flow.wall", flow.get("wall", True)),
        gravity=_bool("physics.gravity", physics.get("gravity", False)),
        fluid_density=_number("physics.fluid_density", physics.get("fluid_density", 1000.0), 100.0, 1e5),
        repulsion=repulsion_model if _bool("physics.repulsion", physics.get("repulsion", False)) else None,
        end=_number("time.end", time["end"], 0, 1e6, low_open=True), dt_max=dt_max, dt_min=dt_min,
        contact_gap=_number("time.contact_gap", time.get("contact_gap", 5e-7), 0, 1e-2, low_open=True),
        scheme=scheme, frame_every=_number("time.frame_every", time.get("frame_every", 1), 1, 1e9, integer=True),
        quadrature_order=_number("solver.quadrature_order", solver.get("quadrature_order", 2), 1, 10, integer=True),
        contact_refinement=_number("solver.contact_refinement", solver.get("contact_refinement", 3.0), 0, 20),
        tolerance=_number("solver.tolerance", solver.get("tolerance", 1e-8), 0, 0.1, low_open=True),
        refine_fixed_at_wall=_bool("solver.refine_fixed_at_wall", solver.get("refine_fixed_at_wall", True)),
        sweep=sweep,
    )


def _sweep_axes(table) -> dict:
    """[sweep.AXIS] tables: label = ["key=value", ...], one case per label."""
    if not isinstance(table, dict):
        raise SceneError(f"sweep: expected tables [sweep.NAME], got {table!r}")
    axes = {}
    for axis, cases in table.items():
        if not isinstance(cases, dict) or not cases:
            raise SceneError(f"sweep.{axis}: expected a table of label = [\"key=value\", ...] cases")
        for label, overrides in cases.items():
            if (not isinstance(overrides, list) or not overrides
                    or not all(isinstance(o, str) and "=" in o for o in overrides)):
                raise SceneError(f"sweep.{axis}.{label}: expected a list of \"key=value\" strings")
        axes[axis] = {str(label): list(overrides) for label, overrides in cases.items()}
    return axes


def apply_overrides(table: dict, overrides) -> dict:
    """Apply ``key=value`` strings (dotted keys; list indices as numbers) to a copy of the table."""
    table = copy.deepcopy(table)
    for item in overrides:
        if "=" not in item:
            raise SceneError(f"--set {item!r}: expected key=value")
        key, text = item.split("=", 1)
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            try:
                value = ast.literal_eval(text)
            except (ValueError, SyntaxError):
                value = text
        node, parts = table, key.split(".")
        for part in parts[:-1]:
            node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return table


def load(path, overrides=()) -> Scene:
    """Read, override and validate a scene file; also checks that the bodies do not overlap."""
    path = Path(path)
    try:
        table = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as err:
        raise SceneError(f"{path}: cannot read the scene ({err})") from err
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{path}: not valid TOML ({err})") from err
    scene = parse(apply_overrides(table, overrides), path.parent)
    from .placement import PlacementError, check_placement

    try:
        check_placement(scene.initial_bodies(), scene.wall)
    except PlacementError as err:
        raise SceneError(f"{path}: initial placement: {err}") from err
    if scene.repulsion is not None:
        _check_roughness(scene)
    return scene


def _check_roughness(scene: Scene):
    """With repulsion on, the roughness layers of a free body must not start in contact
    (thesis eq. 3.1 diverges there)."""
    from .contact import WALL, GapFinder, candidate_pairs, outer_radius

    bodies, finder, rep = scene.initial_bodies(), GapFinder(), scene.repulsion
    layers = rep.cell_roughness + max(rep.cell_roughness, rep.wall_roughness)  # the thickest pair
    pairs = candidate_pairs([b.position for b in bodies], [outer_radius(b.mesh) for b in bodies],
                            [b.fixed for b in bodies], scene.wall, 2.0 * layers)
    for i, j in pairs:
        gap = finder.between(bodies, i, j).distance
        if rep.separation(gap, j == WALL) <= 0:
            other = "the wall" if j == WALL else f"bodies.{j}"
            raise SceneError(f"bodies.{i}.position: its roughness layer touches that of {other} (gap"
                             f" {gap:.4g} m; with repulsion on the gap must exceed"
                             f" {rep.cell_roughness + (rep.wall_roughness if j == WALL else rep.cell_roughness):.4g} m)")


def body_arrays(scene: Scene):
    """Initial positions (n, 3), orientations (n, 4), densities (n,), forces and torques (n, 3)."""
    return tuple(np.array([b[k] for b in scene.bodies]) for k in (2, 3, 5, 6, 7))
