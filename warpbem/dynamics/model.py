"""The static part of a scene (DESIGN.md §3): meshes, which bodies are fixed, the flow, the
interactions that are switched on, solver and stepping options. Validated when made (each
interaction checked against the bodies) and frozen; the ``State`` holds what changes. The model
is the one source of the meshes, fixed flags and flow: interactions are configurations that
read them when bound to it (``forces/interaction.py``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from ..forces.adhesion import Adhesion
from ..forces.interaction import BoundInteraction, Interaction
from ..forces.repulsion import Repulsion
from ..hydro.frozen import FrozenArraySolver
from ..hydro.mobility import MobilitySolver
from ..hydro.options import TIME_STEPPING_DENSITY_ORDER, Flow, SolverOptions
from ..options import OptionError, option, validate
from ..surfaces.body import Body
from ..surfaces.gaps import outer_radius
from ..surfaces.mesh import Mesh
from .integrate import DEFAULT_SCHEME, SCHEMES
from .state import State


def build_solver(options: SolverOptions, flow: Flow, device, fixed_cells: int = 0,
                 unknowns: int | None = None) -> MobilitySolver | FrozenArraySolver:
    """The mobility solver of a model's ``options`` (resolved for time stepping) and ``flow``,
    with the near-far split of frozen adherent arrays (``hydro/frozen.py``) where the options
    take it for ``fixed_cells`` fixed cells (``SolverOptions.splits_near_far``). Without the
    split the operator's mode is decided here from ``unknowns`` (``Model.unknowns``) if given;
    with it, at the first solve of the near cells, which are fewer."""
    options = options.resolved(time_stepping=True)
    if options.splits_near_far(fixed_cells):
        return FrozenArraySolver(MobilitySolver(flow.shear_rate, flow.viscosity, flow.wall, device, options),
                                 options.near_far_cutoff)
    return MobilitySolver(flow.shear_rate, flow.viscosity, flow.wall, device, options, unknowns=unknowns)


def context_defaults(interactions: tuple, solver: SolverOptions) -> tuple[tuple, SolverOptions]:
    """Every default that depends on what else a model switches on, resolved in this one place
    (a scene file and a script building the same model get the same settings): the solver's
    time-stepping defaults and, with bonds, its snapshot lattice (``SolverOptions.resolved``);
    the bonds' layers from the model's repulsion roughness (``Adhesion.repulsion``)."""
    repulsion = next((x for x in interactions if isinstance(x, Repulsion)), None)
    bonds = any(isinstance(x, Adhesion) for x in interactions)
    if repulsion is not None:
        interactions = tuple(replace(x, repulsion=repulsion) if isinstance(x, Adhesion) else x for x in interactions)
    return interactions, solver.resolved(time_stepping=True, bonds=bonds)


DT_MIN = 1e-5  # s: the shortest step by default (thesis ch. 3.3: 1e-4 to 1e-5 s), or dt_max if shorter


@dataclass(frozen=True)
class StepPolicy:
    """Adaptive step: dt = dt_max far from contact, shrinking in proportion to the smallest gap
    below ``contact_gap`` (m) down to dt_min (thesis ch. 3.3: 1e-4 to 1e-5 s).

    Examples
    --------
    >>> import warpbem as wb
    >>> policy = wb.StepPolicy(dt_max=1e-4, contact_gap=0.5e-6)
    >>> policy.dt_min, policy.dt(0.25e-6)    # s: the default shortest step; the step at a 250 nm gap
    (1e-05, 5e-05)
    """

    dt_max: float = option(1e-4, "the step far from contact", "s", low=0.0, low_open=True)
    dt_min: float | None = option(None, "the shortest step, near contact (and of retries). Default: 1e-5 or dt_max"
                                  " if shorter", "s", kind=float, low=0.0, low_open=True)
    contact_gap: float = option(0.5e-6, "the step shrinks in proportion to the smallest gap below this", "m",
                                low=0.0, low_open=True)

    def __post_init__(self):
        validate(self)
        if self.dt_min is None:
            object.__setattr__(self, "dt_min", min(DT_MIN, self.dt_max))
        if self.dt_min > self.dt_max:
            raise OptionError(f"dt_min: {self.dt_min:g} is outside the allowed range (0, {self.dt_max:g}] (at most"
                              " dt_max)")

    def dt(self, gap: float) -> float:
        return float(np.clip(self.dt_max * gap / self.contact_gap, self.dt_min, self.dt_max))

    @staticmethod
    def landing(planned: float, remaining: float) -> float:
        """The step towards a time ``remaining`` (s) ahead (a frame time or the end): the whole
        remainder if one planned step reaches it, else the remainder split in equal steps no
        longer than ``planned``, so the stepping lands on it without a sliver of a last step."""
        if not math.isfinite(remaining):
            return planned
        if remaining <= planned * (1 + 1e-9):
            return remaining
        return remaining / math.ceil(remaining / planned - 1e-9)


def density_unknowns(meshes, density_order: int) -> int:
    """The unknowns of a mobility problem of ``meshes`` before contact refinement: 3 per density
    point, density_order^2 of them per element (``hydro/geometry.py``)."""
    return 3 * density_order**2 * sum(len(m.elements) for m in meshes)


@dataclass(frozen=True)
class Model:
    """Bodies (``meshes`` in metres about their reference points, ``fixed`` flags, ``names``),
    the ``flow``, the ``interactions`` switched on (``forces``: Gravity, ExternalLoads,
    Repulsion, Adhesion, Deformation; configurations, each checked against the bodies here), the
    solver options, the step policy and the scheme ("euler" or "heun"). The defaults that depend
    on what is switched on are resolved here (``context_defaults``), for scenes and scripts alike.

    Examples
    --------
    >>> import warpbem as wb
    >>> cell = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> model = wb.Model([cell, cell], [False, True], wb.Flow(shear_rate=100.0),
    ...                  interactions=[wb.Gravity([1070.0, 1070.0]), wb.Repulsion()], names=["free", "adherent"])
    >>> model.n_bodies, model.solver.density_order, model.solver.reuse_tolerance
    (2, 1, 0.0)

    With bonds the mobility is reused across steps on a 2 nm lattice, as in a scene file:

    >>> bonds = wb.Adhesion(wb.BondOptions(spring_constant=5e-4))
    >>> wb.Model([cell], [False], interactions=[wb.Repulsion(), bonds]).solver.reuse_tolerance
    2e-09
    """

    meshes: tuple
    fixed: tuple
    flow: Flow = Flow()
    interactions: tuple = ()
    solver: SolverOptions = SolverOptions()
    policy: StepPolicy = StepPolicy()
    scheme: str = DEFAULT_SCHEME
    names: tuple = ()

    def __post_init__(self):
        meshes, fixed = tuple(self.meshes), tuple(bool(f) for f in self.fixed)
        if not meshes or not all(isinstance(m, Mesh) for m in meshes):
            raise ValueError("a model needs at least one mesh, each a warpbem.mesh.Mesh")
        if len(fixed) != len(meshes):
            raise ValueError(f"fixed must have one flag per mesh ({len(meshes)}), got {len(fixed)}")
        names = tuple(self.names) or tuple(f"body{i}" for i in range(len(meshes)))
        if len(names) != len(meshes):
            raise ValueError(f"names must have one name per mesh ({len(meshes)}), got {len(names)}")
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme must be one of {SCHEMES}, got {self.scheme!r}")
        interactions = tuple(self.interactions)
        for x in interactions:
            if not isinstance(x, Interaction):
                raise TypeError(f"interactions must be warpbem.forces Interaction objects, got {type(x).__name__}")
        seen = [x.name for x in interactions]
        if len(set(seen)) != len(seen):
            raise ValueError(f"interaction names must be unique, got {seen}")
        interactions, solver = context_defaults(interactions, self.solver)
        for name, value in (("meshes", meshes), ("fixed", fixed), ("names", names), ("interactions", interactions),
                            ("solver", solver)):
            object.__setattr__(self, name, value)
        for x in interactions:  # e.g. one density per body, ligands on fixed bodies only
            x.check(self)

    @property
    def n_bodies(self) -> int:
        return len(self.meshes)

    @property
    def unknowns(self) -> int:
        """The unknowns of the largest mobility problem the time stepping solves, before contact
        refinement: 3 per density point (with an accuracy target, which chooses the density per
        solve, at the time-stepping default's) of every body, or with grand_mobility = "pairs" of
        the two largest cells (the pairs never solve the whole system: a patch of 256 cells would
        otherwise solve its pair snapshots on the treecode its whole system would need)."""
        meshes = sorted(self.meshes, key=lambda m: len(m.elements))
        if self.solver.grand_mobility == "pairs":
            meshes = meshes[-2:]
        return density_unknowns(meshes, self.solver.density_order or TIME_STEPPING_DENSITY_ORDER)

    @cached_property
    def fixed_mask(self) -> np.ndarray:
        mask = np.array(self.fixed, dtype=bool)
        mask.setflags(write=False)
        return mask

    @cached_property
    def outer_radii(self) -> np.ndarray:
        return np.array([outer_radius(m) for m in self.meshes])

    def interaction(self, name: str) -> Interaction | None:
        """The interaction called ``name`` (its configuration), or None if it is not switched on."""
        return next((x for x in self.interactions if x.name == name), None)

    @cached_property
    def bound_interactions(self) -> tuple:
        """Each interaction bound to this model without a device (``Interaction.bound``): the
        host view of what it derives from the meshes, fixed flags and flow (receptor tips, the
        weights, the state's layout), which this model's own methods and the frames read. A
        ``Simulator`` steps with its own binding, with device data (forces/interaction.py)."""
        return tuple(x.bound(self) for x in self.interactions)

    def bound(self, name: str) -> BoundInteraction | None:
        """The host view (``bound_interactions``) of the interaction called ``name``, or None."""
        return next((x for x in self.bound_interactions if x.name == name), None)

    def bodies(self, state: State, contact: bool = False) -> list[Body]:
        """The bodies of a state; ``contact``: with the shapes their gaps are measured on
        (``Interaction.body_meshes``), which differ from their surfaces only for deformable cells."""
        if len(state.positions) != self.n_bodies:
            raise ValueError(f"the state has {len(state.positions)} bodies, the model {self.n_bodies}")
        meshes, slip = list(self.meshes), [None] * self.n_bodies
        for x in self.bound_interactions:  # deformable cells: the shapes of this state, their surfaces' motion
            if x.shapes_bodies and x.name in state.parts:
                meshes = x.body_meshes(state.parts[x.name], meshes, contact)
                slip = x.surface_velocities(state.parts[x.name], slip)
        bodies = [Body(m, position=p, orientation=q, fixed=f, name=n)
                  for m, p, q, f, n in zip(meshes, state.positions, state.orientations, self.fixed, self.names)]
        return [b if v is None else replace(b, surface_velocity=v @ b.rotation().T) for b, v in zip(bodies, slip)]

    @property
    def shapes_bodies(self) -> bool:
        return any(x.shapes_bodies for x in self.interactions)

    def initial_state(self, positions, orientations=None, time: float = 0.0) -> State:
        """The state at ``time`` with the bodies placed; each interaction's own part at its start."""
        positions = np.asarray(positions, dtype=float)
        if orientations is None:
            orientations = np.tile([1.0, 0.0, 0.0, 0.0], (len(positions), 1))
        start = State(time, positions, orientations)
        bodies = self.bodies(start)
        parts = {x.name: x.initial_state(bodies) for x in self.bound_interactions if x.state_columns()}
        return State(time, positions, orientations, parts=parts)
