"""The flow and the solver settings, declared once (``warpbem.options``): the mobility solve
(``mobility.py``), the traction (``traction.py``) and the interior elastic problem
(``elastic/interior.py``) take one ``SolverOptions``; the time step reads its snapshot and
near-far settings from the same object; scenes read both from ``[flow]`` and ``[solver]``.

Defaults that depend on the context are ``None`` and resolved by ``SolverOptions.resolved``:
the density order (2 for a solve, 1 for a time-stepped model: why in its doc), the contact
refinement by the density order, the GMRES tolerance by the precision, the snapshot lattice by
whether the model has bonds. A ``Model`` resolves them once, so that a scene file and a script
that build the same bodies and interactions get the same settings.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .. import units
from ..options import OptionError, option, validate
from .treecode import TreecodeOptions

OPERATOR_MODES = ("auto", "dense", "matrix_free", "treecode")
# contact refinement ratio by density order when none is given (surfaces/refinement.py: the
# ratio on the k = 4 sphere, scaled with the mesh): the Pareto chart's choice (docs/benchmarks.md,
# benchmarks/pareto.py)
DEFAULT_CONTACT_REFINEMENT = {1: 3.0, 2: 1.1, 3: 1.1}
# adaptive quadrature's near_factor by density order: a constant density's error hides the
# element integrals' from 2 (errors against the exact series unchanged to 3 digits from 3, k = 3
# to 8, h/a = 1.5 and 1.1); a bilinear one's does not
NEAR_FACTOR = {1: 2.0, 2: 3.0, 3: 3.0}
# Gauss points per direction on an element by density order when none is given: 2 x 2 reaches
# the seed's 3 x 3 accuracy with the constant density at 60 % of the cost (benchmarks/pareto.py)
# and serves the bilinear one; the biquadratic density needs 3 x 3 (two k = 4 spheres pushed
# together 0.05 radius apart, ratio 0.35: 7.2e-3 off the exact with 2 x 2, 1.7e-3 with 3 x 3; 0.02
# apart, ratio 0.25: 2.5e-2 and 6.7e-3; benchmarks/error_model.py's measured_pair at these settings)
QUADRATURE_ORDER = {1: 2, 2: 2, 3: 3}
# GMRES relative residual by precision when none is given: float32 products carry ~1e-7 of
# round-off, so 1e-8 is out of their reach (the stability map: 1e-6 converges down to gaps of
# 0.1 radius)
DEFAULT_TOLERANCE = {"float64": 1e-8, "float32": 1e-6}
# m: adherent cells within this gap (between bounding spheres) of a free cell are solved with it
# by the near-far split (frozen.py); the free cell's velocity then stays within 1.2e-4 of the full
# solve on an 8 x 8 array of domes (benchmarks/frozen.py, docs/benchmarks.md "Frozen adherent arrays"; 30 um:
# 3.5e-4, 20 um: 2e-3)
DEFAULT_CUTOFF = 40e-6
NEAR_FAR_SPLITS = ("auto", "on", "off")
GRAND_MOBILITIES = ("system", "pairs")
MANY_BODY_REMAINDERS = ("none", "coarse")
# m: the lateral lattice of the many-body remainder's snapshots (dynamics/many_body.py): nine cells
# of a 3 x 3 patch 25 um apart each moved at random within +-0.5 um (+-1 um) of their positions
# raised the remainder's error (the constant density's) from 1.2e-4 / 8.9e-4 (grand mobility /
# flow) to 1.5e-4 / 1.1e-3 (1.8e-4 / 1.3e-3; a script beside benchmarks/many_cells.py --parts
# accuracy); with the biquadratic density the 3 x 3 patch on this lattice errs by 2.2e-4 / 3.1e-4
DEFAULT_MANY_BODY_LATERAL = 1e-6
# m: the pair lattice at contact distance (dynamics/pairwise.py), interpolated bilinearly: 250 nm
# up to 1.32 contact distances (13.2 um between 5 um cells), 2 um at 25 um; two cells 12.5 um
# apart interpolate to 3.4e-4 of the grand mobility on a 500 nm lattice, 1.6e-3 on a 1 um one
# (benchmarks/many_cells.py --parts lattice)
DEFAULT_PAIR_LATERAL = 250e-9
# m: pairs of cells farther apart than this are left out (dynamics/pairwise.py). The flow's part of
# the coupling sums slowly over a patch (each pair's as r^-3, their number as r): on an 8 x 8 patch
# 25 um apart leaving out pairs beyond 50 / 100 / 150 um errs by 7.0e-2 / 1.3e-2 / 3.8e-3 in the
# flow's motion (benchmarks/many_cells.py --parts cutoff), so every pair of a patch up to 1 mm wide
# is kept
DEFAULT_PAIR_CUTOFF = 1e-3
# bytes: the on-disk store of lone and pair snapshots (dynamics/snapshot_store.py) is capped at this, the
# least recently used ones evicted beyond it: room for about 200 000 snapshots (their arrays are per cell,
# whatever the mesh: the 71 of 10 ms of scenes/rolling_patch_4x4.toml took 0.6 MB)
DEFAULT_SNAPSHOT_STORE_SIZE = 2e9
FAR_FIELDS = ("moments", "none")
CLOSE_PAIRS = ("lubrication", "lattice")
CLOSE_CLUSTERS = ("resistance", "none")
# pairs of cells farther apart than this many mean outer radii are far (dynamics/far_field.py):
# measured on two 5 um cells at the rolling height (benchmarks/many_cells.py --parts far): at 7 and
# 8 radii (35, 40 um) the pair errs by 4.4e-4 and 1.6e-4 of the grand mobility, most of it the second
# reflection on each cell's own block, which adds over the neighbours around a cell (4 diagonal
# ones 35.4 um apart in a patch 25 um apart)
NEAR_RADII = 8.0
SNAPSHOT_STORES = ("on", "off")
# fixed cells from which "auto" switches the near-far split on: per step on the crossing path
# (benchmarks/frozen.py steps --counts 1 2 3 4 5 --full; docs/figures/frozen_steps_notes.md) the
# split cost as much as the full solve up to 4 x 4 domes (2.11 against 2.12 s at 16) and 35-40 %
# less from 5 x 5 (2.26 against 3.40 s) in each of three runs; below, it would add its error
# (1e-4 at the 40 um cut-off) for no gain
NEAR_FAR_FIXED_CELLS = 25
# m: the snapshot lattice of a model with bonds when none is given (SolverOptions.reuse_tolerance):
# the bonds' stiff springs are taken implicitly with the cell's mobility, which then need not be
# solved again for each sub-nanometre move (benchmarks/adhesion.py, docs/adhesion.md)
BONDS_REUSE_TOLERANCE = 2e-9
# the density order of a solve, and of a time-stepped model (SolverOptions.density_order)
SOLVE_DENSITY_ORDER = 2
TIME_STEPPING_DENSITY_ORDER = 1


@dataclass(frozen=True)
class Flow:
    """Undisturbed flow u = shear_rate z e_x above the no-slip wall z = 0 (if ``wall``).

    Examples
    --------
    >>> import warpbem as wb
    >>> flow = wb.Flow(shear_rate=100.0)            # 1/s; plasma's viscosity by default
    >>> flow.viscosity, flow.wall
    (0.0012, True)
    >>> wb.Flow(shear_rate=100.0, viscosity=0.0)
    Traceback (most recent call last):
    ...
    warpbem.options.OptionError: viscosity: 0 is outside the allowed range (0, 1000]
    """

    shear_rate: float = option(0.0, "shear rate of the undisturbed flow u = shear_rate z e_x", "1/s",
                               low=-1e6, high=1e6, plausible=units.PLAUSIBLE_SHEAR_RATE)
    viscosity: float = option(1.2e-3, "fluid viscosity (plasma, thesis ch. 3-5: 1.2e-3)", "Pa s",
                              low=0.0, high=1e3, low_open=True, plausible=units.PLAUSIBLE_VISCOSITY)
    wall: bool = option(True, "a no-slip plane wall at z = 0 (Blake images; false: unbounded fluid)")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class SolverOptions:
    """Settings of the boundary-element solves and of how the time step reuses them.

    Examples
    --------
    The defaults left open (``None``) are resolved by the context: a solve takes the bilinear
    density and a contact refinement of 1.1, a time-stepped model the constant density and 3.0;
    the GMRES tolerance follows the precision. A value out of range is refused with its field:

    >>> import warpbem as wb
    >>> options = wb.SolverOptions(quadrature_order=3)
    >>> solve, stepping = options.resolved(), options.resolved(time_stepping=True)
    >>> solve.density_order, solve.contact_refinement, stepping.density_order, stepping.contact_refinement
    (2, 1.1, 1, 3.0)
    >>> wb.SolverOptions().resolved().tolerance, wb.SolverOptions(dtype="float32").resolved().tolerance
    (1e-08, 1e-06)
    >>> wb.SolverOptions(quadrature_order=0)
    Traceback (most recent call last):
    ...
    warpbem.options.OptionError: quadrature_order: 0 is outside the allowed range [1, 10]
    """

    quadrature_order: int | None = option(
        None, "Gauss points per direction on an element and on each adaptive sub-panel. Default by density"
        " order: 2 for 1 and 2 (2 x 2 reaches the seed's 3 x 3 accuracy at 60 % of the cost: benchmarks/pareto.py),"
        " 3 for 3", kind=int, low=1, high=10)
    adaptive_quadrature: bool = option(True, "subdivide nearly singular element integrals (near a collocation"
                                       " point or its wall image)")
    density_order: int | None = option(
        None, "double-layer density per element: 1 constant (the seed's), 2 bilinear, 3 biquadratic. Default: 2"
        " for a solve (solve_mobility, MobilitySolver: below the constant density's cost-accuracy curve from"
        " 0.01-0.05 s per solve, docs/benchmarks.md 'Accuracy per cost'); 1 in time-stepped models and scenes, whose"
        " deformable cells' traction and surface motion are per element (1 only) and whose published figures"
        " were measured with it", kind=int, low=1, high=3)
    contact_refinement: float | None = option(
        None, "split elements nearer than 1/ratio of their radius to the wall or another body (0: never); the ratio"
        " on the k = 4 sphere, scaled with the mesh. Default by density order: 3.0 for 1, 1.1 for 2 and 3",
        kind=float, low=0.0, high=20.0)
    refine_fixed_at_wall: bool = option(True, "refine fixed bodies for their own gap to the wall (false: a ~1 %"
                                        " effect on free cells in recruitment scenes at ~1/90 of the cost)")
    accuracy: float | None = option(
        None, "requested relative accuracy of the bodies' motion and loads: each solve picks the cheapest mesh"
        " subdivisions (library meshes: sphere, spheroid, adherent shapes), density order and contact refinement"
        " that reach it by the measured error model (hydro/accuracy.py, benchmarks/error_model.py) and reports"
        " its error estimate. With it, density_order may be given (the choice keeps it) and contact_refinement"
        " may not. None: the settings as given", kind=float, low=1e-6, high=0.5)
    tolerance: float | None = option(None, "GMRES relative residual. Default by dtype: 1e-8 for float64, 1e-6 for"
                                     " float32", kind=float, low=0.0, high=0.1, low_open=True)
    max_iterations: int = option(600, "GMRES iterations before a ConvergenceError", low=1, high=1e6)
    dtype: str = option("float64", "precision of the Warp kernels", choices=("float64", "float32"))
    operator: str = option("auto", "discrete form of the operator: dense, matrix_free (the direct sum), treecode,"
                           " or auto (dense while one matrix takes at most a quarter of the device's memory)",
                           choices=OPERATOR_MODES)
    precondition: bool = option(True, "block-Jacobi preconditioner (each body's own block, LU)")
    reuse_tolerance: float | None = option(None, "mobility snapshots reused across time steps on a lattice of this"
                                           " spacing in height (dynamics/hydrodynamics.py); 0 solves every state."
                                           f" Default: {BONDS_REUSE_TOLERANCE:g} in a model with bonds"
                                           " (benchmarks/adhesion.py), 0 otherwise", "m", kind=float,
                                           low=0.0, high=1e-6)
    reuse_lateral: float | None = option(None, "lateral lattice of the several-body snapshots. Default: 50 x"
                                         " reuse_tolerance", "m", kind=float, low=0.0, high=1e-5, low_open=True)
    reuse_interaction: float | None = option(None, "height lattice of the several-body snapshots, >= reuse_tolerance."
                                             " Default: 10 x reuse_tolerance", "m", kind=float, low=0.0, high=1e-6,
                                             low_open=True)
    grand_mobility: str = option("system", "several free cells' snapshots: 'system' (the whole system's, 6 n + 1"
                                 " solves of n cells) or 'pairs' (each cell's lone snapshot and the two-body"
                                 " snapshots of every pair within pair_cutoff, shared by pairs of the same offset and"
                                 " heights: a cost linear in the cells, for free spherical cells tens of"
                                 " micrometres apart, leaving out the three-body part: 9.3e-4 of the flow's motion"
                                 " in a line 25 um apart, 7.5e-3 in a 3 x 3 patch, 1.2e-2 in a 4 x 4 one;"
                                 " dynamics/pairwise.py, docs/many-cells.md)", choices=GRAND_MOBILITIES)
    many_body: str = option("none", "with grand_mobility = 'pairs', 'coarse' adds the part the pairs leave out (three"
                            " cells and more) from coarse cells (the k = 2 sphere, 24 elements, unrefined, with the"
                            " biquadratic density; the constant density beyond about 40 cells, where that system"
                            " is not dense): their whole system's solve minus their pairs, kept on a lattice of"
                            " many_body_lateral. 4 x 4 cells 25 um apart: 2.1e-4 / 3.8e-4 of the grand mobility /"
                            " flow's motion against the pairs' 1.7e-3 / 1.2e-2 (dynamics/many_body.py,"
                            " docs/many-cells.md). Cells near contact take close_clusters instead",
                            choices=MANY_BODY_REMAINDERS)
    many_body_lateral: float = option(DEFAULT_MANY_BODY_LATERAL, "with many_body = 'coarse', the lateral lattice of"
                                      " the cells' positions the remainder is solved at", "m", low=0.0, high=1e-4,
                                      low_open=True)
    pair_lateral: float = option(DEFAULT_PAIR_LATERAL, "with grand_mobility = 'pairs', the lateral lattice of the pair"
                                 " snapshots at contact distance, growing as (distance / contact)^(5/2) in steps of 2"
                                 " up to distance / 8; each pair interpolated bilinearly between its lattice points",
                                 "m", low=0.0, high=1e-5, low_open=True)
    close_pairs: str = option("lubrication", "with grand_mobility = 'pairs', two equal spherical cells less than half a"
                              " radius apart: 'lubrication' takes their pair snapshot from the exact two-sphere"
                              " resistance (Jeffrey & Onishi 1984) plus the wall's part on a coarse lattice of gaps"
                              " (0.1 radius x 2^(k/2)), their films added in resistance among more cells"
                              " (dynamics/close_pairs.py); 'lattice' from the pair lattice of pair_lateral, solving"
                              " the pair as it is where a lattice point is too near", choices=CLOSE_PAIRS)
    close_clusters: str | None = option(None, "with close_pairs = 'lubrication', three or more cells joined by close"
                                        " pairs: 'resistance' adds the part their pairs leave out (the middle cell"
                                        " screening the outer ones) in resistance, from the cluster solved on the"
                                        " k = 3 sphere with the biquadratic density less its pairs: three cells in a"
                                        " line 0.2 um apart 3.9e-4 / 5.9e-4 of the grand mobility / flow's motion"
                                        " against 1.5e-2 / 2.1e-2 without it (dynamics/close_clusters.py); 'none'"
                                        " leaves it out. Default: 'resistance' with many_body = 'none', else 'none'"
                                        " (the coarse remainder holds a three-body part of its own)",
                                        kind=str, choices=CLOSE_CLUSTERS)
    pair_cutoff: float = option(DEFAULT_PAIR_CUTOFF, "with grand_mobility = 'pairs', pairs of cells farther apart"
                                " along the wall than this do not interact", "m", low=0.0, high=1e-2)
    far_field: str = option("moments", "with grand_mobility = 'pairs', the pairs farther apart than near_radius:"
                            " 'moments' couples them through each cell's surface traction alone above the wall,"
                            " compressed to its moments to second order, with the wall's images (the first"
                            " reflection; dynamics/far_field.py), with no pair snapshot; 'none' takes every pair"
                            " within pair_cutoff from pair snapshots", choices=FAR_FIELDS)
    near_radius: float | None = option(None, "with far_field = 'moments', pairs farther apart along the wall than this"
                                       " are far. Default: NEAR_RADII x the mean outer radius of the two"
                                       f" ({NEAR_RADII:g}: 40 um between 5 um cells; docs/many-cells.md)", "m",
                                       kind=float, low=0.0, high=1e-2, low_open=True)
    snapshot_store: str = option("on", "keep the lone and pair snapshots on disk across runs: another seed, scene or"
                                 " resumed run of the same cells and settings reads them instead of solving them. In"
                                 " the folder WARPBEM_SNAPSHOT_STORE, else snapshots/ in the kernel cache's"
                                 " (.warp_cache or WARPBEM_CACHE); docs/adhesion.md", choices=SNAPSHOT_STORES)
    snapshot_store_size: float = option(DEFAULT_SNAPSHOT_STORE_SIZE, "the snapshot store's cap on disk: beyond it the"
                                        " least recently used snapshots are evicted", "B", low=1e6, high=1e13)
    near_far_split: str = option("auto", "time stepping: the adherent cells' background solved once, each solve"
                                 " holding the free cells and the adherent cells near them (hydro/frozen.py): on,"
                                 f" off, or auto: on with at least {NEAR_FAR_FIXED_CELLS} fixed cells"
                                 " (benchmarks/frozen.py)", choices=NEAR_FAR_SPLITS)
    near_far_cutoff: float = option(DEFAULT_CUTOFF, "with the split, adherent cells whose bounding sphere stays"
                                    " farther than this from every free cell's keep their background (docs/benchmarks.md 'Frozen"
                                    " adherent arrays': the error against it)", "m", low=0.0, high=1e-2)
    treecode: TreecodeOptions = TreecodeOptions()  # the far field's settings (API only, not a scene key)

    def __post_init__(self):
        validate(self)
        if self.many_body != "none" and self.grand_mobility != "pairs":
            raise OptionError(f"many_body: {self.many_body!r} corrects the pairs' grand mobility; it needs"
                              " grand_mobility = 'pairs' (the whole system's holds every cell already)")
        if self.close_clusters == "resistance" and self.many_body != "none":
            raise OptionError(f"close_clusters: 'resistance' with many_body = {self.many_body!r} would count the"
                              " clusters' three-body part twice; give one or the other")
        if self.accuracy is not None and self.contact_refinement is not None:
            raise OptionError("contact_refinement: the accuracy target chooses it; give one or the other")
        if self.accuracy is not None and self.quadrature_order is not None:
            raise OptionError("quadrature_order: the accuracy target takes each density order's own (QUADRATURE_ORDER,"
                              " what its error model measured); give one or the other")
        if self.reuse_tolerance is not None:  # else checked once the context gives it (resolved)
            self._check_reuse_interaction(self.reuse_tolerance)

    def _check_reuse_interaction(self, tolerance: float):
        if self.reuse_interaction is not None and not self.reuse_interaction >= tolerance > 0:
            raise OptionError(f"reuse_interaction: {self.reuse_interaction:g} is outside the allowed range"
                              f" [{max(tolerance, 1e-12):g}, 1e-06] (>= reuse_tolerance > 0)")

    def resolved(self, time_stepping: bool = False, bonds: bool = False) -> "SolverOptions":
        """These options with the context defaults filled in (module docstring): ``time_stepping``,
        a time-stepped model's; ``bonds``, a model with bonds (the snapshot lattice). With an
        accuracy target the density order and refinement stay open for it (``accuracy.py``). A
        ``Model`` resolves its options with this once, for scenes and scripts alike."""
        tolerance = DEFAULT_TOLERANCE[self.dtype] if self.tolerance is None else self.tolerance
        reuse = (BONDS_REUSE_TOLERANCE if bonds else 0.0) if self.reuse_tolerance is None else self.reuse_tolerance
        self._check_reuse_interaction(reuse)
        clusters = self.close_clusters or ("resistance" if self.many_body == "none" else "none")
        if self.accuracy is not None:
            return dataclasses.replace(self, tolerance=tolerance, reuse_tolerance=reuse, close_clusters=clusters)
        order = self.density_order or (TIME_STEPPING_DENSITY_ORDER if time_stepping else SOLVE_DENSITY_ORDER)
        refinement = DEFAULT_CONTACT_REFINEMENT[order] if self.contact_refinement is None else self.contact_refinement
        return dataclasses.replace(self, density_order=order, contact_refinement=refinement, tolerance=tolerance,
                                   reuse_tolerance=reuse, close_clusters=clusters,
                                   quadrature_order=self.quadrature_order or QUADRATURE_ORDER[order])

    def without_accuracy(self) -> "SolverOptions":
        """These options with no accuracy target, for the solves it does not cover (the traction,
        the interior elastic problem, the coarse many-body remainder): their own defaults apply."""
        return dataclasses.replace(self, accuracy=None)

    def splits_near_far(self, fixed_cells: int) -> bool:
        """Whether a time-stepped model with ``fixed_cells`` fixed cells takes the near-far split."""
        return self.near_far_split == "on" or (self.near_far_split == "auto" and fixed_cells >= NEAR_FAR_FIXED_CELLS)

    def near_far_report(self, fixed_cells: int) -> str:
        """The split's state and why, for the run's attributes: "on (auto: 64 fixed cells)"."""
        state = "on" if self.splits_near_far(fixed_cells) else "off"
        if self.near_far_split != "auto":
            return f"{state} (set)"
        return f"{state} (auto: {fixed_cells} fixed cells" + ("" if state == "on" else
                                                             f", below {NEAR_FAR_FIXED_CELLS}") + ")"

    @property
    def element_quadrature(self) -> int:
        """Gauss points per direction on an element: as given, else by density order
        (QUADRATURE_ORDER; resolved options carry it)."""
        return self.quadrature_order or QUADRATURE_ORDER[self.density_order or SOLVE_DENSITY_ORDER]

    @property
    def near_factor(self) -> float:
        """The adaptive quadrature's subdivision distance in panel radii, by density order."""
        return NEAR_FACTOR[self.density_order or SOLVE_DENSITY_ORDER]
