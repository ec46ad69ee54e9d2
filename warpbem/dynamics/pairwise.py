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
offset is stored with x >= 0 and y >= 0.

The pair's snapshot at its lateral offset is the bilinear interpolation of the snapshots at the
four points of a square lattice around it (each mapped to its stored form on its own, so a
square may straddle the lines x = 0 or y = 0). Its error is (s^2 / 8) times the coupling's
second derivative along the wall, where snapping to the nearest point errs by (s / 2) times the
first: on two 5 um cells 12.5 um apart a 500 nm lattice interpolates to 3.4e-4 of the grand
mobility and the flow's motion, the nearest point of a 20 nm lattice snaps to about the same,
and the nearest point of a 500 nm one to 8.6e-3 (``benchmarks/many_cells.py --parts lattice``).
The coupling between two cells at the wall falls as the cube of their distance r (a
wall-parallel Stokeslet is felt as h z / r^3 along the wall, Blake 1971), its second derivative
as r^-5, so the lattice spacing grows as (r / r0)^(5/2) from ``pair_lateral`` at r0 = the sum
of the outer radii (contact), in steps of 2 and at most r / 8: the interpolation error is then
about the same at every distance. The pairs' heights stay snapped to ``reuse_interaction``, as
the whole system's, with each cell's self part moved to its fine height by its lone snapshots.
Pairs farther apart than ``pair_cutoff`` are left out; the flow's coupling sums slowly over a
patch (r^-3 per pair, r pairs per ring), so the default keeps every pair of a patch up to 1 mm
wide.
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
# the interpolation error of the pair lattice at spacing s is (s^2 / 8) times the coupling's
# second derivative along the wall, which falls as r^-5 (the coupling as r^-3): the lattice grows
# as r^(5/2) to hold it the same at every distance
LATTICE_POWER = 2.5
# a pair snapshot's parts stored as one row (flow velocity, angular velocity (2, 3); basis
# velocity, angular velocity (12, 2, 3)): the lattice points' rows are interpolated at once
PART_SHAPES = ((2, 3), (2, 3), (12, 2, 3), (12, 2, 3))
PART_SIZES = tuple(int(np.prod(s)) for s in PART_SHAPES)
# an offset this close to a lattice line, in lattice spacings, lies on it (lattice_corners)
ROUND_OFF = 1e-9


class TooClose(Exception):
    """A snapped configuration is not a valid placement (a gap below the lattice spacing)."""


def lateral_spacing(distance: float, base: float, contact: float) -> float:
    """The pair lattice's spacing (m) at lateral ``distance`` (m): ``base`` times the largest
    power of 2 not above (distance / contact)^(5/2) (LATTICE_POWER), nor above distance /
    (8 base): the coupling's smooth change with the offset, which the interpolation assumes,
    does not reach across a lattice as wide as the distance itself."""
    if distance <= contact:
        return base
    level = min(LATTICE_POWER * math.log2(distance / contact), math.log2(distance / (WIDEST_SHARE * base)))
    return base * 2.0 ** max(0, math.floor(level))


def lattice_corners(offset, spacing: float):
    """[(weight, lattice point (2,) ints)] of the bilinear interpolation at the lateral
    ``offset`` (m) on the square lattice of ``spacing`` (m): the four points of the lattice
    square that holds it, those of weight 0 left out (an offset on a lattice line or point, to
    ROUND_OFF of the spacing: cells placed on the lattice stay on it)."""
    u = np.asarray(offset, dtype=float) / spacing
    nearest = np.round(u)
    u = np.where(np.abs(u - nearest) < ROUND_OFF, nearest, u)
    base = np.floor(u)
    f = u - base
    corners = []
    for dx in (0, 1):
        for dy in (0, 1):
            weight = (f[0] if dx else 1.0 - f[0]) * (f[1] if dy else 1.0 - f[1])
            if weight > 0.0:
                corners.append((float(weight), base.astype(int) + (dx, dy)))
    return corners


def pair_key(point, spacing: float, heights, meshes):
    """(key, swapped, mirrored, canonical offset, canonical heights) of the pair whose second
    cell is at the lattice ``point`` (ints, in units of ``spacing``) from its first: the cells
    exchanged so that it points to x > 0 (or x = 0, y >= 0), mirrored so that y >= 0."""
    point = np.array(point, dtype=int)
    swapped = bool(point[0] < 0 or (point[0] == 0 and point[1] < 0))
    if swapped:
        point, heights, meshes = -point, heights[::-1], meshes[::-1]
    mirrored = bool(point[1] < 0)
    point[1] = abs(point[1])
    key = ("pair",) + tuple(meshes) + tuple(heights) + (spacing,) + tuple(int(c) for c in point)
    return key, swapped, mirrored, point * spacing, heights


def part_row(flow_velocity, flow_angular, basis_velocity, basis_angular, swapped: bool, mirrored: bool):
    """A pair snapshot's parts as one row, in the order of the model's pair (the first cell the
    one whose offset was taken): mirrored back (y -> -y: forces and velocities change their y
    components, torques and angular velocities their x and z ones) and exchanged back."""
    if mirrored:
        load = np.tile(MIRROR_LOAD, 2)[:, None, None]
        flow_velocity, flow_angular = flow_velocity * MIRROR_VELOCITY, flow_angular * MIRROR_ANGULAR
        basis_velocity = basis_velocity * load * MIRROR_VELOCITY
        basis_angular = basis_angular * load * MIRROR_ANGULAR
    if swapped:  # the loads' cell (row blocks of 6) and the responding cell (axis 1) both exchanged
        flow_velocity, flow_angular = flow_velocity[::-1], flow_angular[::-1]
        basis_velocity, basis_angular = (b.reshape(2, 6, 2, 3)[::-1, :, ::-1] for b in (basis_velocity, basis_angular))
    return np.concatenate([np.ravel(a) for a in (flow_velocity, flow_angular, basis_velocity, basis_angular)])


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
        self._rows: dict = {}  # (pair key, swapped, mirrored) -> part_row of a kept pair snapshot

    def assemble(self, bodies):
        """(flow velocity, angular velocity (n, 3); basis velocity, angular velocity (6n, n, 3),
        iterations, residual) of the free ``bodies``: each cell's lone snapshot at its fine
        height, plus the pairs' part."""
        hydro = self.hydro
        velocity, angular, basis_velocity, basis_angular = self._pairs_part(bodies)
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
        """sum over the pairs within the cut-off of [pair snapshot, interpolated at the pair's
        offset - each cell's lone snapshot at the pair's heights]: the flow's (n, 3) velocity and
        angular velocity corrections and the basis's (6n, n, 3) ones."""
        n = len(bodies)
        positions = np.array([body.position for body in bodies])
        first, second = np.triu_indices(n, 1)
        offsets = positions[second, :2] - positions[first, :2]
        within = np.hypot(offsets[:, 0], offsets[:, 1]) <= self.cutoff
        first, second, offsets = first[within], second[within], offsets[within]
        rows = np.array([self._pair_row(bodies, i, j, o) for i, j, o in zip(first, second, offsets)])
        rows = rows.reshape(len(first), sum(PART_SIZES))
        flow_v, flow_w, grand_v, grand_w = (part.reshape((-1,) + shape) for part, shape in
                                            zip(np.split(rows, np.cumsum(PART_SIZES)[:-1], axis=1), PART_SHAPES))
        velocity, angular = np.zeros((n, 3)), np.zeros((n, 3))
        # (loaded cell, responding cell, load component, 3): the advanced indices side by side
        by_cells_v, by_cells_w = np.zeros((n, n, 6, 3)), np.zeros((n, n, 6, 3))
        cells = (first, second)
        for a in (0, 1):
            np.add.at(velocity, cells[a], flow_v[:, a])
            np.add.at(angular, cells[a], flow_w[:, a])
            for c in (0, 1):  # the loads on the pair's cell c, the motion of its cell a
                np.add.at(by_cells_v, (cells[c], cells[a]), grand_v.reshape(-1, 2, 6, 2, 3)[:, c, :, a])
                np.add.at(by_cells_w, (cells[c], cells[a]), grand_w.reshape(-1, 2, 6, 2, 3)[:, c, :, a])
        # each cell's lone snapshot at its pair height, once per pair it is in
        pairs_of = np.bincount(np.concatenate(cells), minlength=n)
        for b in np.flatnonzero(pairs_of):
            lone_flow, lone_grand = self.hydro._lone(b, bodies[b], self.hydro.interaction, exact_if_too_close=True)
            velocity[b] -= pairs_of[b] * lone_flow.velocity[0]
            angular[b] -= pairs_of[b] * lone_flow.angular_velocity[0]
            by_cells_v[b, b] -= pairs_of[b] * lone_grand.velocity[:, 0]
            by_cells_w[b, b] -= pairs_of[b] * lone_grand.angular_velocity[:, 0]
        basis_velocity, basis_angular = (a.transpose(0, 2, 1, 3).reshape(6 * n, n, 3) for a in (by_cells_v, by_cells_w))
        return velocity, angular, basis_velocity, basis_angular

    def _pair_row(self, bodies, i, j, offset):
        """The pair (i, j)'s snapshot at ``offset`` (m, of j from i along the wall) as one row
        (part_row, in the order (i, j)): the bilinear interpolation of its lattice points'
        snapshots, at the cells' heights on the pair lattice; solved as it is (not kept) when a
        lattice point is too near for a valid placement."""
        hydro = self.hydro
        d = hydro.interaction
        heights = tuple(float(np.round(bodies[b].position[2] / d) * d) for b in (i, j))
        meshes = (hydro.lone_of[i], hydro.lone_of[j])
        spacing = lateral_spacing(float(np.hypot(*offset)), self.base, self.radii[i] + self.radii[j])
        try:
            return sum(weight * self._point_row(bodies, (i, j), pair_key(point, spacing, heights, meshes))
                       for weight, point in lattice_corners(offset, spacing))
        except TooClose:
            flow, grand = hydro._solved([bodies[i], bodies[j]], self.radii[[i, j]])
            return part_row(flow.velocity, flow.angular_velocity, grand.velocity, grand.angular_velocity, False, False)

    def _point_row(self, bodies, cells, keyed):
        """The part_row of a lattice point's pair snapshot (``keyed``: pair_key's answer), solved
        and kept if new."""
        key, swapped, mirrored, offset, (h0, h1) = keyed
        if (key, swapped, mirrored) in self._rows:
            return self._rows[key, swapped, mirrored]
        hydro = self.hydro
        order = cells[::-1] if swapped else cells
        snapped = [Body(bodies[order[0]].mesh, position=(0.0, 0.0, h0)),
                   Body(bodies[order[1]].mesh, position=(offset[0], offset[1], h1))]
        radii = self.radii[list(order)]
        # two cells of one mesh at one height: a half turn exchanges them, 7 solves instead of 13
        half_turn = h0 == h1 and snapped[0].mesh is snapped[1].mesh
        flow, grand = hydro._kept(key, snapped, lambda b: hydro._solved(b, radii, half_turn), store=hydro._pairs)
        row = part_row(flow.velocity, flow.angular_velocity, grand.velocity, grand.angular_velocity, swapped, mirrored)
        if len(self._rows) > 4 * len(hydro._pairs):  # rows of snapshots no longer kept go with them
            self._rows = {k: v for k, v in self._rows.items() if k[0] in hydro._pairs}
        self._rows[key, swapped, mirrored] = row
        return row
