"""Frozen adherent arrays: the flow past many fixed cells solved once, and in each step only
what the free cells change ("model no more than a scene needs", DESIGN.md §3).

Adherent cells at rest never move. In the CDL system of ``mobility.py`` split the bodies into
free cells F and adherent cells A, and write the adherent density as q_A = q0_A + dq_A, q0_A
the solution of the adherent cells alone in the shear flow (the background, solved once):

    rows of F:   A_FF q_F + A_FA dq_A = b_F - A_FA q0_A
    rows of A:   A_AF q_F + A_AA dq_A = b_A - A_AA q0_A = 0.

The free cells see, as their undisturbed flow, the background flow u_bg = u_inf + w0 (w0 the
double layer of q0 and the adherent cells' completions, ``BackgroundField``), and the adherent
cells answer the free cells' disturbance with dq_A under the no-slip condition u_bg = 0 on
them. Exact so far. The approximation: adherent cells whose bounding sphere is farther than
the ``cutoff`` from every free cell's ("far" cells) do not answer (dq = 0 there), so a step
solves the free cells and the near adherent cells only, an ordinary ``MobilitySolver`` system
(meshes refined near contact as usual) whose undisturbed flow is u_bg on the free cells and
zero on the adherent ones.

What it leaves out: the far cells' answer to the free cell's disturbance, and the free cell's
to theirs. Above the wall both decay fast (a wall-parallel Stokeslet at height h is felt as
h z / r^3 along the wall, Blake 1971; a force-free cell's stresslet faster): on an 8 x 8
array of domes the largest error of the free cell's velocity over its crossing falls about as
R^-4 with the cut-off R, to 1.2e-4 at ``DEFAULT_CUTOFF`` = 40 um, eight times inside 1e-3
(``benchmarks/frozen.py``, docs/benchmarks.md "Frozen adherent arrays").

The background flow at the free cells' points comes from the solved density through the
treecode (``treecode.py``): the far field of the whole array at every leaf's Chebyshev points is
computed once (``FarField.local_values``), and each evaluation interpolates it in the leaf of
the point and adds the leaf's own and 8 neighbours' elements and poles by the exact (adaptive)
element integrals (``DiscreteOperator.field_at``). The tree covers the region of the bodies
at set-up with a margin (``COVER_SHARE``); points beyond it (a free cell that left) are summed
directly over every element, slower, with a warning.

Loads: a near adherent cell's load is its background load plus its answer; a far one keeps its
background load (its answer dropped); in solves of loads alone (``background=False``) far cells
carry none.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..surfaces.gaps import candidate_pairs, outer_radius
from ..surfaces.placement import body_label
from ..surfaces.quad9 import CENTRE_NODE
from .completed_double_layer import all_completion_poles
from .mobility import MobilitySolution, MobilitySolver, checked_bodies, checked_loads
from .operators import BoundaryOperator, discrete_form, quadrature_strengths
from .options import DEFAULT_CUTOFF
from .treecode import FarField, TreecodeOptions

# adherent elements from which the background flow is evaluated by the tree; below, the direct
# sum over every element costs less than the tree's set-up (a 2 x 2 array's tree: 20 s; an 8 x 8
# array of domes, 6144 elements: 0.05 s per evaluation at a free cell's 96 points)
TREE_ELEMENTS = 8192
# the tree covers the bodies at set-up and, along the wall, this share of their extent (at least
# COVER_DIAMETERS outer diameters of the largest body) around them, and one outer radius above
# the highest top (a taller tree has wider leaves, more near field per point). Points beyond
# are summed directly: a free cell that left the 32 x 32 array's first cover (two diameters)
# stepped in 30 s instead of 1.5 s; a wider cover costs a few seconds at set-up
COVER_SHARE = 0.25
COVER_DIAMETERS = 2.0


class BackgroundField:
    """u_bg = u_inf + w0 (SI): the shear flow past the adherent ``bodies`` alone, solved once by
    ``solver`` (a fresh MobilitySolver), then evaluated at any points outside them
    (``velocity``). ``cover``: (k, 3) points (m) the evaluation tree must reach; the tree is
    built from ``tree_elements`` elements on (below, every evaluation is the direct sum)."""

    def __init__(self, solver: MobilitySolver, bodies, cover: np.ndarray, treecode: TreecodeOptions,
                 tree_elements: int = TREE_ELEMENTS):
        solution = solver.solve(bodies)
        system, x, speed = solver.last_system
        geo = system.geometry
        self.force, self.torque = solution.force, solution.torque
        self.warned = False  # of points beyond the tree
        self.shear_rate, self.length, self.speed = solver.flow.shear_rate, geo.length_scale, speed
        # the double layer sees the non-rigid part of the density, the completions the loads
        # (CompletedDoubleLayer.matvec)
        rigid = np.concatenate([system.rigid.modes[p] @ system.rigid.coefficients(p, x) for p in range(len(bodies))])
        self.density = x - rigid
        loads = np.concatenate([system.fixed_loads(p, x) for p in range(len(bodies))])
        self.pole_forces = system.pole_forces(loads)
        poles = all_completion_poles(geo)
        self.operator = discrete_form(BoundaryOperator(geo, solver.flow.wall, solver.quadrature, "double_layer",
                                                       solver.options.dtype), "matrix_free", solver.device,
                                      point_sources=poles)
        self.far = self.values = None
        if geo.n_elements < tree_elements:
            return
        n_qp = geo.qp_positions.shape[1]
        self.far = FarField(self.operator.kernels, self.operator.device, geo.element_nodes[:, CENTRE_NODE],
                            geo.collocation, np.arange(geo.n_points) // geo.points_per_element,
                            geo.qp_positions.reshape(-1, 3),
                            np.repeat(np.arange(geo.n_elements), n_qp), poles, treecode,
                            cover=np.asarray(cover, dtype=float) / self.length)
        self.values = self.far.local_values(quadrature_strengths(geo, self.density), self.pole_forces)

    def velocity(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) u_bg (m/s) at ``points`` (m) outside the adherent cells."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        x = points / self.length
        far, op = self.far, self.operator
        if far is None:  # a small array: the direct sum
            w = op.field_at(x, self.density, self.pole_forces)
        else:
            w = np.zeros_like(x)
            inside = far.covers(x)
            if inside.any():
                seg = far.segments_at(x[inside])
                group = far.group_of_target(seg)
                w[inside] = far.interpolate(self.values, seg) + op.field_at(
                    x[inside], self.density, self.pole_forces, (group, *far.near_lists(far.leaf_of_element, seg)),
                    (group, *far.near_lists(far.leaf_of_pole, seg)))
            if not inside.all():
                if not self.warned:
                    warnings.warn("points outside the region the frozen array's tree covers (the bodies at set-up"
                                  f" and {COVER_SHARE:g} of their extent around, a radius above): their background"
                                  " flow is summed directly over every element, which is slower", stacklevel=2)
                    self.warned = True
                w[~inside] = op.field_at(x[~inside], self.density, self.pole_forces)
        u = w * self.speed
        u[:, 0] += self.shear_rate * points[:, 2]
        return u


class FrozenArraySolver:
    """``MobilitySolver.solve`` for free cells among fixed adherent cells at rest, the adherent
    cells' background solved once and only the free cells and the adherent cells within
    ``cutoff`` (m, between bounding spheres) of them solved in each call (module docstring).

    solver: a MobilitySolver with the settings of both solves (it solves the near systems; a
    fresh copy solves the background); treecode: the options of the background flow's tree,
    built from ``tree_elements`` adherent elements on (``BackgroundField``). The fixed bodies
    must be the same in every call (set up at the first).

    Examples
    --------
    A free cell beside the first of three adherent cells 60 um apart: with a 30 um cut-off
    only that one is solved with it, the others keep their background; the free cell's
    velocity is that of the whole system's solve to 1e-5:

    >>> import numpy as np
    >>> import warpbem as wb
    >>> sphere = wb.mesh.sphere(radius=5e-6, subdivisions=2)
    >>> adherent = [wb.Body(sphere, position=(x, 0.0, 7.5e-6), fixed=True) for x in (0.0, 60e-6, 120e-6)]
    >>> free = wb.Body(sphere, position=(-15e-6, 0.0, 10e-6))
    >>> options = wb.SolverOptions(density_order=1)
    >>> split = wb.FrozenArraySolver(wb.MobilitySolver(shear_rate=100.0, options=options), cutoff=30e-6)
    >>> near = split.solve([free, *adherent])
    >>> split.near_bodies.tolist()
    [1]
    >>> whole = wb.MobilitySolver(shear_rate=100.0, options=options).solve([free, *adherent])
    >>> bool(np.abs(near.velocity[0] - whole.velocity[0]).max() < 1e-5 * np.abs(whole.velocity[0]).max())
    True
    """

    def __init__(self, solver: MobilitySolver, cutoff: float = DEFAULT_CUTOFF, treecode: TreecodeOptions | None = None,
                 tree_elements: int = TREE_ELEMENTS):
        if isinstance(cutoff, bool) or not np.isfinite(cutoff) or cutoff < 0:
            raise ValueError(f"cutoff must be a finite distance >= 0 (m), got {cutoff!r}")
        self.inner = solver
        self.cutoff = float(cutoff)
        self.treecode = treecode or solver.options.treecode
        self.tree_elements = int(tree_elements)
        self.background_field: BackgroundField | None = None
        self._fixed_key = None
        self.near_bodies = np.zeros(0, dtype=int)  # the adherent cells solved in the last call

    @property
    def last_chosen(self):
        """The accuracy target's ChosenSettings of the last near solve (None without a target)."""
        return self.inner.last_chosen

    @property
    def operator_description(self) -> str:
        """The near systems' operator, and the split."""
        return f"{self.inner.operator_description}, near-far {self.cutoff * 1e6:g} um"

    def solve(self, bodies, forces=None, torques=None, check_placement_first: bool = True,
              background: bool = True) -> MobilitySolution:
        """As ``MobilitySolver.solve``, for all ``bodies``: far adherent cells keep their
        background load (none with ``background=False``)."""
        bodies = checked_bodies(bodies)
        fixed = np.array([b.fixed for b in bodies])
        if not fixed.any():
            return self.inner.solve(bodies, forces, torques, check_placement_first=check_placement_first,
                                    background=background)
        n = len(bodies)
        forces, torques = checked_loads("forces", forces, bodies), checked_loads("torques", torques, bodies)
        adherent = np.flatnonzero(fixed)
        self._set_up(bodies, adherent)
        field = self.background_field
        free = np.flatnonzero(~fixed)
        velocity, angular_velocity = np.zeros((n, 3)), np.zeros((n, 3))
        force, torque = forces.copy(), torques.copy()
        if background:
            force[adherent], torque[adherent] = field.force, field.torque
        if not len(free):
            self.near_bodies = np.zeros(0, dtype=int)
            return MobilitySolution(velocity, angular_velocity, force, torque, 0, 0.0, True, self.inner.operator_description,
                                    np.zeros(0), fixed.copy())
        near = self._near(bodies, free, adherent)
        subset = np.concatenate([free, near])
        self.near_bodies = near
        held = fixed[subset]

        def ambient(points, body_of_point):  # u_bg on the free cells, no slip on the adherent ones
            out = np.zeros_like(points)
            on_free = ~held[body_of_point]
            out[on_free] = field.velocity(points[on_free])
            return out

        sol = self.inner.solve([bodies[i] for i in subset], forces[subset], torques[subset],
                               check_placement_first=check_placement_first, background=background,
                               ambient_flow=ambient)
        velocity[subset], angular_velocity[subset] = sol.velocity, sol.angular_velocity
        force[free], torque[free] = sol.force[: len(free)], sol.torque[: len(free)]
        force[near] += sol.force[len(free):]
        torque[near] += sol.torque[len(free):]
        reused = fixed.copy()
        reused[subset] = sol.reused_bodies
        return MobilitySolution(velocity, angular_velocity, force, torque, sol.iterations, sol.residual,
                                sol.converged, sol.operator_mode, sol.solution_vector, reused)

    def solve_loads(self, bodies, forces, torques, factor_every_body: bool = False,
                    with_background: bool = False) -> list[MobilitySolution]:
        """As ``MobilitySolver.solve_loads``, one load after the other (its near systems hold
        fixed bodies, whose responses the batched solve does not take)."""
        background = [self.solve(bodies, check_placement_first=False)] if with_background else []
        return background + [self.solve(bodies, f, t, check_placement_first=False, background=False)
                             for f, t in zip(forces, torques)]

    def _set_up(self, bodies, adherent):
        """The background of the adherent cells, solved at the first call; later calls must
        bring the very same adherent cells."""
        key = [(bodies[i].mesh, bodies[i].position.tobytes(), bodies[i].orientation.tobytes()) for i in adherent]
        if self.background_field is not None:
            if key != self._fixed_key:
                raise ValueError("the near-far split solves the adherent cells' background once: the fixed bodies"
                                 " must be the same, in the same places, in every solve")
            return
        for i in adherent:
            b = bodies[i]
            if np.any(b.velocity) or np.any(b.angular_velocity) or b.surface_velocity is not None:
                raise ValueError(f"body {body_label(b.name, i)} is fixed but moves (a prescribed velocity or surface"
                                 " velocity): the near-far split needs adherent cells at rest; solve without it")
        radius = max(outer_radius(b.mesh) for b in bodies)
        centres = np.array([b.position for b in bodies])
        low, high = centres.min(axis=0), centres.max(axis=0)
        margin = max(COVER_SHARE * float(np.ptp(centres[:, :2], axis=0).max()), 2.0 * COVER_DIAMETERS * radius)
        cover = np.array([[low[0] - margin, low[1] - margin, 0.0],
                          [high[0] + margin, high[1] + margin, high[2] + 2.0 * radius]])
        self._radii = np.array([outer_radius(bodies[i].mesh) for i in adherent])
        self.background_field = BackgroundField(self.inner.fresh(), [bodies[i] for i in adherent], cover,
                                                self.treecode, self.tree_elements)
        self._fixed_key = key

    def _near(self, bodies, free, adherent) -> np.ndarray:
        """The adherent cells whose bounding sphere comes within the cut-off of a free cell's."""
        radii = np.zeros(len(bodies))
        radii[adherent] = self._radii
        radii[free] = [outer_radius(bodies[i].mesh) for i in free]
        fixed = np.zeros(len(bodies), dtype=bool)
        fixed[adherent] = True
        pairs = candidate_pairs([b.position for b in bodies], radii, fixed, False, self.cutoff)
        return np.array(sorted({j for unused, j in pairs if fixed[j]}), dtype=int)
