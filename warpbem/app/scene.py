"""Declarative scenes (TOML), validated before any work: every problem is reported with the
field's dotted name and the allowed values or range. Lengths in metres, times in seconds,
viscosity in Pa s, densities in kg/m^3, shear rate in 1/s (SI, like the API).

    [flow]                      shear_rate = 100.0, viscosity = 1.2e-3, wall = true
    [physics]                   gravity = false, fluid_density = 1000.0, repulsion = false,
                                adhesion = false
    [repulsion]                 coefficient = 1e-12 (F0, J), inverse_length = 2e9 (tau, 1/m),
                                cell_roughness = 175e-9, wall_roughness = 50e-9 (thesis eq. 3.1;
                                the unit convention of F0 is explained in warpbem/forces/repulsion.py)
    [adhesion]                  (thesis Table 4.1; warpbem/forces/adhesion.py) spring_constant
                                (N/m, required), receptor_density = 20e12 (1/m^2),
                                ligand_density (1/m^2; default: ligands in excess),
                                equilibrium_length = 30e-9, off_rate = 2.4, on_rate = 365.0
                                (1/s), reactive_compliance = 0.39e-10 (m), temperature = 310.0,
                                max_bonds = 100 (per cell), compression = false, seed = 0,
                                roughness (tips; default: repulsion.cell_roughness),
                                ligand_layer (default: repulsion.wall_roughness),
                                kinetics_fraction = 0.1 (the step keeps k dt below it),
                                cell_ligand_layer (ligands on adherent cells; default:
                                repulsion.cell_roughness)
    [deformation]               (deformable bodies; warpbem/elastic/deformable.py) relaxation =
                                true (the fluid's resistance, tau = 3 mu / 2G; false:
                                quasi-static), surface_velocity = true (the flow sees the
                                surface move with the material; false: the deformed shape
                                rigid), update_interval = 1 (steps between traction and
                                elastic solves)
    [time]                      end = 0.01, dt_max = 1e-4, dt_min = 1e-5, contact_gap = 5e-7,
                                scheme = "heun", and frames by steps, frame_every = 1, or by
                                time, frame_interval = 1e-3 (s; the steps land on frame times)
    [solver]                    quadrature_order = 2, density_order = 1 (1: density constant per
                                element, the seed's; 2: bilinear, README "Accuracy per cost"),
                                contact_refinement (default 3.0 with density_order 1, 1.1 with
                                2; the ratio on the k = 4 sphere, scaled with the mesh), tolerance (GMRES;
                                default 1e-8 for float64, 1e-6 for float32), dtype = "float64",
                                refine_fixed_at_wall = true, reuse_tolerance (m; mobility
                                snapshots reused across steps, dynamics/hydrodynamics.py;
                                default 0, with adhesion on ADHESION_REUSE_TOLERANCE),
                                reuse_lateral (m; their lateral lattice with several bodies,
                                default 50 x reuse_tolerance), reuse_interaction (m; the height
                                lattice of the several-body snapshots, default 10 x
                                reuse_tolerance), near_far_cutoff (m; adherent cells whose
                                bounding sphere stays farther than it from every free cell's keep
                                the background solved once, warpbem/hydro/frozen.py; README
                                "Frozen adherent arrays" charts the error; default: every solve
                                holds every body)
    [[bodies]]                  name, position = [x, y, z], orientation = [w, x, y, z],
                                fixed = false, density = 1000.0, force = [0, 0, 0] (N),
                                torque = [0, 0, 0] (N m) on free bodies, adhesive = true (free
                                bodies with adhesion on), shear_modulus (Pa; none: rigid, no
                                Hertz patch), poisson_ratio = 0.33, deformable = false
                                (free bodies: linear elasticity with shear_modulus, see
                                [deformation]), ligands = false (fixed
                                bodies: free cells can bind to them), and a mesh:
    [bodies.mesh]               shape = "sphere" (radius, subdivisions, pole_grading: elements
                                crowded towards -z, 1 = uniform) | "spheroid" (radius,
                                aspect_ratio, subdivisions) | "file" (path, relative to the scene)

    [[arrays]]                  count = [nx, ny] bodies alike at origin = [x, y, z] + (i pitch_x,
                                j pitch_y, 0), pitch = [pitch_x, pitch_y], named "<name> i j",
                                with any body key but position (one mesh for all); listed after
                                the [[bodies]]

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
from typing import NamedTuple

from ..dynamics.model import Flow, Model, SolverOptions, StepPolicy
from ..options import OptionError, from_table
from ..dynamics.state import State
from ..elastic.deformable import Deformation
from ..forces.adhesion import Adhesion
from ..forces.external import STANDARD_GRAVITY, ExternalLoads, Gravity
from ..forces.repulsion import Repulsion
from ..surfaces import mesh as meshes
from ..surfaces.body import Body
from ..surfaces.gaps import WALL, Contacts, GapFinder
from ..surfaces.placement import PlacementError, check_placement


ADHESION_REUSE_TOLERANCE = 2e-9  # m: chosen from benchmarks/adhesion.py (README: adhesion)
ADHESION_KEYS = {"receptor_density", "ligand_density", "spring_constant", "equilibrium_length", "off_rate",
                 "reactive_compliance", "on_rate", "temperature", "max_bonds", "compression", "seed", "roughness",
                 "ligand_layer", "kinetics_fraction", "cell_ligand_layer"}


class SceneError(ValueError):
    """A scene that cannot run; the message names the field."""


def _options(cls, table, where, **given):
    """A declared options dataclass read from a scene table (``warpbem.options.from_table``)."""
    try:
        return from_table(cls, table, where, **given)
    except OptionError as err:
        raise SceneError(str(err)) from err


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


class BodySpec(NamedTuple):
    """One [[bodies]] entry, validated: SI values, the mesh built."""

    name: str
    mesh: meshes.Mesh
    position: tuple
    orientation: tuple
    fixed: bool
    density: float
    force: tuple
    torque: tuple
    adhesive: bool
    shear_modulus: float | None
    poisson_ratio: float
    ligands: bool
    deformable: bool


@dataclass(frozen=True)
class Scene:
    """A validated scene: the ``model`` it describes, the start placement of its ``bodies``, the
    run settings (end time, frames every ``frame_every`` steps or every ``frame_interval``
    seconds) and its sweep axes; ``raw`` keeps the checked table for the output file."""

    raw: dict
    bodies: tuple  # BodySpec per body
    model: Model
    end: float
    frame_every: int | None
    frame_interval: float | None
    sweep: dict  # {axis: {label: [key=value overrides]}}, the cases ``warpbem sweep`` runs

    def initial_bodies(self) -> list[Body]:
        return [Body(b.mesh, position=b.position, orientation=b.orientation, fixed=b.fixed) for b in self.bodies]

    def initial_state(self) -> State:
        return self.model.initial_state([b.position for b in self.bodies], [b.orientation for b in self.bodies])

    def next_stop(self, time: float) -> float:
        """The time (s) the next step must not pass: the next frame time or the end."""
        if self.frame_interval is None:
            return self.end
        k = round(time / self.frame_interval)
        stop = k * self.frame_interval  # the same expression as the time a landing step sets
        if stop <= time:
            stop = (k + 1) * self.frame_interval
        return min(stop, self.end)

    def frame_due(self, state: State, stop: float) -> bool:
        """Whether ``state``, reached by a step towards ``stop``, is written as a frame."""
        if state.time == self.end:
            return True
        if self.frame_interval is None:
            return state.steps % self.frame_every == 0
        return state.time == stop


def _mesh(where, spec, folder: Path):
    shape = _table(where, spec, {"shape", "radius", "subdivisions", "aspect_ratio", "path", "pole_grading"},
                   ("shape",))["shape"]
    k = _number(f"{where}.subdivisions", spec.get("subdivisions", 4), 1, 32, integer=True)
    if "pole_grading" in spec and shape != "sphere":
        raise SceneError(f"{where}.pole_grading: only a sphere is graded (shape = 'sphere')")
    if shape == "sphere":
        return meshes.sphere(_number(f"{where}.radius", spec.get("radius"), 0, 1e-2, low_open=True), k,
                             pole_grading=_number(f"{where}.pole_grading", spec.get("pole_grading", 1.0), 1, 100))
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
    _table("scene", table, {"flow", "physics", "repulsion", "adhesion", "deformation", "time", "solver",
                           "bodies", "arrays", "sweep"},
           ("flow", "time"))
    sweep = _sweep_axes(table.get("sweep", {}))
    if isinstance(table["flow"], dict) and "shear_rate" not in table["flow"]:
        raise SceneError("flow: missing required key 'shear_rate'")
    flow_ = _options(Flow, table["flow"], "flow")
    physics = _table("physics", table.get("physics", {}), {"gravity", "fluid_density", "repulsion", "adhesion"})
    adhesion = _table("adhesion", table.get("adhesion", {}), ADHESION_KEYS)
    deformation = _table("deformation", table.get("deformation", {}), {"relaxation", "update_interval",
                                                                               "surface_velocity"})
    # validated even when no body deforms, so typos surface early
    relaxation = _bool("deformation.relaxation", deformation.get("relaxation", True))
    surface_velocity = _bool("deformation.surface_velocity", deformation.get("surface_velocity", True))
    update_interval = _number("deformation.update_interval", deformation.get("update_interval", 1), 1, 1e6,
                              integer=True)
    repulsion = _table("repulsion", table.get("repulsion", {}),
                       {"coefficient", "inverse_length", "cell_roughness", "wall_roughness"})
    time = _table("time", table["time"], {"end", "dt_max", "dt_min", "contact_gap", "scheme", "frame_every",
                                          "frame_interval"}, ("end",))
    solver = _table("solver", table.get("solver", {}), {name for name in SolverOptions.__dataclass_fields__
                                                        if name != "treecode"})
    bodies = []
    for i, spec in enumerate(_entries("bodies", table.get("bodies", []))):
        where = f"bodies.{i}"
        _table(where, spec, BODY_KEYS, ("mesh", "position"))
        mesh = _mesh(f"{where}.mesh", spec["mesh"], folder)
        bodies.append(_body(where, spec, mesh, str(spec.get("name", f"body{i}"))))
    for i, spec in enumerate(_entries("arrays", table.get("arrays", []))):
        bodies += _array(f"arrays.{i}", spec, folder)
    if not bodies:
        raise SceneError("bodies: expected at least one [[bodies]] or [[arrays]] entry")
    end = _number("time.end", time["end"], 0, 1e6, low_open=True)
    dt_max = _number("time.dt_max", time.get("dt_max", 1e-4), 0, 10, low_open=True)
    dt_min = _number("time.dt_min", time.get("dt_min", min(1e-5, dt_max)), 0, dt_max, low_open=True)
    if "frame_every" in time and "frame_interval" in time:
        raise SceneError("time.frame_interval: give frames by steps (frame_every) or by time (frame_interval), not both")
    frame_interval = (_number("time.frame_interval", time["frame_interval"], 0, end, low_open=True)
                      if "frame_interval" in time else None)
    frame_every = (None if frame_interval is not None
                   else _number("time.frame_every", time.get("frame_every", 1), 1, 1e9, integer=True))
    repulsion_model = Repulsion(  # validated even when switched off, so typos surface early
        _number("repulsion.coefficient", repulsion.get("coefficient", 1e-12), 0, 1, low_open=True),
        _number("repulsion.inverse_length", repulsion.get("inverse_length", 2e9), 0, 1e12, low_open=True),
        _number("repulsion.cell_roughness", repulsion.get("cell_roughness", 175e-9), 0, 1e-5),
        _number("repulsion.wall_roughness", repulsion.get("wall_roughness", 50e-9), 0, 1e-5))
    scheme = _choice("time.scheme", time.get("scheme", "heun"), ("euler", "heun"))
    meshes_, fixed = [b.mesh for b in bodies], [b.fixed for b in bodies]
    fluid_density = _number("physics.fluid_density", physics.get("fluid_density", 1000.0), 100.0, 1e5)
    # model no more than the scene needs: only the interactions switched on are built
    interactions = []
    if _bool("physics.gravity", physics.get("gravity", False)):
        interactions.append(Gravity(meshes_, fixed, [b.density for b in bodies], fluid_density, STANDARD_GRAVITY))
    if any(any(b.force) or any(b.torque) for b in bodies):
        interactions.append(ExternalLoads(fixed, [b.force for b in bodies], [b.torque for b in bodies]))
    if _bool("physics.repulsion", physics.get("repulsion", False)):
        interactions.append(repulsion_model)
    adhesive = _bool("physics.adhesion", physics.get("adhesion", False))
    if adhesive:
        interactions.append(_adhesion(adhesion, bodies, repulsion_model, dt_min, flow_.wall))
    # bonds: mobility snapshots reused across steps unless the scene says otherwise (SolverOptions)
    solver_options = _options(SolverOptions, {"reuse_tolerance": ADHESION_REUSE_TOLERANCE, **solver} if adhesive
                              else solver, "solver").resolved(time_stepping=True)
    if any(b.deformable for b in bodies):
        interactions.append(Deformation(
            meshes_, [b.deformable for b in bodies], [b.shear_modulus for b in bodies],
            [b.poisson_ratio for b in bodies], flow_,
            relaxation=relaxation, surface_velocity=surface_velocity, update_interval=update_interval,
            solver=solver_options))
    model = Model(
        meshes=meshes_, fixed=fixed, names=[b.name for b in bodies], interactions=interactions,
        flow=flow_, solver=solver_options,
        policy=StepPolicy(dt_max, dt_min,
                          _number("time.contact_gap", time.get("contact_gap", 5e-7), 0, 1e-2, low_open=True)),
        scheme=scheme)
    return Scene(raw=copy.deepcopy(table), bodies=tuple(bodies), model=model, end=end, frame_every=frame_every,
                 frame_interval=frame_interval, sweep=sweep)


BODY_KEYS = {"name", "mesh", "position", "orientation", "fixed", "density", "force", "torque", "adhesive",
             "shear_modulus", "poisson_ratio", "ligands", "deformable"}
ARRAY_KEYS = {"count", "pitch", "origin"}


def _entries(where, value) -> list:
    if not isinstance(value, list):
        raise SceneError(f"{where}: expected a list of tables ([[{where}]] entries), got {value!r}")
    return value


def _body(where, spec, mesh, name, position=None) -> BodySpec:
    """One body's keys (BODY_KEYS, checked by the caller) as a BodySpec named ``name``;
    ``position`` given for the members of an array."""
    body = BodySpec(name, mesh,
                    position or _vector(f"{where}.position", spec["position"], 3),
                    _vector(f"{where}.orientation", spec.get("orientation", [1.0, 0, 0, 0]), 4),
                    _bool(f"{where}.fixed", spec.get("fixed", False)),
                    _number(f"{where}.density", spec.get("density", 1000.0), 100.0, 1e5),
                    _vector(f"{where}.force", spec.get("force", [0.0, 0.0, 0.0]), 3),
                    _vector(f"{where}.torque", spec.get("torque", [0.0, 0.0, 0.0]), 3),
                    _bool(f"{where}.adhesive", spec.get("adhesive", True)),
                    None if "shear_modulus" not in spec else
                    _number(f"{where}.shear_modulus", spec["shear_modulus"], 0, 1e12, low_open=True),
                    _poisson(f"{where}.poisson_ratio", spec.get("poisson_ratio", 0.33)),
                    _bool(f"{where}.ligands", spec.get("ligands", False)),
                    _bool(f"{where}.deformable", spec.get("deformable", False)))
    if body.deformable and (body.fixed or body.shear_modulus is None):
        raise SceneError(f"{where}.deformable: a deformable body must be free and give its shear_modulus (Pa;"
                         " fixed cells are not deformed yet)")
    if body.ligands and not body.fixed:
        raise SceneError(f"{where}.ligands: ligands are modelled on fixed (adherent) cells only")
    if body.fixed and (any(body.force) or any(body.torque)):
        raise SceneError(f"{where}.force: the body is fixed; its load is what holds it (an output), so give"
                         " force and torque for free bodies only")
    return body


def _array(where, spec, folder) -> list:
    """An [[arrays]] entry: count = [nx, ny] bodies alike (the body keys but position) at origin
    + (i pitch_x, j pitch_y, 0), named "<name> i j", sharing one mesh."""
    _table(where, spec, (BODY_KEYS - {"position"}) | ARRAY_KEYS, ("mesh", "count", "pitch", "origin"))
    count = spec["count"]
    if not isinstance(count, list) or len(count) != 2:
        raise SceneError(f"{where}.count: expected [nx, ny], got {count!r}")
    nx, ny = (_number(f"{where}.count[{k}]", c, 1, 4096, integer=True) for k, c in enumerate(count))
    pitch = _vector(f"{where}.pitch", spec["pitch"], 2)
    origin = _vector(f"{where}.origin", spec["origin"], 3)
    mesh = _mesh(f"{where}.mesh", spec["mesh"], folder)
    name = str(spec.get("name", where))
    return [_body(where, spec, mesh, f"{name} {i} {j}",
                  (origin[0] + i * pitch[0], origin[1] + j * pitch[1], origin[2]))
            for i in range(nx) for j in range(ny)]


def _poisson(where, value):
    value = _number(where, value, -1.0, 0.5)
    if value in (-1.0, 0.5):
        raise SceneError(f"{where}: {value:g} is outside the allowed range (-1, 0.5) (linear elasticity)")
    return value


def _adhesion(table, bodies, repulsion: Repulsion, dt_min: float, wall: bool) -> Adhesion:
    """The [adhesion] table and the bodies' keys as an Adhesion, checked by field name."""
    if not wall:
        raise SceneError("physics.adhesion: bonds form with ligands on the wall; it needs flow.wall = true")
    if "spring_constant" not in table:
        raise SceneError("adhesion.spring_constant: missing (N/m; thesis Table 4.1: 0.5-100 dyn/cm = 5e-4-0.1 N/m)")
    get = table.get
    if not any(b.adhesive and not b.fixed for b in bodies):
        raise SceneError("bodies: adhesion is on but no free body is adhesive (bodies.N.adhesive)")
    try:
        adhesion = Adhesion(
            [b.mesh for b in bodies], [b.fixed for b in bodies], adhesive=[b.adhesive for b in bodies],
            receptor_density=_number("adhesion.receptor_density", get("receptor_density", 20e12), 0, 1e18,
                                     low_open=True),
            ligand_density=(None if "ligand_density" not in table else
                            _number("adhesion.ligand_density", table["ligand_density"], 0, 1e18, low_open=True)),
            spring_constant=_number("adhesion.spring_constant", table["spring_constant"], 0, 1e3, low_open=True),
            equilibrium_length=_number("adhesion.equilibrium_length", get("equilibrium_length", 30e-9), 0, 1e-6),
            off_rate=_number("adhesion.off_rate", get("off_rate", 2.4), 0, 1e9),
            reactive_compliance=_number("adhesion.reactive_compliance", get("reactive_compliance", 0.39e-10), 0, 1e-8),
            on_rate=_number("adhesion.on_rate", get("on_rate", 365.0), 0, 1e9),
            temperature=_number("adhesion.temperature", get("temperature", 310.0), 0, 1e4, low_open=True),
            max_bonds=_number("adhesion.max_bonds", get("max_bonds", 100), 1, 1e5, integer=True),
            compression=_bool("adhesion.compression", get("compression", False)),
            seed=_number("adhesion.seed", get("seed", 0), 0, 2**31 - 1, integer=True),
            roughness=_number("adhesion.roughness", get("roughness", repulsion.cell_roughness), 0, 1e-5),
            ligand_layer=_number("adhesion.ligand_layer", get("ligand_layer", repulsion.wall_roughness), 0, 1e-5),
            kinetics_fraction=_number("adhesion.kinetics_fraction", get("kinetics_fraction", 0.1), 0, 1, low_open=True),
            shear_modulus=[b.shear_modulus for b in bodies], poisson_ratio=[b.poisson_ratio for b in bodies],
            ligand_bodies=[b.ligands for b in bodies],
            cell_ligand_layer=_number("adhesion.cell_ligand_layer", get("cell_ligand_layer", repulsion.cell_roughness),
                                      0, 1e-5))
    except ValueError as err:
        raise SceneError(f"adhesion: {err}") from err
    # the step is bounded by the kinetics, k dt <= kinetics_fraction; dt_min must allow it
    for name, rate in (("on_rate", adhesion.fastest_formation), ("off_rate", adhesion.off_rate)):
        if rate * dt_min > adhesion.kinetics_fraction:
            raise SceneError(f"time.dt_min: {dt_min:g} s is too long for the bond kinetics ({name}: k dt ="
                             f" {rate * dt_min:.3g} > kinetics_fraction {adhesion.kinetics_fraction:g}); the"
                             f" allowed range is dt_min <= {adhesion.kinetics_fraction / rate:.3g} s")
    return adhesion


def _choice(where, value, allowed):
    if value not in allowed:
        raise SceneError(f"{where}: {value!r} is not one of {', '.join(repr(a) for a in allowed)}")
    return value


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
    try:
        check_placement(scene.initial_bodies(), scene.model.flow.wall)
    except PlacementError as err:
        raise SceneError(f"{path}: initial placement: {err}") from err
    repulsion = scene.model.interaction(Repulsion.name)
    if repulsion is not None:
        _check_roughness(scene, repulsion)
    return scene


def _check_roughness(scene: Scene, rep: Repulsion):
    """With repulsion on, the roughness layers of a free body must not start in contact
    (thesis eq. 3.1 diverges there)."""
    contacts = Contacts(scene.initial_bodies(), scene.model.outer_radii, scene.model.flow.wall, GapFinder())
    layers = rep.cell_roughness + max(rep.cell_roughness, rep.wall_roughness)  # the thickest pair
    for gap in contacts.within(2.0 * layers):
        if rep.separation(gap.distance, gap.other == WALL) <= 0:
            other = "the wall" if gap.other == WALL else f"bodies.{gap.other}"
            needed = rep.cell_roughness + (rep.wall_roughness if gap.other == WALL else rep.cell_roughness)
            raise SceneError(f"bodies.{gap.body}.position: its roughness layer touches that of {other} (gap"
                             f" {gap.distance:.4g} m; with repulsion on the gap must exceed {needed:.4g} m)")
