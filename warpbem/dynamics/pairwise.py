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
neighbours; 1.7e-3 and 1.2e-2 in a 4 x 4 one), and by 3.5e-2 at 12 um in a line (2 um between
the surfaces, where the middle cell screens the outer two). In a close train that part is
taken in resistance from the cluster's own solve on a coarser discretisation (``[solver]
close_clusters``, ``close_clusters.py``, added with the films). In a patch, the part left out,
taken from a coarse mesh's whole system (24-element cells, biquadratic density), cuts the 4 x 4
patch's errors to 2.1e-4 and 3.8e-4 (``[solver] many_body = "coarse"``, ``many_body.py``, added
to the assembly here).

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
Two equal cells less than half a radius apart leave this lattice for the close pairs'
(``close_pairs.py``): the exact two-sphere resistance at their own gap plus the wall's part on a
lattice of gaps, their films added to the assembled resistance after the sum. Pairs farther
apart than ``pair_cutoff`` are left out; the flow's coupling sums slowly over a
patch (r^-3 per pair, r pairs per ring), so the default keeps every pair of a patch up to 1 mm
wide.
"""

from __future__ import annotations

import numpy as np

from ..hydro.options import NEAR_RADII
from ..surfaces.body import Body
from .close_clusters import CloseClusters, clusters
from .close_pairs import ClosePairs, generalised_matrices, with_resistance
from .far_field import COUPLING_SHAPES, FarField
from .many_body import ManyBodyRemainder

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
FAR_SIZES = tuple(int(np.prod(s)) for s in COUPLING_SHAPES)
# an offset this close to a lattice line, in lattice spacings, lies on it (lattice_corners)
ROUND_OFF = 1e-9
# the corners of a lattice square from its lower left one, in lattice spacings
CORNER_STEPS = np.array([(0, 0), (1, 0), (0, 1), (1, 1)])


class TooClose(Exception):
    """A snapped configuration is not a valid placement (a gap below the lattice spacing)."""


def lateral_spacing(distance, base: float, contact):
    """The pair lattice's spacing (m) at lateral ``distance`` (m; a number or an array, with
    ``contact`` alike): ``base`` times the largest power of 2 not above (distance /
    contact)^(5/2) (LATTICE_POWER), nor above distance / (8 base): the coupling's smooth change
    with the offset, which the interpolation assumes, does not reach across a lattice as wide as
    the distance itself. ``base`` at contact distance and below."""
    distance, contact = np.asarray(distance, dtype=float), np.asarray(contact, dtype=float)
    beyond = np.maximum(distance, contact)
    level = np.minimum(LATTICE_POWER * np.log2(beyond / contact), np.log2(beyond / (WIDEST_SHARE * base)))
    spacing = base * 2.0 ** np.maximum(0.0, np.floor(level))
    return float(spacing) if spacing.ndim == 0 else spacing


def lattice_corners(offsets, spacings):
    """(points (P, 4, 2) ints, weights (P, 4)) of the bilinear interpolation at each lateral
    offset (m, (P, 2)) on the square lattice of its spacing (m, (P,)): the four points of the
    lattice square that holds it. An offset on a lattice line or point, to ROUND_OFF of the
    spacing (cells placed on the lattice stay on it), gives the points beyond it weight 0."""
    u = np.asarray(offsets, dtype=float).reshape(-1, 2) / np.asarray(spacings, dtype=float).reshape(-1, 1)
    nearest = np.round(u)
    u = np.where(np.abs(u - nearest) < ROUND_OFF, nearest, u)
    base = np.floor(u)
    f = u - base
    points = base.astype(int)[:, None, :] + CORNER_STEPS
    weights = np.where(CORNER_STEPS == 1, f[:, None, :], 1.0 - f[:, None, :]).prod(axis=2)
    return points, weights


def canonical(points, heights, meshes):
    """(points, heights, meshes, swapped, mirrored) of the pairs whose second cell is at the
    lattice ``points`` ((K, 2) ints) from the first, at ``heights`` and of ``meshes`` ((K, 2)
    each, first and second cell): their stored forms, the cells exchanged so that the point lies
    at x > 0 (or x = 0, y >= 0), then mirrored so that y >= 0."""
    points = np.asarray(points, dtype=int).reshape(-1, 2)
    swapped = (points[:, 0] < 0) | ((points[:, 0] == 0) & (points[:, 1] < 0))
    exchange = swapped[:, None]
    points = np.where(exchange, -points, points)
    heights = np.where(exchange, np.asarray(heights)[:, ::-1], heights)
    meshes = np.where(exchange, np.asarray(meshes)[:, ::-1], meshes)
    mirrored = points[:, 1] < 0
    points[:, 1] = np.abs(points[:, 1])
    return points, heights, meshes, swapped, mirrored


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


def summed(cells, values, n: int) -> np.ndarray:
    """(n, ...) the sum of ``values`` ((P, ...), one per pair) over the pairs, by the cell
    ``cells[p]`` of each: one np.bincount over (cell, component) bins, each bin summed in the
    pairs' order (np.add.at took 60 ms of a step of 64 cells, a product with the incidence matrix
    20 ms beside the BLAS threads of other runs; a bincount per component copied each column, 34
    ms of a step of 256 cells)."""
    size = int(np.prod(values.shape[1:]))
    bins = (np.asarray(cells)[:, None] * size + np.arange(size)).ravel()
    sums = np.bincount(bins, weights=values.reshape(len(cells), size).ravel(), minlength=n * size)
    return sums.astype(float, copy=False).reshape((n,) + values.shape[1:])  # integers where there is no pair


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
        # of the last assembly: (pairs (2, P), each one's lattice square, spacing and heights (P, 5),
        # which of its points' rows were looked up (P, 4), those rows (P, 4, row))
        self._squares = None
        self.remainder = ManyBodyRemainder(hydro) if model.solver.many_body == "coarse" else None
        self.far = FarField(hydro) if model.solver.far_field == "moments" else None
        self.near_radius = model.solver.near_radius
        self.close = ClosePairs(hydro) if model.solver.close_pairs == "lubrication" else None
        self.clusters = (CloseClusters(hydro) if self.close is not None and model.solver.close_clusters == "resistance"
                         else None)

    def assemble(self, bodies):
        """(flow velocity, angular velocity (n, 3); basis velocity, angular velocity (6n, n, 3),
        iterations, residual) of the free ``bodies``: each cell's lone snapshot at its fine
        height, plus the pairs' part, plus the many-body remainder if asked for
        (``many_body.py``), the close pairs' films and the close clusters' three-body parts then
        added in resistance (``close_pairs.py``, ``close_clusters.py``)."""
        velocity, angular, basis_velocity, basis_angular, films, near = self._pairs_part(bodies)
        iterations, residual = 0, 0.0
        lone = self._lone_snapshots(bodies, self.hydro.tolerance)
        for b, (flow, grand) in lone.items():
            velocity[b] += flow.velocity[0]
            angular[b] += flow.angular_velocity[0]
            rows = slice(6 * b, 6 * b + 6)
            basis_velocity[rows, b] += grand.velocity[:, 0]
            basis_angular[rows, b] += grand.angular_velocity[:, 0]
            iterations += flow.iterations + grand.iterations
            residual = max(residual, flow.residual, grand.residual)
        if self.remainder is not None:
            for total, part in zip((velocity, angular, basis_velocity, basis_angular), self.remainder.parts(bodies)):
                total += part
        # the close pairs' films and clusters, added in resistance to all of the above
        terms = [(np.array([i, j]), film, None) for i, j, film in films]
        if films and self.clusters is not None:
            terms += self._cluster_terms(bodies, films, near, lone)
        if terms:
            velocity, angular, basis_velocity, basis_angular = with_resistance(
                velocity, angular, basis_velocity, basis_angular, self.radii, terms)
        return velocity, angular, basis_velocity, basis_angular, iterations, residual

    def _cluster_terms(self, bodies, films, near, lone) -> list:
        """[(cells, the correction to their resistance, to their holding loads)] of the close
        clusters among the films' pairs (close_clusters.py), from the near pairs' rows and lone
        snapshots at the pair heights (``near``, of ``_pairs_part``) and the cells' own lone
        snapshots (``lone``)."""
        near_first, near_second, rows, at_pair_heights = near
        film_of = {(i, j): film for i, j, film in films}
        first, second = (np.array([pair[k] for pair in film_of]) for k in (0, 1))
        terms = []
        for cells in clusters(first, second, len(bodies)):
            local = {int(c): k for k, c in enumerate(cells)}
            pairs = {}
            for p in np.flatnonzero(np.isin(near_first, cells) & np.isin(near_second, cells)):
                i, j = int(near_first[p]), int(near_second[p])
                parts = (part.reshape(shape) for part, shape in
                         zip(np.split(rows[p], np.cumsum(PART_SIZES)[:-1]), PART_SHAPES))
                pairs[local[i], local[j]] = generalised_matrices(*parts, self.radii[[i, j]]) + (film_of.get((i, j)),)
            own, shared = ([generalised_matrices(snapshots[c][0].velocity, snapshots[c][0].angular_velocity,
                                                 snapshots[c][1].velocity, snapshots[c][1].angular_velocity,
                                                 self.radii[[c]]) for c in cells.tolist()]
                           for snapshots in (lone, at_pair_heights))
            terms.append((cells,) + self.clusters.correction(bodies, cells, own, shared, pairs))
        return terms

    def _pairs_part(self, bodies):
        """sum over the pairs within the cut-off of [pair snapshot, interpolated at the pair's
        offset - each cell's lone snapshot at the pair's heights]: the flow's (n, 3) velocity and
        angular velocity corrections and the basis's (6n, n, 3) ones. A far pair's rows hold its
        coupling alone (far_field.py), so only the near pairs add to the cells' own blocks."""
        n = len(bodies)
        positions = np.array([body.position for body in bodies])
        first, second = np.triu_indices(n, 1)
        offsets = positions[second, :2] - positions[first, :2]
        distance = np.hypot(offsets[:, 0], offsets[:, 1])
        within = distance <= self.cutoff
        first, second, offsets, distance = first[within], second[within], offsets[within], distance[within]
        near = self._near(first, second, distance)
        close = near & self.close.takes(first, second, positions) if self.close is not None else np.zeros_like(near)
        rows = np.zeros((np.count_nonzero(near), sum(PART_SIZES)))  # of the near pairs
        lattice, close = ~close[near], close[near]
        near_first, near_second = first[near], second[near]
        if np.any(lattice):
            rows[lattice] = self._pair_rows(bodies, near_first[lattice], near_second[lattice], offsets[near][lattice])
        films = []
        if np.any(close):  # near contact: the two-sphere resistance plus the wall's part (close_pairs.py)
            rows[close], films = self._close_rows(bodies, near_first[close], near_second[close])
        flow_v, flow_w, grand_v, grand_w = (part.reshape((-1,) + shape) for part, shape in
                                            zip(np.split(rows, np.cumsum(PART_SIZES)[:-1], axis=1), PART_SHAPES))
        # (near pair, loaded cell, load component, responding cell, 3)
        grand_v, grand_w = (g.reshape(len(rows), 2, 6, 2, 3) for g in (grand_v, grand_w))
        # of every pair: (pair, loaded cell, load component, 3) the other cell's motion
        coupling_v, coupling_w = np.empty((len(first), 2, 6, 3)), np.empty((len(first), 2, 6, 3))
        for coupling, grand in ((coupling_v, grand_v), (coupling_w, grand_w)):
            coupling[near, 0], coupling[near, 1] = grand[:, 0, :, 1], grand[:, 1, :, 0]
        if not np.all(near):  # the far pairs add their coupling to the cells alone (far_field.py)
            far_rows = self.far.rows(bodies, first[~near], second[~near], offsets[~near])
            far_flow_v, far_flow_w, far_v, far_w = (part.reshape((-1,) + shape) for part, shape in zip(
                np.split(far_rows, np.cumsum(FAR_SIZES)[:-1], axis=1), COUPLING_SHAPES))
            coupling_v[~near], coupling_w[~near] = far_v, far_w
            near_flow_v, near_flow_w = flow_v, flow_w
            flow_v, flow_w = np.empty((len(first), 2, 3)), np.empty((len(first), 2, 3))
            flow_v[near], flow_w[near] = near_flow_v, near_flow_w
            flow_v[~near], flow_w[~near] = far_flow_v, far_flow_w
        velocity = summed(first, flow_v[:, 0], n) + summed(second, flow_v[:, 1], n)
        angular = summed(first, flow_w[:, 0], n) + summed(second, flow_w[:, 1], n)
        # (loaded cell, load component, responding cell, 3): a pair's loads on one cell and the
        # motion of the other land on its own entry, those on a cell and its own motion on the
        # cell's diagonal entry, summed over its near pairs
        cells = np.arange(n)
        basis_velocity, basis_angular = np.zeros((n, 6, n, 3)), np.zeros((n, 6, n, 3))
        for basis, coupling, grand in ((basis_velocity, coupling_v, grand_v), (basis_angular, coupling_w, grand_w)):
            basis[first, :, second], basis[second, :, first] = coupling[:, 0], coupling[:, 1]
            basis[cells, :, cells] = (summed(near_first, grand[:, 0, :, 0], n)
                                      + summed(near_second, grand[:, 1, :, 1], n))
        # each cell's lone snapshot at its pair height, once per near pair it is in
        pairs_of = np.bincount(np.concatenate([near_first, near_second]), minlength=n)
        lone = self._lone_snapshots(bodies, self.hydro.interaction, np.flatnonzero(pairs_of))
        for b, (lone_flow, lone_grand) in lone.items():
            velocity[b] -= pairs_of[b] * lone_flow.velocity[0]
            angular[b] -= pairs_of[b] * lone_flow.angular_velocity[0]
            basis_velocity[b, :, b] -= pairs_of[b] * lone_grand.velocity[:, 0]
            basis_angular[b, :, b] -= pairs_of[b] * lone_grand.angular_velocity[:, 0]
        return (velocity, angular, basis_velocity.reshape(6 * n, n, 3), basis_angular.reshape(6 * n, n, 3),
                films, (near_first, near_second, rows, lone))

    def _lone_snapshots(self, bodies, spacing: float, cells=None):
        """{cell: its lone snapshot} of ``cells`` (default all) at their heights snapped to
        ``spacing`` (``HydrodynamicSolves._lone``), looked up once per mesh and lattice height: the
        cells of a patch share a few. A height too near the wall for the lattice is solved as it
        is, cell by cell."""
        hydro = self.hydro
        cells = range(len(bodies)) if cells is None else cells
        heights = np.round(np.array([bodies[b].position[2] for b in cells]) / spacing).tolist()
        shared, found = {}, {}
        for b, height in zip(cells, heights):
            key = (hydro.lone_of[b], height)
            if key not in shared:
                try:
                    shared[key] = hydro._lone(b, bodies[b], spacing)
                except TooClose:
                    shared[key] = None
            found[b] = shared[key] or hydro._lone(b, bodies[b], spacing, exact_if_too_close=True)
        return found

    def _near(self, first, second, distance) -> np.ndarray:
        """(P,) which of the pairs at lateral ``distance`` (m) take pair snapshots: all without a
        far field, else those within near_radius (default NEAR_RADII mean outer radii)."""
        if self.far is None:
            return np.ones(len(first), bool)
        radius = self.near_radius
        if radius is None:
            radius = NEAR_RADII * 0.5 * (self.radii[first] + self.radii[second])
        return distance <= radius

    def _pair_rows(self, bodies, first, second, offsets) -> np.ndarray:
        """(P, row) the snapshots of the pairs (first[p], second[p]) at ``offsets`` (m, of the
        second cell from the first along the wall) as rows (part_row, in that order): the
        bilinear interpolation of their lattice points' snapshots, at the cells' heights on the
        pair lattice; a pair one of whose points is too near for a valid placement is solved as
        it is (not kept). Arrays over the pairs: the points' rows are looked up again only for
        the pairs whose lattice square, spacing or heights changed since the last assembly (or
        that now need a point they did not), so a step of 64 cells, 2016 pairs, loops over few."""
        heights = self._pair_heights(bodies)
        spacings = lateral_spacing(np.hypot(offsets[:, 0], offsets[:, 1]), self.base,
                                   self.radii[first] + self.radii[second])
        points, weights = lattice_corners(offsets, spacings)
        square = np.column_stack([points[:, 0], spacings, heights[first], heights[second]])
        pairs = np.stack([first, second])
        kept = self._squares
        if kept is None or not np.array_equal(kept[0], pairs):
            kept = self._squares = (pairs, np.full_like(square, np.nan), np.zeros(weights.shape, bool),
                                    np.zeros(weights.shape + (sum(PART_SIZES),)))
        _, squares, filled, point_rows = kept
        stale = np.any(square != squares, axis=1) | np.any((weights > 0) & ~filled, axis=1)
        squares[stale], filled[stale], point_rows[stale] = square[stale], False, 0.0
        too_close = self._look_up(bodies, first, second, points, weights, spacings, heights, stale)
        rows = np.einsum("pc,pcr->pr", weights, point_rows)  # the points never looked up hold zeros and weigh 0
        for p in too_close:
            squares[p] = np.nan  # looked up again at the next assembly
            rows[p] = self._solved_row(bodies, first[p], second[p])
        return rows

    def _close_rows(self, bodies, first, second):
        """((P, row) the smooth parts of the close pairs (first[p], second[p]) as rows (part_row),
        [(i, j, the film's resistance L)] of each): from the two-sphere resistance and the wall's
        part on its lattice at the pair lattice's heights, the film taken out (close_pairs.py);
        a pair one of whose lattice points is not a valid placement is solved as it is, whole,
        with no film."""
        heights = self._pair_heights(bodies)
        rows, films = np.zeros((len(first), sum(PART_SIZES))), []
        for p, (i, j) in enumerate(zip(first.tolist(), second.tolist())):
            try:
                rows[p] = part_row(*self.close.parts(bodies, i, j, heights))
                films.append((i, j, self.close.film(bodies, i, j)))
            except TooClose:
                rows[p] = self._solved_row(bodies, i, j)
        return rows, films

    def _pair_heights(self, bodies) -> np.ndarray:
        """(n,) m the cells' heights on the pair lattice (``reuse_interaction``)."""
        d = self.hydro.interaction
        return np.round(np.array([b.position[2] for b in bodies]) / d) * d

    def _solved_row(self, bodies, i: int, j: int) -> np.ndarray:
        """The part_row of the pair (i, j) solved as it is (not kept)."""
        flow, grand = self.hydro._solved([bodies[i], bodies[j]], self.radii[[i, j]])
        return part_row(flow.velocity, flow.angular_velocity, grand.velocity, grand.angular_velocity, False, False)

    def _look_up(self, bodies, first, second, points, weights, spacings, heights, stale) -> set:
        """Fill the kept rows (self._squares) of the ``stale`` pairs' lattice points of weight >
        0; the pairs one of whose points is too near for a valid placement (not filled)."""
        _, _, filled, point_rows = self._squares
        meshes = np.array(self.hydro.lone_of)
        pair_of, corner = np.nonzero(stale[:, None] & (weights > 0.0))
        canonical_points, hs, ms, swapped, mirrored = canonical(
            points[pair_of, corner], np.stack([heights[first], heights[second]], axis=1)[pair_of],
            np.stack([meshes[first], meshes[second]], axis=1)[pair_of])
        keys = zip(ms[:, 0].tolist(), ms[:, 1].tolist(), hs[:, 0].tolist(), hs[:, 1].tolist(),
                   spacings[pair_of].tolist(), canonical_points[:, 0].tolist(), canonical_points[:, 1].tolist())
        too_close = set()
        for k, key in enumerate(keys):
            p, c = int(pair_of[k]), int(corner[k])
            if p in too_close:
                continue
            try:
                point_rows[p, c] = self._point_row(bodies, (first[p], second[p]), ("pair",) + key, bool(swapped[k]),
                                                   bool(mirrored[k]))
                filled[p, c] = True
            except TooClose:
                too_close.add(p)
        return too_close

    def _point_row(self, bodies, cells, key, swapped: bool, mirrored: bool):
        """The part_row, in the order of the model's ``cells``, of the pair snapshot ``key``
        (("pair", meshes, heights, spacing, point): a lattice point's stored form, which
        ``swapped`` and ``mirrored`` map back to the cells), solved and kept if new."""
        if (key, swapped, mirrored) in self._rows:
            return self._rows[key, swapped, mirrored]
        hydro = self.hydro
        h0, h1, spacing, point = key[3], key[4], key[5], np.array(key[6:])
        order = cells[::-1] if swapped else cells
        offset = point * spacing
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
