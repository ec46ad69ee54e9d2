"""Declarative scenes (TOML), validated before any work: every problem is reported with the
field's dotted name and the allowed values or range. SI units, like the API.

Each table is read through the declaration of the options it sets (``warpbem/options.py``):
``[flow]`` and ``[solver]`` (``hydro/options.py``), ``[physics]``, ``[time]`` (``RunSettings`` and
the ``StepPolicy``), ``[repulsion]``, ``[adhesion]`` (``BondOptions``), ``[deformation]``,
``[[bodies]]`` with ``[bodies.mesh]``, and ``[[arrays]]`` (a grid of alike bodies listed after the
[[bodies]]). Every key with its unit, default, range and meaning: ``docs/scene-reference.md``,
generated from those declarations (``warpbem/app/reference.py``).

``[sweep.AXIS]`` tables give the cases of ``warpbem sweep``; ``--set key=value`` overrides use
the dotted names, e.g. ``flow.shear_rate=80`` or ``bodies.0.position=[0,0,7.75e-6]``.
"""

from __future__ import annotations

import ast
import copy
import dataclasses
import hashlib
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units
from ..dynamics.integrate import DEFAULT_SCHEME, SCHEMES
from ..dynamics.model import Flow, Model, SolverOptions, StepPolicy
from ..dynamics.state import State
from ..elastic.deformable import Deformation, DeformationOptions
from ..forces.adhesion import Adhesion
from ..forces.bond_model import BondOptions
from ..forces.external import FLUID_DENSITY, STANDARD_GRAVITY, ExternalLoads, Gravity
from ..forces.repulsion import Repulsion
from ..options import (OptionError, check_keys, check_plausible, declared, from_table, option, plausible_magnitudes,
                       validate)
from ..surfaces import mesh as meshes
from ..surfaces.body import Body
from ..surfaces.gaps import WALL, Contacts, GapFinder
from ..surfaces.placement import PlacementError, body_label, check_placement


MESH_SHAPES = ("sphere", "spheroid", "file")

class SceneError(ValueError):
    """A scene that cannot run; the message names the field."""


def _options(cls, table, where, **given):
    """A declared options dataclass read from a scene table (``warpbem.options.from_table``)."""
    try:
        return from_table(cls, table, where, **given)
    except OptionError as err:
        raise SceneError(str(err)) from err


def _table(where, value, allowed, required=()):
    try:
        return check_keys(where, value, allowed, required)
    except OptionError as err:
        raise SceneError(str(err)) from err


@dataclass(frozen=True)
class Physics:
    """What a scene switches on (model no more than it needs)."""

    gravity: bool = option(False, "gravity and buoyancy on the free bodies (body density against fluid_density)")
    fluid_density: float = option(FLUID_DENSITY, "density of the fluid, for buoyancy", "kg/m^3", low=100.0, high=1e5)
    repulsion: bool = option(False, "electrostatic repulsion of thesis eq. 3.1 ([repulsion])")
    adhesion: bool = option(False, "receptor-ligand bonds of thesis ch. 4 ([adhesion]; needs flow.wall)")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class RunSettings:
    """How long a scene runs and which states become frames (the [time] table with the
    ``StepPolicy``'s keys).

    Examples
    --------
    >>> import warpbem as wb
    >>> wb.RunSettings(end=0.01).frame_every, wb.RunSettings(end=0.01, frame_interval=1e-3).frame_every
    (1, None)
    """

    end: float | None = option(None, "simulated time to run to. Required", "s", kind=float, low=0.0, high=1e6,
                               low_open=True)
    scheme: str = option(DEFAULT_SCHEME, "time integrator", choices=SCHEMES)
    frame_every: int | None = option(None, "a frame every this many steps. Default: 1, unless frame_interval is"
                                     " given", kind=int, low=1, high=1e9)
    frame_interval: float | None = option(None, "a frame every this simulated time, the steps landing on the frame"
                                          " times (not with frame_every)", "s", kind=float, low=0.0, high=1e6,
                                          low_open=True)

    def __post_init__(self):
        validate(self)
        if self.frame_every is not None and self.frame_interval is not None:
            raise OptionError("frame_interval: give frames by steps (frame_every) or by time (frame_interval), not"
                              " both")
        if self.frame_interval is not None and self.frame_interval > self.end:
            raise OptionError(f"frame_interval: {self.frame_interval:g} is outside the allowed range (0,"
                              f" {self.end:g}] (at most end)")
        if self.frame_interval is None and self.frame_every is None:
            object.__setattr__(self, "frame_every", 1)


@dataclass(frozen=True)
class MeshOptions:
    """A body's mesh ([bodies.mesh]): a library shape or a QUAD9 mesh file."""

    shape: str = option("sphere", "the mesh: a cube-sphere, a spheroid (axis z) or a file", choices=MESH_SHAPES)
    radius: float | None = option(None, "radius (sphere; spheroid: equatorial). Required for a sphere or spheroid",
                                  "m", kind=float, low=0.0, low_open=True, plausible=units.PLAUSIBLE_SIZE)
    subdivisions: int = option(4, "k: 6 k^2 QUAD9 elements (k = 4: 96)", low=1, high=32)
    aspect_ratio: float | None = option(None, "spheroid's polar over equatorial radius (<1 oblate). Required for a"
                                        " spheroid", kind=float, low=0.05, high=20.0)
    pole_grading: float = option(1.0, "sphere: elements crowded towards -z by this ratio (1: uniform)", low=1.0,
                                 high=100.0)
    path: str | None = option(None, "QUAD9 mesh file, relative to the scene file (shape = 'file')", kind=str)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class BodySpec:
    """One [[bodies]] entry (or a member of an [[arrays]] entry), validated, SI; ``mesh`` built
    from its [bodies.mesh] table."""

    position: tuple | None = option(None, "reference point (the mesh's origin). Required", "m", kind=float,
                                    length=3, plausible=units.PLAUSIBLE_POSITION)
    name: str | None = option(None, "name in outputs. Default: body<index> (arrays: '<name> i j')", kind=str)
    orientation: tuple = option((1.0, 0.0, 0.0, 0.0), "unit quaternion (w, x, y, z) of the body frame",
                                kind=float, length=4)
    fixed: bool = option(False, "held at rest (an adherent cell): its holding load is an output")
    density: float = option(FLUID_DENSITY, "density (gravity)", "kg/m^3", low=100.0, high=1e5)
    force: tuple = option((0.0, 0.0, 0.0), "external force on a free body", "N", kind=float, length=3,
                          plausible=units.PLAUSIBLE_FORCE)
    torque: tuple = option((0.0, 0.0, 0.0), "external torque on a free body, about its reference point", "N m",
                           kind=float, length=3, plausible=units.PLAUSIBLE_TORQUE)
    adhesive: bool = option(True, "a free body forms bonds (with physics.adhesion)")
    shear_modulus: float | None = option(None, "shear modulus G: the Hertz patch, and the deformation of a"
                                         " deformable body. Default: rigid", "Pa", kind=float, low=0.0, high=1e12,
                                         low_open=True)
    poisson_ratio: float = option(0.33, "Poisson ratio nu", low=-1.0, high=0.5, low_open=True, high_open=True)
    ligands: bool = option(False, "a fixed body carries ligands free cells can bind to")
    deformable: bool = option(False, "a free body deforms as a linear elastic solid ([deformation])")
    mesh: meshes.Mesh | None = None  # built from [bodies.mesh]

    def __post_init__(self):
        validate(self)
        if self.position is None:
            raise OptionError("position: missing (m)")
        if self.deformable and (self.fixed or self.shear_modulus is None):
            raise OptionError("deformable: a deformable body must be free and give its shear_modulus (Pa; fixed"
                              " cells are not deformed yet)")
        if self.ligands and not self.fixed:
            raise OptionError("ligands: ligands are modelled on fixed (adherent) cells only")
        if self.fixed and (any(self.force) or any(self.torque)):
            raise OptionError("force: the body is fixed; its load is what holds it (an output), so give force and"
                              " torque for free bodies only")


@dataclass(frozen=True)
class ArrayOptions:
    """An [[arrays]] entry's grid: count = [nx, ny] alike bodies at origin + (i pitch_x, j pitch_y,
    0), with any [[bodies]] key but position."""

    count: tuple | None = option(None, "bodies along x and y. Required", kind=int, length=2, low=1, high=4096)
    pitch: tuple | None = option(None, "spacing along x and y. Required", "m", kind=float, length=2,
                                 plausible=units.PLAUSIBLE_POSITION)
    origin: tuple | None = option(None, "position of body (0, 0). Required", "m", kind=float, length=3,
                                  plausible=units.PLAUSIBLE_POSITION)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class Scene:
    """What a run needs: the ``model``, the start placement of its ``bodies`` (each with its
    ``mesh``, ``position``, ``orientation`` and ``fixed`` flag), the run settings (end time,
    frames every ``frame_every`` steps or every ``frame_interval`` seconds) and the sweep axes.
    Read from a scene file by ``load_scene``, or built in a script by ``Scene.of``; either way
    ``warpbem.run`` runs it. ``raw``: the scene table it was read from (None when built in
    Python); ``table()`` is what the run file stores.

    Examples
    --------
    >>> import warpbem as wb
    >>> model = wb.Model([wb.mesh.sphere(radius=5e-6, subdivisions=2)], [False], wb.Flow(shear_rate=100.0))
    >>> scene = wb.Scene.of(model, [[0.0, 0.0, 7e-6]], end=1e-3, frame_every=2)
    >>> scene.initial_state().positions.tolist(), scene.next_stop(0.0)
    ([[0.0, 0.0, 7e-06]], 0.001)
    """

    raw: dict | None
    bodies: tuple  # BodySpec per body (a scene file) or Body (Scene.of)
    model: Model
    end: float
    frame_every: int | None
    frame_interval: float | None
    sweep: dict  # {axis: {label: [key=value overrides]}}, the cases ``warpbem sweep`` runs
    folder: Path | None = None  # a scene file's folder: its mesh files' paths are relative to it

    @classmethod
    def of(cls, model: Model, positions, orientations=None, *, end: float, frame_every: int | None = None,
           frame_interval: float | None = None) -> "Scene":
        """The scene of a ``model`` built in Python, its bodies starting at ``positions`` ((n, 3),
        m) with ``orientations`` ((n, 4) unit quaternions w, x, y, z; default: identity), run to
        ``end`` (s) with a frame every ``frame_every`` steps (default 1) or every
        ``frame_interval`` s. Checked as a scene file is: the run settings' ranges, the bodies'
        placement (no overlap, above the wall) and, with repulsion, their roughness layers apart.

        Examples
        --------
        >>> import warpbem as wb
        >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
        >>> model = wb.Model([cell], [False], wb.Flow(shear_rate=0.0), interactions=[wb.Gravity([1070.0])])
        >>> scene = wb.Scene.of(model, [[0.0, 0.0, 7e-6]], end=1e-3, frame_interval=5e-4)
        >>> scene.end, len(scene.bodies)
        (0.001, 1)
        """
        positions = np.asarray(positions, dtype=float)
        if positions.shape != (model.n_bodies, 3):
            raise ValueError(f"positions: expected ({model.n_bodies}, 3) (one per body of the model, m), got"
                             f" {positions.shape}")
        orientations = (np.tile([1.0, 0.0, 0.0, 0.0], (model.n_bodies, 1)) if orientations is None
                        else np.asarray(orientations, dtype=float))
        run = RunSettings(end=end, scheme=model.scheme, frame_every=frame_every, frame_interval=frame_interval)
        bodies = tuple(Body(m, position=tuple(p), orientation=tuple(q), fixed=f, name=name)
                       for m, p, q, f, name in zip(model.meshes, positions, orientations, model.fixed, model.names))
        scene = cls(raw=None, bodies=bodies, model=model, end=run.end, frame_every=run.frame_every,
                    frame_interval=run.frame_interval, sweep={})
        try:
            return _checked(scene)
        except SceneError as err:
            raise PlacementError(str(err)) from err

    def table(self) -> dict:
        """What a run file stores of this scene (its ``scene`` attribute): the scene table it was
        read from, or for a scene built in Python its model, placement and run settings as plain
        values (each mesh by its size and a digest of its nodes and elements)."""
        if self.raw is not None:
            return self.raw
        return {"built_in": "python (warpbem.Scene.of)", "model": plain(self.model),
                "bodies": [{"position": list(b.position), "orientation": list(b.orientation)} for b in self.bodies],
                "time": {"end": self.end, "frame_every": self.frame_every, "frame_interval": self.frame_interval}}

    def initial_bodies(self) -> list[Body]:
        return [Body(b.mesh, position=b.position, orientation=b.orientation, fixed=b.fixed, name=b.name)
                for b in self.bodies]

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
    options = _options(MeshOptions, spec, where, required=("shape",))
    for key in ("radius", "aspect_ratio", "path"):
        needed = {"radius": ("sphere", "spheroid"), "aspect_ratio": ("spheroid",), "path": ("file",)}[key]
        if options.shape in needed and getattr(options, key) is None:
            raise SceneError(f"{where}.{key}: missing (needed by shape = {options.shape!r})")
    if "pole_grading" in spec and options.shape != "sphere":
        raise SceneError(f"{where}.pole_grading: only a sphere is graded (shape = 'sphere')")
    if options.shape == "sphere":
        return meshes.sphere(options.radius, options.subdivisions, pole_grading=options.pole_grading)
    if options.shape == "spheroid":
        return meshes.spheroid(options.radius, options.aspect_ratio, options.subdivisions)
    try:
        loaded = meshes.load(folder / options.path)
    except meshes.MeshError as err:
        raise SceneError(f"{where}.path: {err}") from err
    try:  # a mesh file in micrometres
        check_plausible(f"{where}.path", loaded.size(), "m", units.PLAUSIBLE_SIZE, "its size ")
    except OptionError as err:
        raise SceneError(str(err)) from err
    return loaded


POLICY_KEYS = {name for name, _, _ in declared(StepPolicy)}
TIME_KEYS = POLICY_KEYS | {name for name, _, _ in declared(RunSettings)}  # the [time] table


def parse(table: dict, folder: Path = Path(".")) -> Scene:
    """Validate a scene table (as read from TOML) and build the Scene; lengths, forces, the shear
    rate and the viscosity within their plausible magnitudes (``warpbem.units``: a value typed
    in another unit), unless the scene says ``any_scale = true``."""
    any_scale = table.get("any_scale", False) if isinstance(table, dict) else False
    if not isinstance(any_scale, bool):
        raise SceneError(f"any_scale: expected true or false, got {any_scale!r}")
    with plausible_magnitudes(not any_scale):
        return _parse(table, folder)


def _parse(table: dict, folder: Path) -> Scene:
    _table("scene", table, {"any_scale", "flow", "physics", "repulsion", "adhesion", "deformation", "time", "solver",
                           "bodies", "arrays", "sweep"},
           ("flow", "time"))
    sweep = _sweep_axes(table.get("sweep", {}))
    flow = _options(Flow, table["flow"], "flow", required=("shear_rate",))
    physics = _options(Physics, table.get("physics", {}), "physics")
    # validated even when switched off, so typos surface early
    deformation = _options(DeformationOptions, table.get("deformation", {}), "deformation")
    repulsion = _options(Repulsion, table.get("repulsion", {}), "repulsion")
    adhesion = _table("adhesion", table.get("adhesion", {}), {name for name, _, _ in declared(BondOptions)})
    time = _table("time", table["time"], TIME_KEYS, ("end",))
    run = _options(RunSettings, {k: v for k, v in time.items() if k not in POLICY_KEYS}, "time")
    policy = _options(StepPolicy, {k: v for k, v in time.items() if k in POLICY_KEYS}, "time")
    solver = _table("solver", table.get("solver", {}), {name for name, _, _ in declared(SolverOptions)})
    bodies = []
    for i, spec in enumerate(_entries("bodies", table.get("bodies", []))):
        where = f"bodies.{i}"
        _table(where, spec, BODY_KEYS, ("mesh", "position"))
        bodies.append(_body(where, spec, _mesh(f"{where}.mesh", spec["mesh"], folder), f"body{i}"))
    for i, spec in enumerate(_entries("arrays", table.get("arrays", []))):
        bodies += _array(f"arrays.{i}", spec, folder)
    if not bodies:
        raise SceneError("bodies: expected at least one [[bodies]] or [[arrays]] entry")
    # model no more than the scene needs: only the interactions switched on are built
    interactions = []
    if physics.gravity:
        interactions.append(Gravity([b.density for b in bodies], physics.fluid_density, STANDARD_GRAVITY))
    if any(any(b.force) or any(b.torque) for b in bodies):
        interactions.append(ExternalLoads([b.force for b in bodies], [b.torque for b in bodies]))
    if physics.repulsion:
        interactions.append(repulsion)
    if physics.adhesion:
        interactions.append(_adhesion(adhesion, bodies, flow.wall))
    solver_options = _options(SolverOptions, solver, "solver")  # its context defaults: the Model's
    if any(b.deformable for b in bodies):
        interactions.append(Deformation([b.deformable for b in bodies], [b.shear_modulus for b in bodies],
                                        [b.poisson_ratio for b in bodies], deformation))
    try:
        model = Model(meshes=[b.mesh for b in bodies], fixed=[b.fixed for b in bodies], names=[b.name for b in bodies],
                      interactions=interactions, flow=flow, solver=solver_options, policy=policy, scheme=run.scheme)
    except ValueError as err:  # an interaction that does not fit the bodies or the step (Interaction.check)
        field = str(err).split(":", 1)[0]
        raise SceneError(f"{MODEL_FIELDS[field]}: {str(err).split(':', 1)[1].strip()}" if field in MODEL_FIELDS
                         else f"bodies: {err}") from err
    return Scene(raw=copy.deepcopy(table), bodies=tuple(bodies), model=model, end=run.end,
                 frame_every=run.frame_every, frame_interval=run.frame_interval, sweep=sweep, folder=folder)


# the fields the Model's own checks name (its context defaults, Interaction.check), as a scene names them
MODEL_FIELDS = {**{name: f"solver.{name}" for name, _, _ in declared(SolverOptions)},
                **{name: f"time.{name}" for name in POLICY_KEYS}}
BODY_KEYS = {name for name, _, _ in declared(BodySpec)} | {"mesh"}
ARRAY_KEYS = {name for name, _, _ in declared(ArrayOptions)}


def _entries(where, value) -> list:
    if not isinstance(value, list):
        raise SceneError(f"{where}: expected a list of tables ([[{where}]] entries), got {value!r}")
    return value


def _body(where, spec, mesh, name, position=None) -> BodySpec:
    """One body's keys (BODY_KEYS, checked by the caller) as a BodySpec, named ``name`` unless
    it names itself; ``position`` given for the members of an array."""
    keys = {k: v for k, v in spec.items() if k not in ("mesh", "name")}
    given = {"name": str(spec.get("name", name)), "mesh": mesh}
    if position is not None:
        given["position"] = position
    return _options(BodySpec, keys, where, **given)


def _array(where, spec, folder) -> list:
    """An [[arrays]] entry (``ArrayOptions``): alike bodies named "<name> i j", sharing one mesh."""
    _table(where, spec, (BODY_KEYS - {"position"}) | ARRAY_KEYS, ("mesh", "count", "pitch", "origin"))
    grid = _options(ArrayOptions, {k: spec[k] for k in ARRAY_KEYS}, where)
    (nx, ny), pitch, origin = grid.count, grid.pitch, grid.origin
    mesh = _mesh(f"{where}.mesh", spec["mesh"], folder)
    name = str(spec.get("name", where))
    body_keys = {k: v for k, v in spec.items() if k not in ARRAY_KEYS | {"name"}}
    return [_body(where, body_keys, mesh, f"{name} {i} {j}", (origin[0] + i * pitch[0], origin[1] + j * pitch[1],
                                                             origin[2]))
            for i in range(nx) for j in range(ny)]


def _adhesion(table, bodies, wall: bool) -> Adhesion:
    """The [adhesion] table and the bodies' keys as an Adhesion, checked by field name (its layers
    and the step's bound by the kinetics: the Model's, ``context_defaults`` and ``Adhesion.check``)."""
    if not wall:
        raise SceneError("physics.adhesion: bonds form with ligands on the wall; it needs flow.wall = true")
    if not any(b.adhesive and not b.fixed for b in bodies):
        raise SceneError("bodies: adhesion is on but no free body is adhesive (bodies.N.adhesive)")
    return Adhesion(_options(BondOptions, table, "adhesion"), adhesive=[b.adhesive for b in bodies],
                    shear_modulus=[b.shear_modulus for b in bodies], poisson_ratio=[b.poisson_ratio for b in bodies],
                    ligand_bodies=[b.ligands for b in bodies])


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
    """Read a scene file (TOML), apply ``overrides`` ("key=value" strings with dotted keys, as
    ``warpbem run --set``) and validate it: the Scene holds its Model, built by the same public
    constructors a script uses, the bodies' start and the run settings. Also checks that the
    bodies do not overlap. ``warpbem.load_scene``.

    Examples
    --------
    >>> import warpbem as wb
    >>> from pathlib import Path
    >>> _ = Path("settle.toml").write_text('''
    ... [flow]
    ... shear_rate = 0.0
    ... [physics]
    ... gravity = true
    ... [time]
    ... end = 0.01
    ... [[bodies]]
    ... name = "cell"
    ... position = [0.0, 0.0, 6.0e-6]
    ... density = 1070.0
    ... mesh = { shape = "sphere", radius = 5.0e-6, subdivisions = 2 }
    ... ''')
    >>> scene = wb.load_scene("settle.toml", ["time.end=2e-4"])
    >>> scene.model.names, scene.end, scene.model.interaction("gravity").densities.tolist()
    (('cell',), 0.0002, [1070.0])
    """
    path = Path(path)
    try:
        table = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as err:
        raise SceneError(f"{path}: cannot read the scene ({err})") from err
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{path}: not valid TOML ({err})") from err
    scene = parse(apply_overrides(table, overrides), path.parent)
    try:
        return _checked(scene)
    except PlacementError as err:
        raise SceneError(f"{path}: initial placement: {err}") from err


def _checked(scene: Scene) -> Scene:
    """``scene``, once its bodies are checked not to overlap (PlacementError) and, with repulsion
    on, not to start with their roughness layers in contact (SceneError)."""
    check_placement(scene.initial_bodies(), scene.model.flow.wall)
    repulsion = scene.model.interaction(Repulsion.name)
    if repulsion is not None:
        _check_roughness(scene, repulsion)
    return scene


def plain(value):
    """A configuration as JSON-ready values: dataclasses as {"type": name, field: value}, meshes by
    their size and a digest of their nodes and elements, arrays and tuples as lists."""
    if isinstance(value, meshes.Mesh):
        digest = hashlib.sha256(np.ascontiguousarray(value.nodes).tobytes()
                                + np.ascontiguousarray(value.elements).tobytes()).hexdigest()
        return {"elements": len(value.elements), "sha256": digest}
    if dataclasses.is_dataclass(value):
        return {"type": type(value).__name__,
                **{f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _check_roughness(scene: Scene, rep: Repulsion):
    """With repulsion on, the roughness layers of a free body must not start in contact
    (thesis eq. 3.1 diverges there)."""
    contacts = Contacts(scene.initial_bodies(), scene.model.outer_radii, scene.model.flow.wall, GapFinder())
    layers = rep.cell_roughness + max(rep.cell_roughness, rep.wall_roughness)  # the thickest pair
    for gap in contacts.within(2.0 * layers):
        if rep.separation(gap.distance, gap.other == WALL) <= 0:
            other = "the wall" if gap.other == WALL else f"bodies.{gap.other}{_named(scene, gap.other)}"
            needed = rep.cell_roughness + (rep.wall_roughness if gap.other == WALL else rep.cell_roughness)
            raise SceneError(f"bodies.{gap.body}.position{_named(scene, gap.body)}: its roughness layer touches that"
                             f" of {other} (gap {gap.distance:.4g} m; with repulsion on the gap must exceed"
                             f" {needed:.4g} m)")


def _named(scene: Scene, i: int) -> str:
    """Body ``i``'s own name for a message beside its scene key (" ('free cell')"); nothing for
    the default name."""
    name = scene.bodies[i].name
    return f" ({name!r})" if body_label(name, i) == repr(name) else ""
