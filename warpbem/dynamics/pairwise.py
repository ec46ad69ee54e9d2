"""The grand mobility of many free cells from lone and two-body snapshots, at a cost that grows
linearly with their number (``SolverOptions.grand_mobility = "pairs"``; issue 25).

The whole system's snapshot (``hydrodynamics.py``) costs 6 n + 1 solves of n cells and is keyed
by every cell's lattice point, so n cells that roll independently ask for a new one whenever
any of them crosses a lattice line. The pairwise approximation of the method of reflections
(Batchelor 1976; the pairwise-additive mobility of Stokesian dynamics, Brady & Bossis 1988)
builds it from parts that depend on one cell or two:

    M_ii = M_i(h_i) + sum_{j near} [M^(ij)_ii - M_i(h_i*)],       M_ij = M^(ij)_ij,

M_i the lone cell's mobility at its own fine height h_i, M^(ij) the mobility of the pair (i, j)
alone above the wall, on the pair lattice (heights h* to ``reuse_interaction``, as the whole
system's snapshot; the lateral offset on a lattice whose spacing grows with the distance,
below), and the flow's motion alike. What it leaves out is the three-body part: the third
cell's answer to the flow of the two. Side by side with the whole-system solve
(``benchmarks/many_cells.py``, part 1; largest change over largest entry) it errs by 3.6e-4 in
the grand mobility and 9.3e-4 in the motion in the flow on three cells 25 um apart in a line,
by 1.6e-3 and 7.5e-3 in a 3 x 3 patch 25 um apart (the middle cell shielded by eight
neighbours), and by 3.5e-2 at 12 um in a line (2 um between the surfaces, where the middle cell
screens the outer two). So the pairs serve lines and sparse patches of cells tens of
micrometres apart, and the whole system's snapshot close trains (the default).

A pair above the wall in shear is invariant under translation along the wall, so its snapshot
is computed with its first cell at x = y = 0 and shared by every pair of cells of the same
meshes, heights and offset; it is also symmetric under the exchange of the two cells and, for
spheres in the flow u = gdot z e_x, under the mirror y -> -y (forces and velocities change the
sign of their y components, torques and angular velocities of their x and z ones), so the
offset is stored with x >= 0 and y >= 0. The coupling between two cells at the wall falls as
the cube of their distance r (a wall-parallel Stokeslet is felt as h z / r^3 along the wall,
Blake 1971) and its change with the offset as r^-4, so the lateral lattice spacing grows as
(r / r0)^4 from ``pair_lateral`` at r0 = the sum of the outer radii (contact), in steps of 2
and at most r / 8: the snapping error is then about the same at every distance. Pairs farther
apart than ``pair_cutoff`` are left out; the flow's coupling sums slowly over a patch (r^-3 per
pair, r pairs per ring), so the default keeps every pair of a patch up to 1 mm wide.
"""

from __future__ import annotations

import math

import numpy as np

from ..surfaces.body import Body

# y -> -y: a (basis) load's force keeps x, z and its torque (a pseudovector) keeps y; the
# motion's velocity and angular velocity alike
MIRROR_LOAD = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])
MIRROR_VELOCITY = np.array([1.0, -1.0, 1.0])
MIRROR_ANGULAR = -MIRROR_VELOCITY


# the pair lattice is at most this many times finer than the pair's distance (lateral_spacing)
WIDEST_SHARE = 8.0


class TooClose(Exception):
    """A snapped configuration is not a valid placement (a gap below the lattice spacing)."""


def lateral_spacing(distance: float, base: float, contact: float) -> float:
    """The pair lattice's spacing (m) at lateral ``distance`` (m): ``base`` times the largest
    power of 2 not above (distance / contact)^4 (module docstring), nor above distance /
    (8 base): the coupling's linear change with the offset, which the r^4 law assumes, does not
    reach across a lattice as wide as the distance itself (without the cap two cells 247 um apart
    would be snapped onto one another)."""
    if distance <= contact:
        return base
    level = min(4.0 * math.log2(distance / contact), math.log2(distance / (WIDEST_SHARE * base)))
    return base * 2.0 ** max(0, math.floor(level))


def pair_key(offset, heights, meshes, base: float, contact: float):
    """(key, swapped, mirrored, canonical offset, canonical heights) of the pair whose second cell
    is ``offset`` (m, lateral) from its first: the offset snapped to the pair lattice, the cells
    exchanged so that it points to x > 0 (or x = 0, y >= 0), mirrored so that y >= 0."""
    spacing = lateral_spacing(float(np.hypot(*offset)), base, contact)
    cell = np.round(np.asarray(offset) / spacing).astype(int)
    swapped = bool(cell[0] < 0 or (cell[0] == 0 and cell[1] < 0))
    if swapped:
        cell, heights, meshes = -cell, heights[::-1], meshes[::-1]
    mirrored = bool(cell[1] < 0)
    cell[1] = abs(cell[1])
    key = ("pair",) + tuple(meshes) + tuple(heights) + (spacing,) + tuple(int(c) for c in cell)
    return key, swapped, mirrored, cell * spacing, heights


def mirror_motion(velocity, angular_velocity):
    """The flow's motion (2, 3) of the mirrored pair."""
    return velocity * MIRROR_VELOCITY, angular_velocity * MIRROR_ANGULAR


def mirror_basis(velocity, angular_velocity):
    """The basis responses (12, 2, 3) of the mirrored pair (loads and motions both mirrored)."""
    load = np.tile(MIRROR_LOAD, 2)[:, None, None]
    return velocity * load * MIRROR_VELOCITY, angular_velocity * load * MIRROR_ANGULAR


class PairwiseMobility:
    """Assembles the snapshot (flow Motion parts and grand-mobility parts) of ``hydro``'s model
    from its lone snapshots and pair snapshots (module docstring). ``hydro`` is the
    ``HydrodynamicSolves`` whose lattices and snapshot store it uses."""

    def __init__(self, hydro):
        model = hydro.model
        self.hydro = hydro
        self.base = model.solver.pair_lateral
        self.cutoff = model.solver.pair_cutoff
        self.radii = model.outer_radii
        self._cached_key, self._cached = None, None

    def assemble(self, bodies):
        """(flow velocity, angular velocity (n, 3); basis velocity, angular velocity (6n, n, 3),
        iterations, residual) of the free ``bodies``: each cell's lone snapshot at its fine
        height, plus the pairs' part, which is kept while no pair changes its lattice point (the
        fine heights change every few steps of a rolling cell, the pairs' lattice points rarely)."""
        hydro = self.hydro
        velocity, angular, basis_velocity, basis_angular = (a.copy() for a in self._pairs_part(bodies))
        iterations, residual = 0, 0.0
        for b, body in enumerate(bodies):
            flow, grand = hydro._lone(b, body, hydro.tolerance, exact_if_too_close=True)
            velocity[b] += flow.velocity[0]
            angular[b] += flow.angular_velocity[0]
            rows = slice(6 * b, 6 * b + 6)
            basis_velocity[rows, b] += grand.velocity[:, 0]
            basis_angular[rows, b] += grand.angular_velocity[:, 0]
            iterations += flow.iterations + grand.iterations
            residual = max(residual, flow.residual, grand.residual)
        return velocity, angular, basis_velocity, basis_angular, iterations, residual

    def _pairs_part(self, bodies):
        """sum over the pairs within the cut-off of [pair snapshot - each cell's lone snapshot at
        the pair's heights]: the flow's (n, 3) velocity and angular velocity corrections and the
        basis's (6n, n, 3) ones."""
        n = len(bodies)
        positions = np.array([body.position for body in bodies])
        entries = []
        for i in range(n):
            for j in range(i + 1, n):
                offset = positions[j, :2] - positions[i, :2]
                if np.hypot(*offset) <= self.cutoff:
                    entries.append(self._pair_entry(bodies, i, j, offset))
        key = tuple((e[0], e[1], e[2], e[4]) for e in entries)
        if key == self._cached_key:
            return self._cached
        velocity, angular = np.zeros((n, 3)), np.zeros((n, 3))
        basis_velocity, basis_angular = np.zeros((6 * n, n, 3)), np.zeros((6 * n, n, 3))
        exact, coarse = False, {}  # each cell's lone snapshot at its pair height, looked up once
        for entry in entries:
            (flow_v, flow_w), (grand_v, grand_w), order, solved_as_is = self._pair_values(bodies, *entry)
            exact |= solved_as_is
            for a, b in enumerate(order):
                if b not in coarse:
                    coarse[b] = self.hydro._lone(b, bodies[b], self.hydro.interaction, exact_if_too_close=True)
                lone_flow, lone_grand = coarse[b]
                velocity[b] += flow_v[a] - lone_flow.velocity[0]
                angular[b] += flow_w[a] - lone_flow.angular_velocity[0]
                for c, other in enumerate(order):
                    rows, pair_rows = slice(6 * other, 6 * other + 6), slice(6 * c, 6 * c + 6)
                    basis_velocity[rows, b] += grand_v[pair_rows, a]
                    basis_angular[rows, b] += grand_w[pair_rows, a]
                rows = slice(6 * b, 6 * b + 6)
                basis_velocity[rows, b] -= lone_grand.velocity[:, 0]
                basis_angular[rows, b] -= lone_grand.angular_velocity[:, 0]
        part = (velocity, angular, basis_velocity, basis_angular)
        # a pair solved as it is (too near for its lattice) is not a lattice point: not kept
        self._cached_key, self._cached = (None, None) if exact else (key, part)
        return part

    def _pair_entry(self, bodies, i, j, offset):
        """(key, swapped, mirrored, canonical offset and heights, (i, j)) of the pair (pair_key)."""
        d = self.hydro.interaction
        heights = tuple(float(np.round(bodies[b].position[2] / d) * d) for b in (i, j))
        meshes = (self.hydro.lone_of[i], self.hydro.lone_of[j])
        key, swapped, mirrored, canonical, canonical_heights = pair_key(offset, heights, meshes, self.base,
                                                                        self.radii[i] + self.radii[j])
        return key, swapped, mirrored, (canonical, canonical_heights), (i, j)

    def _pair_values(self, bodies, key, swapped, mirrored, canonical, cells):
        """The pair's (flow motion, basis responses) in the order ``order`` of its cells (model
        indices), from its snapshot at the canonical offset and snapped heights, and whether it
        was solved as it is instead."""
        hydro, (i, j) = self.hydro, cells
        (offset, (h0, h1)) = canonical
        order = (j, i) if swapped else (i, j)
        snapped = [Body(bodies[order[0]].mesh, position=(0.0, 0.0, h0)),
                   Body(bodies[order[1]].mesh, position=(offset[0], offset[1], h1))]
        radii = self.radii[list(order)]
        # two cells of one mesh at one height: a half turn exchanges them, 7 solves instead of 13
        half_turn = h0 == h1 and snapped[0].mesh is snapped[1].mesh
        try:
            flow, grand = hydro._kept(key, snapped, lambda b: hydro._solved(b, radii, half_turn), store=hydro._pairs)
        except TooClose:  # nearer than the lattice allows: the pair solved as it is, not kept
            flow, grand = hydro._solved([bodies[i], bodies[j]], self.radii[[i, j]])
            return (flow.velocity, flow.angular_velocity), (grand.velocity, grand.angular_velocity), (i, j), True
        motion = (flow.velocity, flow.angular_velocity)
        basis = (grand.velocity, grand.angular_velocity)
        if mirrored:
            motion, basis = mirror_motion(*motion), mirror_basis(*basis)
        return motion, basis, order, False
