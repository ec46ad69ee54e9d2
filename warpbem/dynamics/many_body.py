"""The part of many cells' grand mobility that their pairs leave out, from coarse cells
(``SolverOptions.many_body = "coarse"``; issue 25).

The pairs (``pairwise.py``) sum two-body couplings; what they leave out is the answer of a third
cell (and more) to the flow of the others. It grows with the cells around: 9.3e-4 of the flow's
motion for three 5 um cells in a line 25 um apart, 7.0e-3 in a 3 x 3 patch, 1.2e-2 in a 4 x 4
one (``benchmarks/many_cells.py --parts accuracy``, against the whole system's solve). Here it
is taken from the same cells on a coarse mesh, the k = 2 sphere of 24 elements without contact
refinement and with the biquadratic density, as the difference of that mesh's whole system and
its pairs at the cells' positions:

    M ~ M_pairs(fine) + [M_system(coarse) - M_pairs(coarse)],

and the flow's motion alike. The discretisation errors the two coarse terms share (each cell's
own near-wall mobility, by far the largest) cancel; the coupling through third cells is smooth at
tens of micrometres, where the coarse mesh resolves it, but only with the biquadratic density.
On 4 x 4 cells 25 um apart at one height (``--parts three_body``, against the largest entry of
the k = 3 biquadratic whole system) the part of the flow's motion is 1.08e-2 with the constant
density unrefined, 1.12e-2 and 1.23e-2 refined to ratios 0.5 and 1, and 1.28e-2 / 1.29e-2 with
the biquadratic density on the k = 2 / 3 spheres, unrefined: the constant density approaches
from below as it is refined, 2.1e-3 / 1.8e-3 / 6.2e-4 off the k = 3 biquadratic part, where the
k = 2 biquadratic one is 3.0e-4 off (the grand mobility's part, 1.7e-3, agrees to 1e-4 on all).
With the biquadratic density, on its lattice (below), against the whole system of 252-element
cells, 4 x 4 cells err by 2.1e-4 / 3.8e-4 (grand mobility / flow), 3 x 3 by 2.2e-4 / 3.1e-4, 2 x 2
by 7.1e-5 / 4.4e-5, three in a line by 2.1e-4 / 2.2e-4 (``--parts accuracy --solver-paths
--refinement 1``, column "pairs_remainder"); with the constant density 1.9e-4 / 2.0e-3 on 4 x 4.
Cells near contact are the close clusters' (``close_clusters.py``, in resistance): in mobility
the films of a train do not add.

The remainder is a snapshot as the others are (``hydrodynamics.py``): the cells' lateral
positions snapped to ``many_body_lateral`` (1 um: moving each of nine cells at random by up to
0.5 um added 3e-5 / 2e-4 to the error of the constant density's remainder) and their heights
rounded up to HEIGHT_LATTICE, keyed relative to the first cell (translation along the wall), so
it is a function of the state alone (resumed runs repeat uninterrupted ones). Its cost is the
coarse whole system's, 6 n + 1 solves of 648 n unknowns in one batched GMRES (6.1-7.3 s for 16
cells, against 0.3-0.4 s with the constant density's 72 n), and the coarse pairs' snapshots at
the snapped offsets, which the cells' lattice makes recur: 9.7 s in all for a 4 x 4 patch.
Beyond about 40 cells the biquadratic system no longer fits a dense matrix in a quarter of the
memory of a 25 GB machine ("auto"'s rule, which would take the treecode, one product per load),
and the remainder takes the constant density instead, with a warning
(LARGE_PATCH_DENSITY_ORDER). A patch that rolls as a whole keeps its
remainder. What it does not reach: linear cost (the coarse whole system grows as its unknowns
squared to cubed; a far field at coarse resolution would be needed) and close trains (the close
clusters' part).
"""

from __future__ import annotations

import warnings
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from ..hydro.mobility import ContactResolutionWarning
from ..hydro.operators.forms import choose_mode
from ..surfaces.body import Body
from ..surfaces.mesh import sphere
from ..surfaces.placement import PlacementError, check_placement
from .model import Model, build_solver, density_unknowns

# the coarse cells: the k = 2 sphere (24 elements), not refined near contact
COARSE_SUBDIVISIONS = 2
COARSE_REFINEMENT = 0.0
# the coarse cells' density (module docstring): biquadratic (27 unknowns per element, 648 per
# cell) while their whole system's matrix is dense ("auto"'s rule, operators/forms.py), else the
# constant density (72 per cell), whose remainder is 1.5e-3-2.0e-3 of the flow's motion off on
# 4 x 4 cells (at the cells' positions / on the lattice)
COARSE_DENSITY_ORDER = 3
LARGE_PATCH_DENSITY_ORDER = 1
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
        device = hydro.mobility.device
        order = COARSE_DENSITY_ORDER
        unknowns = density_unknowns([meshes[r] for r in radii], order)
        if choose_mode(unknowns, model.solver.dtype, device) != "dense":
            warnings.warn(f"many_body = 'coarse': the coarse system of {len(radii)} cells with the biquadratic"
                          f" density ({unknowns} unknowns) does not fit a dense matrix on {device}; the"
                          " remainder is taken with the constant density instead, 1.5e-3-2.0e-3 of the flow's"
                          " motion off on 4 x 4 cells where the biquadratic is 3.8e-4 (docs/many-cells.md)",
                          RuntimeWarning, stacklevel=2)
            order = LARGE_PATCH_DENSITY_ORDER
        options = replace(model.solver.without_accuracy(), many_body="none", far_field="none",
                          contact_refinement=COARSE_REFINEMENT, density_order=order,
                          reuse_tolerance=tiny, reuse_interaction=tiny, reuse_lateral=None, pair_lateral=tiny)
        coarse = Model([meshes[r] for r in radii], [False] * len(radii), model.flow, solver=options)
        self.coarse = type(hydro)(coarse, build_solver(coarse.solver, coarse.flow, device))
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
