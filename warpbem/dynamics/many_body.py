"""The part of many cells' grand mobility that their pairs leave out, from coarse cells
(``SolverOptions.many_body = "coarse"``; issue 25).

The pairs (``pairwise.py``) sum two-body couplings; what they leave out is the answer of a third
cell (and more) to the flow of the others. It grows with the cells around: 9.3e-4 of the flow's
motion for three 5 um cells in a line 25 um apart, 7.0e-3 in a 3 x 3 patch, 1.2e-2 in a 4 x 4
one (``benchmarks/many_cells.py --parts accuracy``, against the whole system's solve). Here it
is taken from the same cells on a coarse mesh, the k = 2 sphere of 24 elements without contact
refinement, as the difference of that mesh's whole system and its pairs at the cells' positions:

    M ~ M_pairs(fine) + [M_system(coarse) - M_pairs(coarse)],

and the flow's motion alike. The discretisation errors the two coarse terms share (each cell's
own near-wall mobility, by far the largest) cancel; the coupling through third cells is smooth at
tens of micrometres, where the coarse mesh resolves it. On 4 x 4 cells 25 um apart the errors
fall from 1.7e-3 / 1.2e-2 (grand mobility / flow) to 1.3e-4 / 1.5e-3, on 3 x 3 to 1.2e-4 /
8.9e-4, at 1/13-1/56 of the whole system's fine solve; at 12 um (2 um between the surfaces) only
to 2.1e-3 / 4.4e-3, since the coarse mesh does not resolve the gap between the cells (the
remainder at the cells' own positions; on its lattice, below, 1.3e-4 / 1.7e-3, 1.3e-4 / 9.5e-4
and 2.3e-3 / 4.2e-3, the benchmark's column "pairs_remainder").

The remainder is a snapshot as the others are (``hydrodynamics.py``): the cells' lateral
positions snapped to ``many_body_lateral`` (1 um: moving each of nine cells at random by up to
0.5 um added 3e-5 / 2e-4 to the error) and their heights rounded up to HEIGHT_LATTICE, keyed
relative to the first cell (translation along the wall), so it is a function of the state alone
(resumed runs repeat uninterrupted ones). Its cost is the coarse whole system's, 6 n + 1 solves
of 72 n unknowns in one batched GMRES (0.56 s for 16 cells, 8.0 s for 64, growing as n^1.66 from
4 to 64; one after the other 0.77 and 25.7 s: ``benchmarks/many_cells.py --parts batch``), and the coarse pairs'
snapshots at the snapped offsets, which the cells' lattice makes recur. A patch that rolls as a
whole keeps its remainder: 0.1 s of the 4 x 4 patch took 14 min 26 s with it, against 15 min 50 s
on the pairs alone (docs/many-cells.md). What it does not reach: linear cost (the
coarse whole system grows as n^1.66; a far field at coarse resolution would be needed) and close
trains (4.2e-3 of the flow's motion at 2 um between the surfaces).
"""

from __future__ import annotations

import warnings
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from ..hydro.mobility import ContactResolutionWarning
from ..surfaces.body import Body
from ..surfaces.mesh import sphere
from ..surfaces.placement import PlacementError, check_placement
from .model import Model, build_solver

# the coarse cells: the k = 2 sphere (24 elements), not refined near contact
COARSE_SUBDIVISIONS = 2
COARSE_REFINEMENT = 0.0
# m: the remainder's height lattice, rounded up (so a snapped cell never nears the wall). It hardly
# depends on the heights: the 3 x 3 patch's cells moved from their heights (+-20 nm) to one changed
# the remainder's error by 2e-5, all 25 nm up by 5e-5 (the script behind DEFAULT_MANY_BODY_LATERAL)
HEIGHT_LATTICE = 50e-9
# the coarse pairs' lattice at contact is this many times finer than many_body_lateral, so that
# the snapped offsets (multiples of it) are its points as it grows with distance (pairwise.py's
# lateral_spacing, in steps of 2): the coarse pairs are the direct two-body solves there
PAIR_LATTICE_SHARE = 2.0**20
MAX_REMAINDERS = 64  # kept remainder snapshots (64 cells: 1.2 MB each)


class ManyBodyRemainder:
    """The remainder (module docstring) of ``hydro``'s model: ``parts(bodies)`` gives the flow
    velocity, angular velocity (n, 3) and basis velocity, angular velocity (6n, n, 3) to add to
    the pairs' (``PairwiseMobility.assemble``), in the layout of ``HydrodynamicSolves``."""

    def __init__(self, hydro):
        model = hydro.model
        self.lateral = model.solver.many_body_lateral
        radii = model.outer_radii
        meshes = {r: sphere(r, COARSE_SUBDIVISIONS) for r in np.unique(radii)}
        tiny = self.lateral / PAIR_LATTICE_SHARE
        options = replace(model.solver.without_accuracy(), many_body="none", far_field="none",
                          contact_refinement=COARSE_REFINEMENT,
                          reuse_tolerance=tiny, reuse_interaction=tiny, reuse_lateral=None, pair_lateral=tiny)
        coarse = Model([meshes[r] for r in radii], [False] * len(radii), model.flow, solver=options)
        self.coarse = type(hydro)(coarse, build_solver(coarse.solver, coarse.flow, hydro.mobility.device))
        self.wall = model.flow.wall
        self._kept: OrderedDict = OrderedDict()
        self.solved = 0  # remainders solved (not taken from the kept ones)

    def parts(self, bodies):
        positions = np.array([b.position for b in bodies])
        lateral = np.round(positions[:, :2] / self.lateral).astype(int)
        lateral -= lateral[0]
        heights = np.ceil(positions[:, 2] / HEIGHT_LATTICE - 1e-9).astype(int)
        key = tuple(np.column_stack([lateral, heights]).ravel().tolist())
        if key in self._kept:
            self._kept.move_to_end(key)
            return self._kept[key]
        snapped = np.column_stack([lateral * self.lateral, heights * HEIGHT_LATTICE])
        try:
            check_placement([Body(m, position=p) for m, p in zip(self.coarse.model.meshes, snapped)], self.wall)
        except PlacementError:  # cells too close for the lattice: solved where they are, not kept
            return self._solved(positions - np.append(positions[0, :2], 0.0))
        self._kept[key] = self._solved(snapped)
        self.solved += 1
        while len(self._kept) > MAX_REMAINDERS:
            self._kept.popitem(last=False)
        return self._kept[key]

    def _solved(self, positions):
        """The remainder's parts of coarse cells at ``positions``: the whole system's snapshot
        minus the pairs' assembly at the same cells."""
        cells = [Body(m, position=p) for m, p in zip(self.coarse.model.meshes, positions)]
        with warnings.catch_warnings():  # the coarse cells leave the gap to the wall unresolved by design
            warnings.simplefilter("ignore", ContactResolutionWarning)
            flow, grand = self.coarse._solved(cells)
            velocity, angular, basis_velocity, basis_angular, _, _ = self.coarse.pairwise.assemble(cells)
        return (flow.velocity - velocity, flow.angular_velocity - angular, grand.velocity - basis_velocity,
                grand.angular_velocity - basis_angular)
