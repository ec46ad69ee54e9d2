"""Three or more cells near contact: the part their pairs leave out, added in resistance
(``SolverOptions.close_clusters = "resistance"``, with ``close_pairs = "lubrication"``).

In a train of cells near contact the middle cell screens the outer two, a three-body part that
neither the pairs (``pairwise.py``) nor their films (``close_pairs.py``) hold: three 5 um cells in a
line 0.2-2 um apart err by 1.2e-2-2.6e-2 in the grand mobility on the pairs with their films.
Added in mobility, as the many-body remainder of ``many_body.py`` is, it does not converge near
contact: the films of a train do not add in mobility, so the difference of a coarse whole system
and its coarse pairs holds what the coarse mesh makes of each film. In resistance the films are
pairwise (local to each gap; Durlofsky, Brady & Bossis 1987, J. Fluid Mech. 180:21), so the
three-body part

    R_3 = R_system - sum_i R_i - sum_{pairs (i, j)} [R_ij - R_i - R_j],

the whole system's resistance less its pairwise-additive sum, is smooth in the gaps, and a
coarser discretisation of the cluster gives it, its films cancelling in the difference. A cluster
(the cells joined by close pairs, three or more) then takes its resistance as the pairwise sum
of its own pairs (each the pair's snapshot with its film, the close pairs' model) plus R_3 of the
cluster solved on the k = 3 sphere with the biquadratic density, refined at contact to ratio 0.2
(CLUSTER_SUBDIVISIONS, CLUSTER_DENSITY_ORDER, CLUSTER_REFINEMENT): the correction to the
assembled resistance is

    dR = [sum of the pairs' resistances - the assembly's own resistance of the cluster alone] + R_3,

and the holding loads of the flow (f = R u) alike; ``pairwise.py`` adds it with the films, in one
Woodbury update (``close_pairs.with_resistance``). Three 5 um cells in a line at the rolling
height, built on the k = 4 sphere with the biquadratic density at ratio 0.35, against that
discretisation's direct solve of the three (grand mobility / flow's motion;
``benchmarks/many_cells.py --parts train --k 3``): on the pairs with their films 1.5e-2 / 2.1e-2
at 0.2 um between the surfaces and 1.2e-2-2.6e-2 / 1.8e-2-2.0e-2 at 0.35-2 um; with R_3 3.9e-4 /
5.9e-4 at 0.2 um (a cell 50 nm off the cluster lattice), 2.0e-4 / 3.1e-4 at 0.35 um (100 nm off)
and 1.6e-5 / 1.5e-5 or less from 0.5 um. The cluster mesh's solve of three cells and their new
pairs takes 2-6 s (the difference of the benchmark's two times). Taken in mobility from coarse
cells, as ``many_body.py`` takes its remainder, the same three cells 0.5 um apart on the k = 3
sphere stay 6.5e-3 / 2.9e-3 from their whole system, where the close clusters' part leaves
6.3e-4 / 1.4e-3, the k = 3 cells' own three-body error (``--parts accuracy --k 3``,
"pairs_remainder" and "pairs_far").

R_3 is a snapshot keyed by the cluster's meshes and its cells' positions relative to its first,
snapped along the wall to CLUSTER_LATERAL and in height to the pair lattice (``reuse_interaction``):
on these lattices three cells 0.2 um apart go from 3.7e-4 / 1.3e-4 at their own positions to
3.9e-4 / 5.9e-4 (``--parts train``), most of it the heights (in a script, moving the middle cell
by 50 nm along the wall changed R_3's result by 1e-5, raising all three by 25 nm the flow's
motion by 6e-4). A snapped cluster that is not a valid placement is solved where it is, not kept.
"""

from __future__ import annotations

import warnings
from collections import OrderedDict
from dataclasses import replace

import numpy as np
from scipy.linalg import block_diag
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..hydro.mobility import ContactResolutionWarning
from ..surfaces.body import Body
from ..surfaces.mesh import sphere
from ..surfaces.placement import PlacementError, check_placement
from .close_pairs import snapshot_matrices
from .model import Model, build_solver

# the cluster mesh (module docstring): the k = 3 sphere, biquadratic density, refined at contact
# to 0.2. Three k = 4 biquadratic cells 0.2 um apart on their own close pairs, against their direct
# solve, at their own positions (benchmarks/many_cells.py --parts train, many_cells_train_meshes.csv):
# this mesh 3.7e-4 / 1.3e-4 of the grand mobility / flow's motion, unrefined 4.0e-4 / 1.4e-4, k = 2
# at 0.35 3.6e-4 / 2.3e-4 (the close pairs' own error there, 2.3e-4, dominates these three), the
# bilinear k = 4 unrefined 1.9e-3 / 1.7e-3, the bilinear k = 3 at ratio 1 1.6e-3 / 1.4e-3. With the
# pairs solved directly instead (a script) the unrefined one gave 2.6e-4 / 1.1e-4, this one
# 2.2e-5 / 1.3e-5
CLUSTER_SUBDIVISIONS = 3
CLUSTER_DENSITY_ORDER = 3
CLUSTER_REFINEMENT = 0.2
# m: the lateral lattice of the clusters' positions (module docstring; with the heights on 20 nm it
# takes the flow's motion of three cells 0.2 um apart from 1.3e-4 to 5.9e-4, many_cells_train_meshes.csv)
CLUSTER_LATERAL = 250e-9
MAX_CLUSTERS = 64  # kept cluster snapshots
MAX_PIECES = 256  # kept solves of a cluster's cells alone and its pairs
PIECE_ROUND_OFF = 1e-12  # m: positions this close are one piece's
SMALLEST_CLUSTER = 3  # two close cells are their pair snapshot already


def clusters(first, second, n: int) -> list[np.ndarray]:
    """The cells joined by the close pairs (first[p], second[p]) of n cells, SMALLEST_CLUSTER or
    more each, each in ascending order."""
    if len(first) == 0:
        return []
    graph = coo_matrix((np.ones(len(first)), (first, second)), shape=(n, n))
    count, label = connected_components(graph, directed=False)
    found = [np.flatnonzero(label == c) for c in range(count)]
    return [cells for cells in found if len(cells) >= SMALLEST_CLUSTER]


def pairwise_resistance(alone, pairs):
    """(R, f) of m cells, the sum of each cell's resistance and holding loads alone and each
    pair's less its cells' alone: ``alone`` [(Q (6, 6), u (6,))] per cell and ``pairs`` {(i, j):
    (Q (12, 12), u (12,), film L (12, 12) or None)}, mobilities and the flow's motion in the
    snapshots' generalised coordinates (close_pairs.snapshot_matrices), a pair's Q smooth when
    its film is given."""
    m = len(alone)
    r, f = np.zeros((6 * m, 6 * m)), np.zeros(6 * m)
    own = [np.linalg.inv(q) for q, _ in alone]
    for i, ((_, u), r_i) in enumerate(zip(alone, own)):
        r[6 * i:6 * i + 6, 6 * i:6 * i + 6] += r_i
        f[6 * i:6 * i + 6] += r_i @ u
    for (i, j), (q, u, film) in pairs.items():
        rows = np.concatenate([np.arange(6 * i, 6 * i + 6), np.arange(6 * j, 6 * j + 6)])
        pair = np.linalg.inv(q)
        f[rows] += pair @ u - np.concatenate([own[i] @ alone[i][1], own[j] @ alone[j][1]])
        if film is not None:
            pair = pair + film
        pair[:6, :6] -= own[i]
        pair[6:, 6:] -= own[j]
        r[np.ix_(rows, rows)] += pair
    return r, f


class CloseClusters:
    """The three-body part R_3 (module docstring) of ``hydro``'s close clusters: ``part(bodies,
    cells)`` gives it in the cells' generalised coordinates, solved on the cluster mesh or kept."""

    def __init__(self, hydro):
        model = hydro.model
        radii = model.outer_radii
        meshes = {r: sphere(r, CLUSTER_SUBDIVISIONS) for r in np.unique(radii)}
        # solved directly, never from snapshots (so not from the disk store either)
        options = replace(model.solver.without_accuracy(), grand_mobility="system", many_body="none",
                          density_order=CLUSTER_DENSITY_ORDER, quadrature_order=None,
                          contact_refinement=CLUSTER_REFINEMENT, snapshot_store="off")
        self.radii = radii
        self.meshes = [meshes[r] for r in radii]
        self.heights = hydro.interaction
        self._solves_of = {}  # the cells' radii -> the cluster mesh's solves of those cells
        self._options, self._flow, self._device = options, model.flow, hydro.mobility.device
        self._solves_type = type(hydro)
        self._kept: OrderedDict = OrderedDict()
        self._pieces: OrderedDict = OrderedDict()  # (radii, relative positions) -> (Q, u) of a cell or pair
        self.solved = 0  # cluster snapshots solved (not taken from the kept ones)

    def correction(self, bodies, cells, own, shared, pairs) -> tuple[np.ndarray, np.ndarray]:
        """(dR (6m, 6m), df (6m,)) of the cluster ``cells`` (m model indices) of ``bodies``
        (module docstring): ``own`` and ``shared`` [(Q, u)] per cell, its lone snapshot at its
        own height and at the pair lattice's; ``pairs`` {(k, l): (Q, u, film or None)} of the
        cluster's near pairs (local indices, k < l), each the pair's snapshot at the pair lattice's
        heights (its smooth part where it has a film), all generalised (close_pairs.generalised_matrices)."""
        m = len(cells)
        assembled = np.zeros((6 * m, 6 * m))  # the assembly's own mobility of the cluster alone (pairwise.py)
        flow = np.concatenate([u for _, u in own])
        films = np.zeros((6 * m, 6 * m))
        each_pair = {}  # each pair's snapshot with its cells moved to their own heights
        for k, (q, _) in enumerate(own):
            assembled[6 * k:6 * k + 6, 6 * k:6 * k + 6] = q
        for (k, l), (q, u, film) in pairs.items():
            rows = np.concatenate([np.arange(6 * k, 6 * k + 6), np.arange(6 * l, 6 * l + 6)])
            lone_q, lone_u = block_diag(shared[k][0], shared[l][0]), np.concatenate([shared[k][1], shared[l][1]])
            assembled[np.ix_(rows, rows)] += q - lone_q
            flow[rows] += u - lone_u
            each_pair[k, l] = (q - lone_q + block_diag(own[k][0], own[l][0]),
                               u - lone_u + np.concatenate([own[k][1], own[l][1]]), film)
            if film is not None:
                films[np.ix_(rows, rows)] += film
        model = np.linalg.inv(assembled)
        summed, loads = pairwise_resistance(own, each_pair)
        three_body, three_body_loads = self.part(bodies, cells)
        return summed - (model + films) + three_body, loads - model @ flow + three_body_loads

    def part(self, bodies, cells) -> tuple[np.ndarray, np.ndarray]:
        """(R_3 (6m, 6m), its holding loads (6m,)) of the cluster ``cells`` (m model indices) of
        ``bodies``, at the cells' positions snapped (module docstring)."""
        positions = np.array([bodies[c].position for c in cells])
        lateral = np.round((positions[:, :2] - positions[0, :2]) / CLUSTER_LATERAL).astype(int)
        heights = np.round(positions[:, 2] / self.heights).astype(int)
        key = tuple(self.radii[cells].tolist()) + tuple(np.column_stack([lateral, heights]).ravel().tolist())
        if key in self._kept:
            self._kept.move_to_end(key)
            return self._kept[key]
        snapped = np.column_stack([lateral * CLUSTER_LATERAL, heights * self.heights])
        try:
            check_placement([Body(self.meshes[c], position=p) for c, p in zip(cells, snapped)],
                            self._flow.wall)
        except PlacementError:  # too close for the lattice: solved where the cells are, not kept
            return self._solved(cells, positions - np.append(positions[0, :2], 0.0))
        self._kept[key] = self._solved(cells, snapped)
        self.solved += 1
        while len(self._kept) > MAX_CLUSTERS:
            self._kept.popitem(last=False)
        return self._kept[key]

    def _solved(self, cells, positions):
        """R_3 of the cluster mesh's cells at ``positions``: its whole system's resistance and
        holding loads less their pairwise sum, each part solved directly."""
        m = len(cells)
        bodies = [Body(self.meshes[c], position=p) for c, p in zip(cells, positions)]
        radii = self.radii[cells]
        with warnings.catch_warnings():  # the cluster mesh is refined at contact; its wall gaps cancel in R_3
            warnings.simplefilter("ignore", ContactResolutionWarning)
            q, u = self._matrices(bodies, radii)
            alone = [self._piece(bodies, radii, [i]) for i in range(m)]
            pairs = {(i, j): self._piece(bodies, radii, [i, j]) + (None,) for i in range(m) for j in range(i + 1, m)}
        system = np.linalg.inv(q)
        summed, loads = pairwise_resistance(alone, pairs)
        return system - summed, system @ u - loads

    def _piece(self, bodies, radii, cells):
        """(Q, u) of the ``cells`` of ``bodies`` alone (a cell or a pair of the cluster), kept by
        their radii and positions relative to the first: a cluster that changes one gap keeps
        its other pairs and its cells alone."""
        positions = np.array([bodies[c].position for c in cells])
        relative = np.column_stack([positions[:, :2] - positions[0, :2], positions[:, 2]])
        key = tuple(radii[cells].tolist()) + tuple(np.round(relative / PIECE_ROUND_OFF).astype(int).ravel().tolist())
        if key not in self._pieces:
            self._pieces[key] = self._matrices([bodies[c] for c in cells], radii[cells])
            while len(self._pieces) > MAX_PIECES:
                self._pieces.popitem(last=False)
        self._pieces.move_to_end(key)
        return self._pieces[key]

    def _matrices(self, bodies, radii):
        """(Q, u) of ``bodies`` on the cluster mesh solved directly, generalised by their ``radii``."""
        key = tuple(radii.tolist())
        if key not in self._solves_of:
            model = Model([b.mesh for b in bodies], [False] * len(bodies), self._flow, solver=self._options)
            self._solves_of[key] = self._solves_type(model, build_solver(model.solver, model.flow, self._device))
        return snapshot_matrices(*self._solves_of[key]._solved(bodies, radii), radii)
