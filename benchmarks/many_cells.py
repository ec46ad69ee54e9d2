"""Many adhesive cells (issue 25), on the machine it runs on, side by side:

1. accuracy: the grand mobility and the motion in the flow of n rigid 5 um cells at the rolling
   height (heights spread by +-20 nm) against the whole system's solve, in the norm of
   ``benchmarks/adhesion.py`` part 2c (largest change over largest entry), from
   - the pairs (``[solver] grand_mobility = "pairs"``, dynamics/pairwise.py) at the cells' own
     positions, every pair from its snapshot ("pairwise": the approximation alone, close pairs
     with their films added in resistance and no close clusters' part; "pairwise_no_films":
     every pair's mobility summed, ``close_pairs = "lattice"``), the pairs
     beyond the near radius from the far field ("pairs_far", dynamics/far_field.py: the
     solver's default), and on the default lattices ("pairs_lattices");
   - the pairs with ``[solver] many_body = "coarse"`` (dynamics/many_body.py) at the cells' own
     positions ("pairs_remainder": its remainder on its lattice, 1 um, heights rounded up to 50 nm);
   - the pairs at the cells' own positions plus the many-body remainder of a coarse mesh: its
     whole system's solve minus its pairs, the three-body and higher part as that mesh sees it
     (the k = 2 sphere, 24 elements, unrefined and with the contact refinement 0.5 and 1:
     "remainder_RATIO"; unrefined with the biquadratic density, the solver's: "remainder_0_p3");
   - each fine cell alone plus the pairs' part of the coarse mesh ("coarse_pairs_RATIO": the
     coupling itself from the coarse pairs, which would make a pair snapshot 20-30 times cheaper);
   - the unrefined remainder from local clusters ("local_0"): each cell's rows from the cells
     within 2.05 pitches of it solved alone, a cost linear in the cells;
   - the cells alone (no coupling, for scale);
   cells in a line along the flow and in patches (rows of round(sqrt(n)) cells along the flow;
   ``--cases line:3:12 patch:16:25 ...`` to choose). The whole system of 16 refined k = 2 cells
   (78 000 unknowns) does not fit a dense matrix on a 24 GB machine: ``--refinement 1`` refines
   every solve but the remainders' less (252 elements per cell instead of 1632);
1a. resistance: the pairs' mobilities summed (the pairs' rule, at the cells' own positions) and
   the pairs' resistances summed and inverted (pairwise-additive resistance, Stokesian dynamics'
   rule for lubrication), both from direct solves of each cell alone and each pair alone,
   against the whole system's solve, on the accuracy part's cases;
1a'. three_body: the part the pairs leave out, D = M_system - M_pairs (the grand mobility and the
   flow's motion, every pair from its snapshot), of a 4 x 4 patch 25 um apart at one height, on
   several discretisations (THREE_BODY_MESHES: the k = 2 sphere with the constant density
   unrefined and refined with ratios 0.5 and 1, the k = 2 and 3 spheres with the biquadratic
   density unrefined), each against the finest (largest change over the largest entry of that
   one's whole system): whether the part is converged, and which coarse mesh gives it;
1b. cut-off: the error of leaving out pairs beyond 50-150 um on an 8 x 8 patch 25 um apart,
   against every pair (all from pair snapshots, no far field);
1b'. far: two cells at 12-200 um along a line 30 degrees off the flow, each alone plus the far
   field between them (far_field.py: the first reflection from each cell's traction moments),
   against their direct two-body solve, with the coupling itself and the part left out on each
   cell's own block (the second reflection) beside it: where the near radius sits;
1c. lattice: two cells (where the pairs are exact) at 12.5-40 um along a line 30 degrees off the
   flow, the pair's snapshot interpolated bilinearly between the points of its lattice (as the
   pairs do) and taken from the nearest point instead, against the direct solve, for lattices of
   several spacings;
1c'. close: two cells 0.05-2 um apart at the rolling height, along the flow and 30 degrees off it,
   their pair from the close-pair model (close_pairs.py: the exact two-sphere resistance plus the
   wall's part on a lattice of gaps) and from the pairs' lateral lattice, against their direct
   two-body solve; along the flow, against the direct solve on the k + 1 sphere with the
   biquadratic density (REFERENCE_DENSITY), beside the model built on that discretisation (the model's
   own error) and the k sphere's direct solve (the discretisation's);
1c''. train: three cells in a line along the flow 0.2-2 um apart between their surfaces at the
   rolling height, on the pairs (close pairs and their films) without and with the close
   clusters' three-body part (``close_clusters``, dynamics/close_clusters.py), each built on the
   k + 1 sphere with REFERENCE_DENSITY, against that discretisation's direct solve of the three
   (the model's own error), and the pairs with the clusters on the k sphere (time-stepped
   defaults) against it too; wall times, the clusters' solves included; at 0.2 um, the clusters'
   part from other cluster meshes, at the cells' own positions and on the cluster lattice;
1d. reuse: the pair lattice points a run's frames visit (``--runs RUN.h5 ...``, runs of free
   spherical cells on pairs): the interpolation's four around each pair's offset on the lattice
   that grows as distance^(5/2) from 250 nm (the pairs' rule), against the nearest point of the
   distance^4 lattice from 10 nm that the pairs snapped to before, heights on the pair height
   lattice in both. Counted at the frames only (the steps between them visit more points, the
   finer lattice more of them), so both counts are lower bounds;
1e. factors: pair snapshots of two cells at a run of lateral offsets 15-17.5 um (no contact
   refinement between them), with the solver's store of block factors (``hydro/block_factors.py``:
   each cell's LU taken from the store when its shape and height were seen) and without, the two
   interleaved; wall time per snapshot and the store's hits;
1f. batch: pair snapshots of two cells 12-13.5 um apart with the flow and the 12 loads solved
   in one batched GMRES (``MobilitySolver.solve_loads``, the solver's own) and one by one,
   interleaved; wall time, iterations and the difference between the two; and the coarse whole
   system of the many-body remainder (4-64 cells) batched and one by one;
2. cost per step: n cells rolling on stiff bonds (the state diagram's rolling point) for a
   short run from the same start, pairs, pairs with the coarse many-body remainder
   (``--remainder-cells``) and the whole system's snapshots (``--system-cells``), wall time and
   snapshots solved; the fitted exponent of the cost per step over n;
2b. implicit: the same on pairs (``--cells``, default 16 64; cells of ``--k`` subdivisions) with
   the implicit step's Newton step solved without forming its matrix (``implicit.MobilityResponse``:
   GMRES on (I + dt A Q) s = b, products O(p^2)) and from the matrix formed and factored by
   Cholesky (O(p^3), before it), interleaved cell count by cell count.

    python benchmarks/many_cells.py
        [--parts accuracy resistance three_body cutoff far close train lattice reuse factors batch cost implicit]
        [--runs RUN.h5 ...] [--quick]
        [--cells N ...] [--system-cells N ...] [--remainder-cells N ...] [--cases KIND:N:UM ...]
        [--refinement R] [--solver-paths] [--device cuda:0]

On a GPU, benchmarks/device_many_cells.sh measures the 8 x 8 patch's step on CUDA and on that
machine's CPU side by side (part 2).

Writes results/bench/many_cells_*.csv and many_cells.png.
"""

import contextlib
import json
import resource
import time
import warnings
from unittest import mock

import numpy as np

import warpbem as wb
from common import arguments, output as output_path, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress
from warpbem.dynamics import close_clusters, implicit
from warpbem.dynamics.hydrodynamics import HydrodynamicSolves, Motion
from warpbem.dynamics.model import Flow, Model, SolverOptions, StepPolicy, build_solver
from warpbem.dynamics.pairwise import lateral_spacing
from warpbem.hydro.options import DEFAULT_PAIR_CUTOFF
from warpbem.dynamics.simulator import Simulator
from warpbem.forces.adhesion import Adhesion
from warpbem.forces.bond_model import BondOptions
from warpbem.forces.external import STANDARD_GRAVITY, Gravity
from warpbem.forces.repulsion import Repulsion
from warpbem.surfaces.body import Body

warnings.simplefilter("ignore", wb.ContactResolutionWarning)
A = 5e-6
REST = A + 236e-9  # m: centre height where gravity and eq. 3.1 balance (benchmarks/adhesion.py)
# the state diagram's rolling point on stiff bonds (scenes/rolling_cells.toml)
ROLLING = dict(spring_constant=0.1, equilibrium_length=30e-9, off_rate=1.0, reactive_compliance=0.6e-10,
               on_rate=365.0, receptor_density=20e12, max_bonds=200)
# the accuracy part's coarse remainders: column suffix -> (contact refinement ratio, density order)
# of the k = 2 sphere (24 elements: 0 leaves it so, 0.5 and 1 split it to 108 and 252 elements at
# the rolling height, the default 3 to 1632; order 1 the time-stepped models' constant density, 3
# the biquadratic one of dynamics/many_body.py)
COARSE_REMAINDERS = {"0": (0.0, 1), "0.5": (0.5, 1), "1": (1.0, 1), "0_p3": (0.0, 3)}
COARSE_K = 2
# --parts three_body's discretisations (k, density order, contact refinement), the reference last
# (the k = 4 biquadratic sphere, 41 500 unknowns for 16 cells, peaked at 20 GB: not run on 24 GB)
THREE_BODY_MESHES = [(2, 1, 0.0), (2, 1, 0.5), (2, 1, 1.0), (2, 3, 0.0), (3, 3, 0.0)]
# the local remainder's clusters: the cells within this many pitches of each (two cells on in a
# line, so that an end cell's cluster holds the cell that screens it from the next; 1.5 left the
# flow's error of three cells in a line 25 um apart at 9.3e-4, the pairs')
LOCAL_RADIUS = 2.05
# the snapshots of --parts cost: the pairs, the pairs with the coarse many-body remainder
# (dynamics/many_body.py), the whole system's
MODES = {"pairs": dict(grand_mobility="pairs"), "remainder": dict(grand_mobility="pairs", many_body="coarse"),
         "system": dict(grand_mobility="system")}
EXACT = dict(reuse_tolerance=1e-12, reuse_interaction=1e-12, pair_lateral=1e-12)  # lattices below round-off
# the accuracy part's solver paths (column prefix -> options): every pair from its snapshot, with
# and without the close pairs' films; the far field beyond near_radius; the lattices; the remainder
SOLVER_PATHS = {"pairwise": dict(EXACT, grand_mobility="pairs", far_field="none", close_clusters="none"),
                "pairwise_no_films": dict(EXACT, grand_mobility="pairs", far_field="none", close_pairs="lattice"),
                "pairs_far": dict(EXACT, grand_mobility="pairs"),
                "pairs_lattices": dict(reuse_tolerance=2e-9, grand_mobility="pairs"),
                "pairs_remainder": dict(EXACT, grand_mobility="pairs", many_body="coarse")}


def arrangement(kind, n, spacing, seed=1):
    """(n, 3) centres: ``line`` along the flow or a square ``patch`` (rows along the flow),
    heights REST +- 20 nm (seeded)."""
    rng = np.random.default_rng(seed)
    if kind == "line":
        lateral = [(spacing * i, 0.0) for i in range(n)]
    else:
        side = int(round(np.sqrt(n)))
        lateral = [(spacing * (i % side), spacing * (i // side)) for i in range(n)]
    return np.array([(x, y, REST + rng.uniform(-20e-9, 20e-9)) for x, y in lateral])


def motion(flow, grand):
    """(grand mobility Q, the flow's velocity and angular velocity times A) of a snapshot."""
    return grand.quadratic(), np.concatenate([flow.velocity.ravel(), flow.angular_velocity.ravel() * A])


def change(a, b):
    return [np.abs(x - y).max() / np.abs(y).max() for x, y in zip(a, b)]


def solves(mesh, n, device, **solver):
    model = Model([mesh] * n, [False] * n, Flow(100.0, 1e-3), solver=SolverOptions(**solver))
    return HydrodynamicSolves(model, build_solver(model.solver, model.flow, device))


def coarse_parts(device, positions, coarse_k, options):
    """(the coarse whole system's (Q, flow motion), its wall time, the coarse pairs', the coarse
    cells' alone) of cells at ``positions`` on the coarse mesh (``coarse_k`` subdivisions, solver
    ``options``), each at the cells' own positions."""
    mesh = wb.mesh.sphere(A, coarse_k)
    bodies = [Body(mesh, position=p) for p in positions]
    hydro = solves(mesh, len(bodies), device, **options)
    t = time.perf_counter()
    system = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
    wall = time.perf_counter() - t
    # every pair from its snapshot, as dynamics/many_body.py takes them (no far field)
    pairs, alone = (motion(*solves(mesh, len(bodies), device, **EXACT, grand_mobility="pairs", pair_cutoff=cutoff,
                                   far_field="none", **options)._snapshot(bodies))
                    for cutoff in (DEFAULT_PAIR_CUTOFF, 0.0))
    return system, wall, pairs, alone


def remainder(device, positions, coarse_k, options):
    """(the many-body remainder (Q, flow motion), the coarse whole system's wall time): the coarse
    whole system's solve minus the coarse pairs (``coarse_parts``), the part the pairs leave out
    as the coarse mesh sees it."""
    system, wall, pairs, _ = coarse_parts(device, positions, coarse_k, options)
    return tuple(a - b for a, b in zip(system, pairs)), wall


def local_remainder(device, positions, coarse_k, options, radius):
    """(the many-body remainder from local clusters, the clusters' wall time, the largest cluster):
    each cell's rows of ``remainder`` solved for the cluster of cells within ``radius`` (m, along
    the wall) of it alone, the grand mobility's then symmetrised: a cost linear in the cells for
    clusters of bounded size, leaving out the many-body part through cells beyond the radius."""
    n = len(positions)
    q, u, wall, largest = np.zeros((6 * n, 6 * n)), np.zeros(6 * n), 0.0, 0
    for i in range(n):
        cells = list(np.flatnonzero(np.hypot(*(positions[:, :2] - positions[i, :2]).T) <= radius))
        (cluster_q, cluster_u), cluster_wall = remainder(device, positions[cells], coarse_k, options)
        cluster_q, cluster_u = embed(cluster_q, cluster_u, cells, n)
        q[6 * i:6 * i + 6] = cluster_q[6 * i:6 * i + 6]
        for part in (slice(3 * i, 3 * i + 3), slice(3 * n + 3 * i, 3 * n + 3 * i + 3)):
            u[part] = cluster_u[part]
        wall, largest = wall + cluster_wall, max(largest, len(cells))
    return (0.5 * (q + q.T), u), wall, largest


def accuracy(device, cases, k, refinement=None, extras=True, paths=None):
    """Part 1 on ``cases`` ((arrangement, cells, spacing)), every solve but the coarse remainders'
    on the k sphere refined with ``refinement`` (default: the time-stepped models' 3); without
    ``extras`` the solver's own paths only (no coarse remainders at other refinements, no local
    clusters); ``paths`` the names of SOLVER_PATHS to run (default all; with extras "pairwise"
    is needed)."""
    mesh = wb.mesh.sphere(A, k)
    fine = {} if refinement is None else dict(contact_refinement=refinement)
    rows, progress = [], Progress(len(cases))
    for kind, n, spacing in cases:
        positions = arrangement(kind, n, spacing)
        bodies = [Body(mesh, position=p) for p in positions]
        hydro = solves(mesh, n, device, **fine)
        t = time.perf_counter()
        exact = motion(Motion.of(hydro.mobility.solve(bodies)), hydro._grand_mobility(bodies))
        t_system = time.perf_counter() - t
        row = dict(arrangement=kind, cells=n, spacing_um=spacing * 1e6, k=k,
                   refinement=hydro.model.solver.contact_refinement, system_s=t_system)
        approximations = {}
        for name, options in SOLVER_PATHS.items():
            if paths is not None and name not in paths:
                continue
            pairs = solves(mesh, n, device, **options, **fine)
            t = time.perf_counter()
            approximations[name] = motion(*pairs._snapshot(bodies))
            grand, flow = change(approximations[name], exact)
            row.update({f"{name}_grand": grand, f"{name}_flow": flow, f"{name}_s": time.perf_counter() - t,
                        f"{name}_snapshots": pairs.snapshots_solved})
        approximations["alone"] = motion(*solves(mesh, n, device, **EXACT, grand_mobility="pairs", pair_cutoff=0.0,
                                                 **fine)._snapshot(bodies))
        row["alone_grand"], row["alone_flow"] = change(approximations["alone"], exact)
        if not extras:
            rows.append(row)
            print_table([row])
            progress.done(f"accuracy: {kind} of {n} cells, {spacing * 1e6:g} um apart")
            continue
        pairwise_grand, pairwise_flow = approximations["pairwise"]
        for suffix, (ratio, order) in COARSE_REMAINDERS.items():  # added to the pairs at the cells' own positions
            if ratio >= row["refinement"]:
                continue  # no coarser than the reference itself
            system, wall, pairs, alone = coarse_parts(device, positions, COARSE_K,
                                                      dict(contact_refinement=ratio, density_order=order))
            row[f"remainder_{suffix}_grand"], row[f"remainder_{suffix}_flow"] = change(
                tuple(a + s - p for a, s, p in zip(approximations["pairwise"], system, pairs)), exact)
            row[f"remainder_{suffix}_system_s"] = wall
            # the coupling itself from the coarse pairs: each fine cell alone plus the coarse pairs'
            # part (their pairs' snapshots minus the coarse cells alone)
            row[f"coarse_pairs_{suffix}_grand"], row[f"coarse_pairs_{suffix}_flow"] = change(
                tuple(a + p - c for a, p, c in zip(approximations["alone"], pairs, alone)), exact)
        (grand, flow), wall, largest = local_remainder(device, positions, COARSE_K, dict(contact_refinement=0.0),
                                                       LOCAL_RADIUS * spacing)
        row["local_0_grand"], row["local_0_flow"] = change((pairwise_grand + grand, pairwise_flow + flow), exact)
        row["local_0_s"], row["local_largest_cluster"] = wall, largest
        rows.append(row)
        print_table([row])
        progress.done(f"accuracy: {kind} of {n} cells, {spacing * 1e6:g} um apart")
    return rows


def embedded(hydro, bodies, cells, n):
    """(Q (6n, 6n), flow motion (6n,)) of the ``cells`` among n solved alone, in the n cells'
    layout: Q by loads on each cell in turn, the motion as ``motion`` gives it."""
    return embed(*motion(Motion.of(hydro.mobility.solve([bodies[c] for c in cells])),
                         hydro._grand_mobility([bodies[c] for c in cells])), cells, n)


def embed(q, u, cells, n):
    """(Q, flow motion) of the ``cells`` in the layout of n cells (zero elsewhere)."""
    m, rows = len(cells), np.concatenate([np.arange(6 * c, 6 * c + 6) for c in cells])
    big_q, big_u = np.zeros((6 * n, 6 * n)), np.zeros(6 * n)
    big_q[np.ix_(rows, rows)] = q
    for s, c in enumerate(cells):
        big_u[3 * c:3 * c + 3], big_u[3 * n + 3 * c:3 * n + 3 * c + 3] = u[3 * s:3 * s + 3], u[3 * m + 3 * s:3 * m + 3 * s + 3]
    return big_q, big_u


def per_cell(u, n):
    """The flow motion (6n,) of ``motion``'s layout as n blocks of (U, A Omega), and back."""
    return u.reshape(2, n, 3).transpose(1, 0, 2).ravel()


def resistance_error(device, cases, k):
    """The pairwise-additive mobility and resistance against the whole system (part 1a)."""
    mesh = wb.mesh.sphere(A, k)
    rows, progress = [], Progress(len(cases))
    for kind, n, spacing in cases:
        bodies = [Body(mesh, position=p) for p in arrangement(kind, n, spacing)]
        exact = embedded(solves(mesh, n, device), bodies, list(range(n)), n)
        one, two = solves(mesh, 1, device), solves(mesh, 2, device)
        lone = [embedded(one, bodies, [i], n) for i in range(n)]
        pairs = {(i, j): embedded(two, bodies, [i, j], n) for i in range(n) for j in range(i + 1, n)}
        q = sum(l[0] for l in lone) + sum(p[0] - lone[i][0] - lone[j][0] for (i, j), p in pairs.items())
        u = sum(l[1] for l in lone) + sum(p[1] - lone[i][1] - lone[j][1] for (i, j), p in pairs.items())

        def resistance(qu, cells):  # (R, R U) of the cells' block; the flow motion as loads
            rows = np.concatenate([np.arange(6 * c, 6 * c + 6) for c in cells])
            r = np.zeros_like(qu[0])
            r[np.ix_(rows, rows)] = np.linalg.inv(qu[0][np.ix_(rows, rows)])
            return r, r @ per_cell(qu[1], n)

        alone = [resistance(lone[i], [i]) for i in range(n)]
        parts = alone + [(r - alone[i][0] - alone[j][0], f - alone[i][1] - alone[j][1])
                         for (i, j), p in pairs.items() for r, f in [resistance(p, [i, j])]]
        r, f = sum(x[0] for x in parts), sum(x[1] for x in parts)
        m = np.linalg.inv(r)
        summed_resistance = (0.5 * (m + m.T), (m @ f).reshape(n, 2, 3).transpose(1, 0, 2).ravel())
        (mobility_grand, mobility_flow), (resistance_grand, resistance_flow) = (
            change(x, exact) for x in ((q, u), summed_resistance))
        rows.append(dict(arrangement=kind, cells=n, spacing_um=spacing * 1e6, k=k, mobility_grand=mobility_grand,
                         mobility_flow=mobility_flow, resistance_grand=resistance_grand,
                         resistance_flow=resistance_flow))
        print_table([rows[-1]])
        progress.done(f"resistance: {kind} of {n} cells, {spacing * 1e6:g} um apart")
    return rows


def three_body_convergence(device, n, spacing, meshes):
    """Part 1a': the pairs' left-out part D = system - pairs of a patch of n cells at one height
    on each of ``meshes`` ((k, density order, contact refinement)), each against the last's."""
    positions = arrangement("patch", n, spacing)
    positions[:, 2] = REST  # one height, so that the pairs' snapshots recur by offset
    parts, progress = [], Progress(len(meshes))
    for k, order, ratio in meshes:
        t = time.perf_counter()
        # dense on any machine: where a matrix passes a quarter of the memory "auto" takes the treecode,
        # one product per load (the k = 3 biquadratic system of 16 cells is 4.3 GB)
        system, wall, pairs, _ = coarse_parts(device, positions, k, dict(contact_refinement=ratio, density_order=order,
                                                                        operator="dense"))
        parts.append((system, [a - b for a, b in zip(system, pairs)], wall, time.perf_counter() - t))
        progress.done(f"three_body: k = {k}, p = {order}, ratio {ratio:g}")
    reference_system, reference, _, _ = parts[-1]
    scale = [np.abs(x).max() for x in reference_system]
    rows = []
    for (k, order, ratio), (_, part, wall, total) in zip(meshes, parts):
        size, off = ([np.abs(x).max() / largest for x, largest in zip(values, scale)] for values in
                     (part, [a - b for a, b in zip(part, reference)]))
        rows.append(dict(cells=n, spacing_um=spacing * 1e6, k=k, density_order=order, refinement=ratio,
                         part_grand=size[0], part_flow=size[1], off_reference_grand=off[0], off_reference_flow=off[1],
                         system_s=wall, total_s=total))
    print_table(rows)
    return rows


def cutoff_error(device, side, spacing, cutoffs, k):
    """The error of leaving out pairs beyond each cut-off on a side x side patch at one height,
    against the pairs without a cut-off (every pair, so no whole-system solve is needed)."""
    mesh = wb.mesh.sphere(A, k)
    n = side * side
    positions = arrangement("patch", n, spacing)
    positions[:, 2] = REST
    bodies = [Body(mesh, position=p) for p in positions]
    hydro = solves(mesh, n, device, reuse_tolerance=2e-9, grand_mobility="pairs", pair_cutoff=1e-2, far_field="none")
    every = motion(*hydro._snapshot(bodies))
    rows, progress = [], Progress(len(cutoffs))
    for cutoff in cutoffs:  # the same pair snapshots, fewer of them summed
        hydro.pairwise.cutoff = cutoff
        grand, flow = change(motion(*hydro._snapshot(bodies)), every)
        rows.append(dict(cells=n, spacing_um=spacing * 1e6, cutoff_um=cutoff * 1e6, grand=grand, flow=flow))
        print_table([rows[-1]])
        progress.done(f"cut-off {cutoff * 1e6:g} um")
    return rows


def lattice_error(device, distances, bases, k):
    """The lattice's error on two cells at one height: the pair's snapshot interpolated (the
    pairs' rule) and at the nearest lattice point, against the direct solve, for each ``base``
    (pair_lateral; the lattice spacing at each distance follows from it)."""
    mesh = wb.mesh.sphere(A, k)
    direction = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    rows, progress = [], Progress(len(distances) * len(bases))
    for distance in distances:
        offset = distance * direction
        bodies = [Body(mesh, position=(0.0, 0.0, REST)), Body(mesh, position=(*offset, REST))]
        direct_solves = solves(mesh, 2, device)
        exact = motion(Motion.of(direct_solves.mobility.solve(bodies)), direct_solves._grand_mobility(bodies))
        for base in bases:
            hydro = solves(mesh, 2, device, reuse_tolerance=1e-12, reuse_interaction=1e-12, grand_mobility="pairs",
                           pair_lateral=base)
            spacing = lateral_spacing(distance, base, 2 * A)
            interpolated = max(change(motion(*hydro._snapshot(bodies)), exact))
            nearest = [bodies[0], Body(mesh, position=(*(np.round(offset / spacing) * spacing), REST))]
            snapped = max(change(motion(*hydro._snapshot(nearest)), exact))  # a corner above: no new solve
            rows.append(dict(distance_um=distance * 1e6, pair_lateral_nm=base * 1e9, spacing_nm=spacing * 1e9,
                             interpolated=interpolated, nearest_point=snapped, snapshots=hydro.snapshots_solved))
            print_table([rows[-1]])
            progress.done(f"lattice: {distance * 1e6:g} um apart, pair_lateral {base * 1e9:g} nm")
    return rows


def far_error(device, distances, k):
    """The far field's error on two cells (far_field.py: each cell's traction moments with the
    wall's images) against their pair snapshot (the direct two-body solve, exact for two cells),
    at ``distances`` along a line 30 degrees off the flow, heights REST and REST + 13 nm; the
    coupling itself (the cells alone against the direct solve) for scale, and the part the first
    reflection leaves out on each cell's own block (the grand mobility's diagonal blocks of the
    direct solve against the cells alone)."""
    mesh = wb.mesh.sphere(A, k)
    direction = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    rows, progress = [], Progress(len(distances))
    far = solves(mesh, 2, device, **EXACT, grand_mobility="pairs", near_radius=1e-9)
    alone = solves(mesh, 2, device, **EXACT, grand_mobility="pairs", pair_cutoff=0.0)
    direct_solves = solves(mesh, 2, device)
    for distance in distances:
        bodies = [Body(mesh, position=(0.0, 0.0, REST)), Body(mesh, position=(*(distance * direction), REST + 13e-9))]
        t = time.perf_counter()
        exact = motion(Motion.of(direct_solves.mobility.solve(bodies)), direct_solves._grand_mobility(bodies))
        pair_s = time.perf_counter() - t
        t = time.perf_counter()
        modelled = motion(*far._snapshot(bodies))
        far_s = time.perf_counter() - t
        cells_alone = motion(*alone._snapshot(bodies))
        own = np.zeros_like(exact[0], dtype=bool)
        own[:6, :6] = own[6:, 6:] = True
        rows.append(dict(distance_um=distance * 1e6, coupling_grand=change(cells_alone, exact)[0],
                         coupling_flow=change(cells_alone, exact)[1], far_grand=change(modelled, exact)[0],
                         far_flow=change(modelled, exact)[1],
                         own_blocks=np.abs((cells_alone[0] - exact[0])[own]).max() / np.abs(exact[0]).max(),
                         pair_snapshot_s=pair_s, far_s=far_s))
        print_table([rows[-1]])
        progress.done(f"far field: {distance * 1e6:g} um apart")
    return rows


def visited_points(path, interaction=20e-9):
    """(points the interpolation visits, points the nearest-point rule visits, pairs, frames) of
    a run's frames (module docstring, 1d): lattice points as (heights, spacing, point) of each
    pair, the same pair key modulo the symmetries as the pairs' store."""
    from warpbem.app.io import open_result
    from warpbem.dynamics.pairwise import canonical, lattice_corners

    with open_result(path) as f:
        positions = f["position"][:]
        scene = json.loads(f.attrs["scene"])
    meshes = [b["mesh"] for b in scene.get("bodies", [])] + [a["mesh"] for a in scene.get("arrays", [])]
    if any(m.get("shape") != "sphere" or m.get("radius") != A for m in meshes):
        raise SystemExit(f"{path}: --parts reuse counts runs of {A * 1e6:g} um spheres only")
    radii = np.full(positions.shape[1], A)
    interpolated, nearest = set(), set()
    first, second = np.triu_indices(positions.shape[1], 1)
    within = np.hypot(*(positions[0, second, :2] - positions[0, first, :2]).T) <= DEFAULT_PAIR_CUTOFF
    first, second = first[within], second[within]  # the pairs within the cut-off at the start
    contact = radii[first] + radii[second]

    def stored(points, spacings, heights):
        points, heights, _, _, _ = canonical(points, heights, np.zeros((len(points), 2), int))
        return set(zip(heights[:, 0], heights[:, 1], spacings, points[:, 0], points[:, 1]))

    for frame in positions:
        heights = np.round(frame[:, 2] / interaction) * interaction
        hs = np.stack([heights[first], heights[second]], axis=1)
        offsets = frame[second, :2] - frame[first, :2]
        distance = np.hypot(offsets[:, 0], offsets[:, 1])
        spacings = lateral_spacing(distance, 250e-9, contact)
        points, weights = lattice_corners(offsets, spacings)
        used, corner = np.nonzero(weights > 0)
        interpolated |= stored(points[used, corner], spacings[used], hs[used])
        # the rule before: the nearest point of a lattice growing as distance^4 from 10 nm
        level = np.minimum(4.0 * np.log2(np.maximum(distance, contact) / contact), np.log2(distance / (8 * 10e-9)))
        fine = 10e-9 * 2.0 ** np.maximum(0, np.floor(level))
        nearest |= stored(np.round(offsets / fine[:, None]).astype(int), fine, hs)
    return len(interpolated), len(nearest), len(first), len(positions)


def factor_store(device, k, count):
    """Wall time of ``count`` pair snapshots (13 solves each, the pairs' own) with the store of block
    factors and without it, interleaved offset by offset."""
    mesh = wb.mesh.sphere(A, k)
    kept, plain = (solves(mesh, 2, device, reuse_tolerance=2e-9, grand_mobility="pairs") for _ in range(2))
    plain.mobility._factors = None
    walls, progress = {"store": [], "no store": []}, Progress(count)
    for i in range(count):
        bodies = [Body(mesh, position=(0.0, 0.0, REST)), Body(mesh, position=(15e-6 + 0.5e-6 * i, 0.0, REST + 20e-9))]
        for name, hydro in (("store", kept), ("no store", plain)):
            t = time.perf_counter()
            hydro._solved(bodies)
            walls[name].append(time.perf_counter() - t)
        progress.done(f"snapshot {i + 1}, with the store and without")
    store = kept.mobility._factors
    rows = [dict(k=k, snapshots=count, store=name, mean_s=float(np.mean(w)), first_s=w[0], later_mean_s=float(np.mean(w[1:])),
                 hits=store.hits if name == "store" else 0) for name, w in walls.items()]
    print_table(rows)
    print(f"later snapshots: the store takes {rows[0]['later_mean_s'] / rows[1]['later_mean_s']:.2f} of the time")
    return rows


def batched_loads(device, k, count):
    """Wall time of ``count`` pair snapshots of two cells 12-13.5 um apart (refined between them,
    so no block repeats) with the flow and the 12 loads solved in one batched GMRES (the pairs'
    own, ``MobilitySolver.solve_loads``) and one after the other (as before it), interleaved
    offset by offset, and the largest difference between their grand mobilities."""
    mesh = wb.mesh.sphere(A, k)
    batched, sequential = (solves(mesh, 2, device, reuse_tolerance=2e-9, grand_mobility="pairs") for _ in range(2))
    rows, progress = [], Progress(count)
    for i in range(count):
        bodies = [Body(mesh, position=(0.0, 0.0, REST)),
                  Body(mesh, position=(12e-6 + 0.5e-6 * i, 0.3e-6, REST + 20e-9))]
        t = time.perf_counter()
        _, grand = batched._solved(bodies)
        batched_s = time.perf_counter() - t
        t = time.perf_counter()
        solver = sequential.mobility
        flow = solver.solve(bodies, check_placement_first=False, factor_every_body=True)
        loads = sequential._body_loads(2)
        one_by_one = [solver.solve(bodies, 1e-12 * f, 1e-12 * q, check_placement_first=False, background=False)
                      for f, q in zip(*loads)]
        sequential_s = time.perf_counter() - t
        velocity = np.array([s.velocity for s in one_by_one]) / 1e-12
        raw = batched._responses(bodies, *loads)  # the same system kept: its loads once more, unsymmetrised
        rows.append(dict(k=k, distance_um=float(np.hypot(*bodies[1].position[:2])) * 1e6, batched_s=batched_s,
                         one_by_one_s=sequential_s, ratio=sequential_s / batched_s,
                         iterations_batched=grand.iterations, flow_iterations=flow.iterations,
                         iterations_one_by_one=sum(s.iterations for s in one_by_one),
                         difference=float(np.abs(raw.velocity - velocity).max() / np.abs(velocity).max())))
        print_table([rows[-1]])
        progress.done(f"batched loads: snapshot {i + 1}")
    print(f"one by one over batched: {np.mean([r['ratio'] for r in rows]):.2f} times the time (mean)")
    return rows


def batched_coarse_systems(device, counts):
    """Wall time of the coarse whole system's snapshot (the many-body remainder's: k = 2 cells of
    24 elements, patches 25 um apart) with its 6 n + 1 solves batched and one by one."""
    mesh = wb.mesh.sphere(A, COARSE_K)
    warm_up = [Body(mesh, position=p) for p in arrangement("patch", 4, 25e-6)]
    solves(mesh, 4, device, contact_refinement=0.0)._solved(warm_up)  # the process's first solves load kernels
    rows, progress = [], Progress(len(counts))
    for n in counts:
        bodies = [Body(mesh, position=p) for p in arrangement("patch", n, 25e-6)]
        batched, sequential = (solves(mesh, n, device, contact_refinement=0.0) for _ in range(2))
        t = time.perf_counter()
        batched._solved(bodies)
        batched_s = time.perf_counter() - t
        t = time.perf_counter()
        sequential.mobility.solve(bodies, check_placement_first=False, factor_every_body=True)
        for f, q in zip(*sequential._body_loads(n)):
            sequential.mobility.solve(bodies, 1e-12 * f, 1e-12 * q, check_placement_first=False, background=False)
        rows.append(dict(cells=n, unknowns=sequential.mobility.last_system[0].size, batched_s=batched_s,
                         one_by_one_s=time.perf_counter() - t))
        print_table([rows[-1]])
        progress.done(f"coarse system: {n} cells")
    for key in ("batched_s", "one_by_one_s"):
        slope, _ = exponent(rows, key)
        print(f"{key}: n^{slope:.2f}")
    return rows


def rolling_patch(n, spacing, mode, k=3, seed=1):
    """(model, state) of n rigid cells rolling on stiff bonds, released at the rest height in a
    line (n <= 3) or a square patch, with the snapshots of ``mode`` (MODES)."""
    mesh = wb.mesh.sphere(A, k)
    interactions = [Gravity([1050.0] * n, 1000.0, STANDARD_GRAVITY), Repulsion(),
                    Adhesion(BondOptions(**ROLLING, seed=seed))]
    model = Model([mesh] * n, [False] * n, Flow(100.0, 1e-3), interactions=interactions,
                  solver=SolverOptions(reuse_tolerance=2e-9, **MODES[mode]),
                  policy=StepPolicy(1e-3, 1e-8, 1e-9), scheme="euler")
    positions = arrangement("line" if n <= 3 else "patch", n, spacing, seed)
    positions[:, 2] = REST
    return model, model.initial_state(positions)


def solved_snapshots(hydro):
    """The snapshots ``hydro`` solved so far: lone, pair or whole-system ones, and remainders."""
    remainder = hydro.pairwise.remainder if hydro.pairwise is not None else None
    return hydro.snapshots_solved + (remainder.solved if remainder is not None else 0)


def cost(device, counts_by_mode, spacing, end, k=3, progress=None, label=""):
    """Wall time of n rolling cells over ``end`` s, for the cell counts of each mode (MODES) side
    by side: the median step that solved no new snapshot (the cost that must grow linearly), the
    snapshots solved (remainders included) and the time they took (the steps' excess over that
    median), the memory of the kept snapshots and the process's peak resident memory so far. A
    line per run to ``progress`` (a Progress; by default one of the runs here), after ``label``."""
    rows = []
    if progress is None:
        progress = Progress(sum(len(ns) for ns in counts_by_mode.values()))
    for mode, ns in counts_by_mode.items():
        for n in ns:
            model, state = rolling_patch(n, spacing, mode, k)
            sim = Simulator(model, device)
            walls, solved, t0 = [], [], time.perf_counter()
            while state.time < end:
                before, t = solved_snapshots(sim.hydro), time.perf_counter()
                state, frame = sim.step(state, end)
                walls.append(time.perf_counter() - t)
                solved.append(solved_snapshots(sim.hydro) - before)
            walls, solved = np.array(walls), np.array(solved)
            plain = float(np.median(walls[solved == 0])) if np.any(solved == 0) else float("nan")
            kept = list(sim.hydro._pairs.values()) + list(sim.hydro._snapshots.values())
            rows.append(dict(mode=mode, cells=n, simulated_ms=end * 1e3, steps=state.steps,
                             wall_s=time.perf_counter() - t0, step_s=plain, snapshots=int(solved.sum()),
                             snapshot_s=float(np.sum(walls[solved > 0] - plain)) / max(int(solved.sum()), 1),
                             bonds=int(frame.parts["bond"]["count"].sum()),
                             kept_mb=sum(a.nbytes for f, g in kept for a in (f.velocity, f.angular_velocity,
                                                                             g.velocity, g.angular_velocity)) / 1e6,
                             # the process's peak so far: the runs go from few cells to many
                             peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3))
            print_table([rows[-1]])
            progress.done(f"{label}{mode}, {n} cells, {end * 1e3:g} ms")
    return rows


def implicit_solvers(device, counts, end, k):
    """``cost`` on pairs for each of ``counts`` (cells of ``k`` subdivisions), the implicit step's
    Newton step solved without forming its matrix (MobilityResponse) and from the matrix formed
    (its ``newton_step`` declined), the two interleaved."""
    formed = mock.patch.object(implicit.MobilityResponse, "newton_step", lambda *args: None)
    rows, progress = [], Progress(2 * len(counts))
    for n in counts:
        for name, patch in (("structured", contextlib.nullcontext()), ("formed", formed)):
            with patch:
                rows += [dict(implicit=name, **row)
                         for row in cost(device, {"pairs": [n]}, 25e-6, end, k, progress, f"{name}: ")]
    return rows


def exponent(rows, key):
    """The fitted exponent of ``key`` against the cells, and the fit's prefactor."""
    n = np.array([r["cells"] for r in rows], float)
    slope, intercept = np.polyfit(np.log(n), np.log([r[key] for r in rows]), 1)
    return slope, np.exp(intercept)


def cost_chart(rows, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for mode, marker in (("pairs", "o"), ("remainder", "^"), ("system", "s")):
        sel = [r for r in rows if r["mode"] == mode]
        if sel:
            ax.loglog([r["cells"] for r in sel], [r["step_s"] for r in sel], marker=marker, label=mode)
    ax.set(xlabel="rolling cells", ylabel="wall time of a step without new snapshots [s]",
           title="cost per step (2-core CPU)")
    return save_chart(fig, path, [ax], legend_size=8)


# the close part's reference discretisation: the biquadratic density (its 3 x 3 Gauss points) at
# ratio 0.35, the error model's most accurate per second near contact (docs/benchmarks.md, "Ask for
# an accuracy"). Two k = 4 cells at the rolling height 0.05 / 0.1 / 0.2 um apart: within 1.3e-4 /
# 7.6e-5 / 5.0e-5 of ratio 0.5 in the grand mobility, in 35 / 15 / 8 s, where the bilinear density
# at its default 1.1 took 115 s at 0.1 um (3.4e-4 off) and failed at 0.05 um (a script's runs of
# the two-body direct solve)
REFERENCE_DENSITY = dict(density_order=3, contact_refinement=0.35)


def close_error(device, cases, k, reference_k, reference_gaps, lattice_from):
    """Two cells near contact (close_pairs.py: the exact two-sphere resistance plus the wall's part
    W on a lattice of gaps, turned by the line's angle) at the rolling height, ``cases`` ((angle
    of their line from the flow, gap between their surfaces)): against their direct two-body solve
    on the k sphere (time-stepped defaults), beside the pairs' lateral lattice from gaps of
    ``lattice_from`` (``close_pairs = "lattice"``, its snapshots solved as the pair is where a
    lattice point is too near: below, the direct solve itself); and, along
    the flow at ``reference_gaps``, against the direct solve on the ``reference_k`` sphere with
    REFERENCE_DENSITY (the reference), beside the model built on that discretisation (its own
    error: W from its lattice snapshots, interpolated and extrapolated) and the k sphere's direct
    solve (the discretisation's error). Wall times of the model (its lattice snapshots included)
    and of the direct solves."""
    mesh, fine = wb.mesh.sphere(A, k), wb.mesh.sphere(A, reference_k)
    heights_exact = dict(grand_mobility="pairs", reuse_tolerance=1e-12, reuse_interaction=1e-12)
    close, lattice = (solves(mesh, 2, device, **heights_exact, close_pairs=c) for c in ("lubrication", "lattice"))
    direct = solves(mesh, 2, device)
    fine_close = solves(fine, 2, device, **heights_exact, **REFERENCE_DENSITY)
    fine_direct = solves(fine, 2, device, **REFERENCE_DENSITY)
    rows, progress = [], Progress(len(cases))
    for angle, gap in cases:
        line = (2 * A + gap) * np.array([np.cos(angle), np.sin(angle)])
        bodies = [Body(mesh, position=(0.0, 0.0, REST)), Body(mesh, position=(*line, REST))]
        row = dict(angle_deg=np.degrees(angle), gap_um=gap * 1e6, k=k)
        timed = {}
        paths = (("direct", direct), ("close", close)) + ((("lattice", lattice),) if gap >= lattice_from else ())
        for name, hydro in paths:
            before, t = hydro.snapshots_solved, time.perf_counter()
            timed[name] = (motion(*hydro._solved(bodies, half_turn=True)) if name == "direct" else
                           motion(*hydro._snapshot(bodies)))
            row[f"{name}_s"], row[f"{name}_snapshots"] = time.perf_counter() - t, hydro.snapshots_solved - before
            if name != "direct":
                row[f"{name}_grand"], row[f"{name}_flow"] = change(timed[name], timed["direct"])
        if angle == 0.0 and gap in reference_gaps:
            fine_bodies = [Body(fine, position=(0.0, 0.0, REST)), Body(fine, position=(*line, REST))]
            t = time.perf_counter()
            reference = motion(*fine_direct._solved(fine_bodies, half_turn=True))
            row["reference_s"] = time.perf_counter() - t
            own = motion(*fine_close._snapshot(fine_bodies))
            row["reference_close_grand"], row["reference_close_flow"] = change(own, reference)
            row["direct_vs_reference_grand"], row["direct_vs_reference_flow"] = change(timed["direct"], reference)
            row["close_vs_reference_grand"], row["close_vs_reference_flow"] = change(timed["close"], reference)
        rows.append(row)
        print_table([row])
        progress.done(f"close: {gap * 1e6:g} um apart at {np.degrees(angle):g} degrees")
    return rows


# the pairs path of --parts train: every lattice below round-off, every pair from its snapshot
TRAIN_PAIRS = dict(EXACT, grand_mobility="pairs", far_field="none")


def train_reference(device, gap, k):
    """(positions, the cells on the k + 1 sphere, their direct solve with REFERENCE_DENSITY (Q,
    flow motion), its wall time) of three cells in a line ``gap`` (m) apart between their surfaces."""
    fine = wb.mesh.sphere(A, k + 1)
    positions = arrangement("line", 3, 2 * A + gap)
    bodies = [Body(fine, position=p) for p in positions]
    t = time.perf_counter()
    reference = embedded(solves(fine, 3, device, **REFERENCE_DENSITY), bodies, [0, 1, 2], 3)
    return positions, bodies, reference, time.perf_counter() - t


def timed_against(row, name, hydro, bodies, reference):
    """Put into ``row`` the wall time of ``hydro``'s snapshot of ``bodies`` (``name``_s) and its
    change from ``reference`` (``name``_grand, ``name``_flow)."""
    t = time.perf_counter()
    got = motion(*hydro._snapshot(bodies))
    row[f"{name}_s"] = time.perf_counter() - t
    row[f"{name}_grand"], row[f"{name}_flow"] = change(got, reference)


def train_error(device, gaps, k):
    """Part 1c'': three cells in a line ``gaps`` (m) apart between their surfaces (module
    docstring); the reference on the k + 1 sphere with REFERENCE_DENSITY."""
    mesh = wb.mesh.sphere(A, k)
    rows, progress = [], Progress(len(gaps))
    for gap in gaps:
        positions, fine_bodies, reference, seconds = train_reference(device, gap, k)
        row = dict(cells=3, gap_um=gap * 1e6, k=k, reference_k=k + 1, reference_s=seconds)
        own = dict(TRAIN_PAIRS, **REFERENCE_DENSITY)
        for name, cells, options in (("own_pairs", fine_bodies, dict(own, close_clusters="none")),
                                     ("own_clusters", fine_bodies, own),
                                     ("clusters", [Body(mesh, position=p) for p in positions], TRAIN_PAIRS)):
            timed_against(row, name, solves(cells[0].mesh, 3, device, **options), cells, reference)
        rows.append(row)
        print_table([row])
        progress.done(f"train: three cells {gap * 1e6:g} um apart")
    return rows


# the cluster meshes --parts train compares at 0.2 um: (subdivisions, density order, contact
# refinement); the first is close_clusters.py's own
CLUSTER_MESHES = ((3, 3, 0.2), (3, 3, 0.0), (2, 3, 0.35), (4, 1, 0.0), (3, 1, 1.0))


def cluster_mesh_error(device, gap, k):
    """Part 1c'' continued: three cells ``gap`` (m) apart as ``train_error`` builds them on the
    k + 1 sphere with REFERENCE_DENSITY, the close clusters' part from each of CLUSTER_MESHES,
    at the cells' own positions (the cluster lattice below round-off) and on the 250 nm lattice,
    against the direct solve; wall times of the path (the clusters' solves and, on a fresh
    snapshot store, the close pairs' lattice)."""
    _, bodies, reference, _ = train_reference(device, gap, k)
    rows, progress = [], Progress(len(CLUSTER_MESHES))
    for subdivisions, order, ratio in CLUSTER_MESHES:
        row = dict(gap_um=gap * 1e6, subdivisions=subdivisions, density_order=order, contact_refinement=ratio)
        for name, lateral in (("exact", 1e-12), ("lattice", close_clusters.CLUSTER_LATERAL)):
            with mock.patch.multiple(close_clusters, CLUSTER_SUBDIVISIONS=subdivisions, CLUSTER_DENSITY_ORDER=order,
                                     CLUSTER_REFINEMENT=ratio, CLUSTER_LATERAL=lateral):
                hydro = solves(bodies[0].mesh, 3, device, **TRAIN_PAIRS, **REFERENCE_DENSITY)
                timed_against(row, name, hydro, bodies, reference)
        rows.append(row)
        print_table([row])
        progress.done(f"train: the cluster mesh k = {subdivisions}, p = {order}, ratio {ratio:g}")
    return rows


def main():
    parser = arguments(__doc__)
    parser.add_argument("--parts", nargs="+", default=["accuracy"],
                        choices=["accuracy", "resistance", "three_body", "cutoff", "lattice", "reuse", "factors",
                                 "batch", "cost", "implicit", "far", "close", "train"])
    parser.add_argument("--runs", nargs="*", default=[], help="run files for --parts reuse")
    parser.add_argument("--k", type=int, default=2, help="sphere mesh subdivisions")
    parser.add_argument("--cells", nargs="*", type=int, default=[],
                        help="the cell counts of --parts cost (default 1 3 8 16 64; 1 3 with --quick)")
    parser.add_argument("--remainder-cells", nargs="*", type=int, default=None,
                        help="the counts of --parts cost run on pairs with the coarse many-body remainder too"
                             " (default 16)")
    parser.add_argument("--cases", nargs="*", default=[],
                        help="--parts accuracy's cases as ARRANGEMENT:CELLS:SPACING_UM (line or patch), e.g. patch:16:25")
    parser.add_argument("--refinement", type=float, default=None,
                        help="--parts accuracy: the contact refinement of every solve but the coarse remainders'"
                             " (default 3, the time-stepped models')")
    parser.add_argument("--solver-paths", action="store_true",
                        help="--parts accuracy: the solver's own paths only (pairs, far field, lattices, remainder)")
    parser.add_argument("--paths", nargs="*", default=None, choices=list(SOLVER_PATHS),
                        help="--parts accuracy with --solver-paths: the paths to run (default all)")
    parser.add_argument("--system-cells", nargs="*", type=int, default=None,
                        help="the counts of --parts cost solved as whole systems too (default 3)")
    args = parser.parse_args()
    if "accuracy" in args.parts:
        cases = ([("line", 3, 25e-6)] if args.quick else
                 [("line", 3, 12e-6), ("line", 3, 25e-6), ("patch", 4, 25e-6), ("patch", 9, 25e-6)])
        if args.cases:
            cases = [(kind, int(n), float(um) * 1e-6) for kind, n, um in (c.split(":") for c in args.cases)]
        if args.paths is not None and not args.solver_paths:
            parser.error("--paths chooses among --solver-paths")
        rows = accuracy(args.device, cases, args.k, args.refinement, extras=not args.solver_paths, paths=args.paths)
        print(f"wrote {write_csv('many_cells_accuracy.csv', rows)}")
    if "resistance" in args.parts:
        cases = [("line", 3, 25e-6)] if args.quick else [("line", 3, 12e-6), ("line", 3, 25e-6), ("patch", 4, 25e-6)]
        rows = resistance_error(args.device, cases, args.k)
        print(f"wrote {write_csv('many_cells_resistance.csv', rows)}")
    if "three_body" in args.parts:
        meshes = [THREE_BODY_MESHES[0], THREE_BODY_MESHES[3]] if args.quick else THREE_BODY_MESHES
        rows = three_body_convergence(args.device, 4 if args.quick else 16, 25e-6, meshes)
        print(f"wrote {write_csv('many_cells_three_body.csv', rows)}")
    if "cutoff" in args.parts:
        rows = cutoff_error(args.device, 4 if args.quick else 8, 25e-6, [50e-6, 75e-6, 100e-6, 150e-6], args.k)
        print(f"wrote {write_csv('many_cells_cutoff.csv', rows)}")
    if "lattice" in args.parts:
        distances, bases = ([12.5e-6], [250e-9, 500e-9]) if args.quick else ([12.5e-6, 15e-6, 25e-6, 40e-6],
                                                                            [125e-9, 250e-9, 500e-9, 1e-6])
        rows = lattice_error(args.device, distances, bases, args.k)
        print(f"wrote {write_csv('many_cells_lattice.csv', rows)}")
    if "far" in args.parts:
        distances = [25e-6, 50e-6] if args.quick else [12e-6, 15e-6, 20e-6, 25e-6, 30e-6, 35e-6, 40e-6, 50e-6, 75e-6,
                                                       100e-6, 150e-6, 200e-6]
        rows = far_error(args.device, distances, args.k)
        print(f"wrote {write_csv('many_cells_far.csv', rows)}")
    if "close" in args.parts:
        along = [0.1e-6, 0.5e-6] if args.quick else [0.05e-6, 0.1e-6, 0.2e-6, 0.35e-6, 0.5e-6, 0.85e-6, 1e-6, 2e-6]
        across = [] if args.quick else [0.35e-6, 0.85e-6, 2e-6]  # 30 degrees off the flow
        cases = [(0.0, g) for g in along] + [(np.pi / 6, g) for g in across]
        rows = close_error(args.device, cases, args.k, args.k + 1,
                           [] if args.quick else along, 0.2e-6)
        print(f"wrote {write_csv('many_cells_close.csv', rows)}")
    if "train" in args.parts:
        rows = train_error(args.device, [0.5e-6] if args.quick else [0.2e-6, 0.35e-6, 0.5e-6, 1e-6, 2e-6], args.k)
        print(f"wrote {write_csv('many_cells_train.csv', rows)}")
        if not args.quick:
            rows = cluster_mesh_error(args.device, 0.2e-6, args.k)
            print(f"wrote {write_csv('many_cells_train_meshes.csv', rows)}")
    if "reuse" in args.parts:
        rows, progress = [], Progress(len(args.runs))
        for path in args.runs:
            new, old, pairs, frames = visited_points(path)
            rows.append(dict(run=path, pairs=pairs, frames=frames, interpolated_points=new, nearest_points_before=old))
            print_table([rows[-1]])
            progress.done(path)
        print(f"wrote {write_csv('many_cells_reuse.csv', rows)}")
    if "factors" in args.parts:
        rows = factor_store(args.device, 2 if args.quick else 3, 3 if args.quick else 6)
        print(f"wrote {write_csv('many_cells_factors.csv', rows)}")
    if "batch" in args.parts:
        rows = batched_loads(args.device, 2 if args.quick else 3, 2 if args.quick else 4)
        print(f"wrote {write_csv('many_cells_batch.csv', rows)}")
        rows = batched_coarse_systems(args.device, [4, 9] if args.quick else [4, 9, 16, 36, 64])
        print(f"wrote {write_csv('many_cells_batch_coarse.csv', rows)}")
    if "implicit" in args.parts:
        rows = implicit_solvers(args.device, args.cells or ([3, 8] if args.quick else [16, 64]),
                                5e-4 if args.quick else 2e-3, args.k)
        for name in ("structured", "formed"):
            slope, _ = exponent([r for r in rows if r["implicit"] == name], "step_s")
            print(f"{name}: a step without new snapshots costs n^{slope:.2f}")
        print(f"wrote {write_csv('many_cells_implicit.csv', rows)}")
    if "cost" in args.parts:
        counts, system_counts, remainder_counts, end = (([1, 3], [3], [], 5e-4) if args.quick else
                                                        ([1, 3, 8, 16, 64], [3], [16], 2e-3))
        counts = args.cells or counts
        system_counts = system_counts if args.system_cells is None else args.system_cells
        remainder_counts = remainder_counts if args.remainder_cells is None else args.remainder_cells
        rows = cost(args.device, {"pairs": counts, "remainder": remainder_counts, "system": system_counts}, 25e-6, end)
        several = [r for r in rows if r["mode"] == "pairs" and r["cells"] > 1]
        if len(several) > 1:
            slope, _ = exponent(several, "step_s")
            print(f"pairs: a step without new snapshots costs n^{slope:.2f} from {several[0]['cells']} cells")
        print(f"wrote {write_csv('many_cells_cost.csv', rows)}, {cost_chart(rows, output_path('many_cells.png'))}")


if __name__ == "__main__":
    main()
