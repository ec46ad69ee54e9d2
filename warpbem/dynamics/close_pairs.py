"""Two equal spherical cells near contact: their pair snapshot from the exact two-sphere
resistance plus the wall's part on a coarse lattice of gaps, and their films added in resistance
among many cells (``SolverOptions.close_pairs = "lubrication"``).

Near contact the resistance of two spheres diverges in the gap eps between their surfaces, as
a / eps for the squeeze along the line of centres and as ln(a / eps) for the sliding and rolling
across it (Jeffrey & Onishi 1984, J. Fluid Mech. 139:261; Kim & Karrila 1991, ch. 9-11), so a
pair snapshot changes at every step as two cells close, and the bilinear lattice of
``pairwise.py`` (250 nm at contact) would straddle the film. The resistance of the pair above the
wall is written

    R(eps) = R_JO(eps, d) + W(eps),

R_JO the exact resistance of the two spheres alone in unbounded fluid (``hydro/two_spheres.py``,
at the cells' own line of centres) and W what the wall adds. The film is the same with and without
the wall (its pressure is set in the gap, a distance eps from both surfaces and ~a from the wall),
so W is bounded as eps -> 0 and changes slowly with it: W = Q^-1 - R_JO is taken from
boundary-element pair snapshots (Q the symmetrised grand mobility) at gaps GAP_SMALLEST_SHARE
radii times powers of GAP_STEP (0.5, 0.71, 1, 1.41, 2 and 2.83 um between 5 um cells, at the
heights of the pair lattice, ``reuse_interaction``), interpolated linearly in the gap, and R_JO
added back at the state's own gap; the sum, inverted, is the grand mobility. Below the smallest
gap W is extrapolated linearly from the two smallest: there the boundary elements of the
time-stepped defaults stop resolving the film, while the exact part carries what diverges. On two
5 um cells at the rolling height solved with k = 4 and quadratic densities, where W along the
line changes by 1 % from 0.5 um to 0.1 um, W from 0.5 and 1 um extrapolated to 0.2 and 0.1 um
gives the grand mobility to 4.5e-4 and 6.1e-4 and the flow's motion to 1.3e-4 and 1.0e-4 (W held
at its 0.5 um value: 4.3e-3 and 5.5e-3).

The wall is invariant under turns about its normal, so the grand mobility of a pair whose line of
centres makes an angle theta with the flow is that of the pair along x, turned by theta; the
shear flow gdot z e_x is not, but it is linear in its direction: in the pair's frame it is
cos(theta) times the flow along the line plus sin(theta) times the flow across it (the snapshot
of the pair along y in the flow along x, turned into its frame). The flow is carried as the loads
that hold the pair still in it, f = Q^-1 u, bounded at contact (the free pair's relative motion
vanishes as eps while the squeeze resistance grows as 1 / eps), interpolated like W, and
u = Q f. So one gap of the lattice costs two pair snapshots and no lattice of angles is needed;
what the turn leaves out is the mesh's own lack of symmetry under it (3e-4 of the grand mobility
of two k = 3 cells 0.5-2 um apart turned by pi / 32 and pi / 16, against their direct solve).

Among more cells the films add in resistance, not in mobility: a cell between two neighbours
near contact is held by both films, which the pairwise sum of mobilities cannot give. So each
close pair enters the pairwise sum (``pairwise.py``) with its film taken out of its resistance,
smooth in the gap,

    L(eps) = S(eps) - S(CLOSE_GAP_SHARE a),      M_pair = (R_JO - L + W)^-1,

S the terms of R_JO that diverge at contact (``two_spheres.singular_resistance_matrix``), L
positive semidefinite and zero where the pair stops being close, and the films are added back to
the assembled resistance of all the cells, M = (M_sum^-1 + sum L)^-1 (``with_resistance``: Stokesian
dynamics' split of the resistance into a many-body far part and pairwise lubrication, Durlofsky,
Brady & Bossis 1987, J. Fluid Mech. 180:21). For two cells this is their pair snapshot again.
Three 5 um k = 3 cells in a line at the rolling height, against their whole system's solve
(grand mobility / flow's motion; ``benchmarks/many_cells.py --parts accuracy --solver-paths --k 3
--cases line:3:10.5 line:3:11 line:3:12``): 0.5 um between the surfaces 1.1e-2 / 1.9e-2 (the
mobilities summed without films: 0.11 / 3.7e-2), 1 um 1.6e-2 / 1.8e-2 (6.6e-2 / 3.0e-2), 2 um
2.5e-2 / 1.8e-2 (3.6e-2 / 2.1e-2). What is left is the three-body part of the smooth rest, the
middle cell screening the outer two, which ``close_clusters.py`` adds in resistance.

Pairs of cells farther apart than CLOSE_GAP_SHARE radii between their surfaces, or of different
radii, take the pairs' lateral lattice (``pairwise.py``).
"""

from __future__ import annotations

import numpy as np

from ..hydro import two_spheres
from ..surfaces.body import Body

# pairs of equal spheres closer than this many radii between their surfaces are close: at 2.5 um
# between 5 um cells the pairs' 250 nm lateral lattice still interpolates to about 1e-4
# (benchmarks/many_cells.py --parts lattice: 3.4e-4 on a 500 nm one at 2.5 um)
CLOSE_GAP_SHARE = 0.5
# the lattice's smallest gap, in radii, and the ratio of one gap to the next (module docstring)
GAP_SMALLEST_SHARE = 0.1
GAP_STEP = np.sqrt(2.0)
# a gap this close to a lattice point, in lattice steps, lies on it
ROUND_OFF = 1e-9
# rad: the lattice points' angles (0 along the flow, pi / 2 across it) are keyed in these units
ANGLE_UNIT = np.pi / 2
# (force, torque / radius) <- (velocity, radius x angular velocity): the snapshots' basis loads
# are unit forces and torques of 1 N times the radius (HydrodynamicSolves._body_loads)
GENERALISED = np.tile([1.0, 1.0, 1.0, 0.0, 0.0, 0.0], 2)


def generalised(matrix: np.ndarray, radius: float) -> np.ndarray:
    """A resistance matrix (SI, (F, T) of (U, Omega) per sphere) in the snapshots' generalised
    coordinates: (F, T / a) of (U, a Omega)."""
    scale = GENERALISED + (1.0 - GENERALISED) / radius
    return scale[:, None] * matrix * scale[None, :]


def snapshot_matrices(flow, grand, radii) -> tuple[np.ndarray, np.ndarray]:
    """(Q (6n, 6n), u (6n,)) of a snapshot of n cells of ``radii`` ((n,) m, or one radius): the
    symmetrised grand mobility, (U, a Omega) of each cell per unit (F, T / a), and the flow's
    motion (U, a Omega)."""
    radii = np.broadcast_to(np.asarray(radii, float), (len(flow.velocity),))
    return grand.quadratic(), np.concatenate([flow.velocity, flow.angular_velocity * radii[:, None]], axis=1).ravel()


def snapshot_parts(q: np.ndarray, u: np.ndarray, radii) -> tuple:
    """The grand mobility Q (6n, 6n) and the flow's motion u (6n,) of n cells of ``radii`` ((n,)
    m, or one radius), generalised as ``snapshot_matrices`` gives them, as (flow velocity,
    angular velocity (n, 3), basis velocity, angular velocity (6n, n, 3)), the layout of
    HydrodynamicSolves._grand_mobility."""
    n = len(u) // 6
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    by_cell, u = q.reshape(6 * n, n, 6), u.reshape(n, 6)
    return u[:, :3], u[:, 3:] / radii[:, None], by_cell[:, :, :3].copy(), by_cell[:, :, 3:] / radii[None, :, None]


def generalised_matrices(velocity, angular, basis_velocity, basis_angular, radii) -> tuple[np.ndarray, np.ndarray]:
    """(Q (6n, 6n), u (6n,)) of n cells of ``radii`` ((n,) m) from their parts in the layout of
    HydrodynamicSolves._grand_mobility (flow velocity, angular velocity (n, 3), basis velocity,
    angular velocity (6n, n, 3)): ``snapshot_parts`` undone."""
    n = len(radii)
    q = np.concatenate([basis_velocity, basis_angular * radii[None, :, None]], axis=2).reshape(6 * n, 6 * n)
    return q, np.concatenate([velocity, angular * radii[:, None]], axis=1).ravel()


def turn(angle: float) -> np.ndarray:
    """(12, 12) the rotation by ``angle`` (rad) about the wall's normal of both cells' velocity
    and angular velocity (or force and torque): a vector and a pseudovector turn alike."""
    c, s = np.cos(angle), np.sin(angle)
    return np.kron(np.eye(4), np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))


class ClosePairs:
    """Pair snapshots of close equal spheres (module docstring) for ``hydro``, a
    ``HydrodynamicSolves`` whose pair snapshots (and disk store) it uses."""

    def __init__(self, hydro):
        self.hydro = hydro
        model = hydro.model
        self.radii = model.outer_radii
        self.viscosity = model.flow.viscosity
        self._points: dict = {}  # lattice key -> (W, f along, f across) of its pair snapshots

    def takes(self, first, second, positions) -> np.ndarray:
        """(P,) which of the pairs (first[p], second[p]) of cells at ``positions`` ((n, 3) m) are
        close: equal radii and a gap below CLOSE_GAP_SHARE radii."""
        radius = self.radii[first]
        equal = np.isclose(radius, self.radii[second], rtol=1e-9, atol=0.0)
        gap = np.linalg.norm(positions[second] - positions[first], axis=1) - radius - self.radii[second]
        return equal & (gap < CLOSE_GAP_SHARE * radius)

    def parts(self, bodies, i: int, j: int, heights) -> tuple:
        """(flow velocity, angular velocity (2, 3), basis velocity, angular velocity (12, 2, 3),
        swapped, mirrored) of the close pair (i, j) in its stored form (pairwise.part_row maps it
        back), the pair lattice's ``heights`` ((n,) m) keying the wall's part: in the pair's own
        frame (its line of centres along x), R_JO at the cells' own line plus W interpolated in
        the gap, inverted, and the holding loads along and across the line combined by the flow's
        direction; then turned by the line's angle. Raises pairwise.TooClose where a lattice
        point is not a valid placement."""
        a = float(self.radii[i])
        line = np.asarray(bodies[j].position, float) - np.asarray(bodies[i].position, float)
        swapped = bool(line[0] < 0 or (line[0] == 0 and line[1] < 0))
        cells, line = ((j, i), -line) if swapped else ((i, j), line)
        mirrored = bool(line[1] < 0)
        line[1] = abs(line[1])
        lateral, angle = float(np.hypot(line[0], line[1])), float(np.arctan2(line[1], line[0]))
        gap = float(np.linalg.norm(line)) - 2.0 * a
        wall_part, hold = np.zeros((12, 12)), np.zeros(12)
        for index, weight in _gap_weights(gap / a):
            if weight == 0.0:
                continue
            w, hold_along, hold_across = self._point(bodies, cells, heights, index, a, across=angle > 0.0)
            wall_part += weight * w
            # the shear u = gdot z e_x is gdot z (cos e_x' - sin e_y') in the pair's frame; the
            # across snapshot, turned into its own frame, is the response to -e_y'
            hold += weight * (np.cos(angle) * hold_along + np.sin(angle) * hold_across)
        own_line = (lateral, 0.0, line[2])
        smooth = two_spheres.resistance_matrix(self.viscosity, a, own_line) - self._film(a, own_line)
        q = np.linalg.inv(generalised(smooth, a) + wall_part)
        q = 0.5 * (q + q.T)
        rotation = turn(angle)
        return snapshot_parts(rotation @ q @ rotation.T, rotation @ (q @ hold), a) + (swapped, mirrored)

    def film(self, bodies, i: int, j: int) -> np.ndarray:
        """(12, 12) the film's resistance L between the close cells (i, j), in that order, in the
        snapshots' generalised coordinates (module docstring)."""
        a = float(self.radii[i])
        line = np.asarray(bodies[j].position, float) - np.asarray(bodies[i].position, float)
        return generalised(self._film(a, line), a)

    def _film(self, a: float, line) -> np.ndarray:
        """L (SI) of two spheres of radius ``a`` along ``line``: the terms of Jeffrey & Onishi's
        resistance that diverge at contact less their value at CLOSE_GAP_SHARE radii, so that it
        vanishes where the pair stops being close."""
        line = np.asarray(line, float)
        edge = line / np.linalg.norm(line) * (2.0 + CLOSE_GAP_SHARE) * a
        return (two_spheres.singular_resistance_matrix(self.viscosity, a, line)
                - two_spheres.singular_resistance_matrix(self.viscosity, a, edge))

    def _point(self, bodies, cells, heights, gap_index: int, a: float, across: bool):
        """(W (12, 12), holding loads of the flow along and across (12,) each) at a gap of the
        lattice, of the pair ``cells`` (stored order) with its line of centres along x and along
        y (the latter, turned into the pair's frame, only if ``across``; else zeros): their pair
        snapshots solved (or read) once, kept."""
        hydro = self.hydro
        h0, h1 = (float(heights[c]) for c in cells)
        key = ("pair",) + tuple(hydro.lone_of[c] for c in cells) + (h0, h1, "close", gap_index)
        if key not in self._points:
            self._points[key] = self._solved_point(bodies, cells, key, 0.0, a) + (None,)
        w, hold_along, hold_across = self._points[key]
        if across and hold_across is None:
            _, hold_across = self._solved_point(bodies, cells, key, np.pi / 2, a)
            hold_across = turn(-np.pi / 2) @ hold_across
            self._points[key] = w, hold_along, hold_across
        return w, hold_along, (hold_across if across else np.zeros(12))

    def _solved_point(self, bodies, cells, key, angle: float, a: float):
        """(W, holding loads of the flow) of the lattice point ``key`` with the line of centres at
        ``angle`` from the flow (rad), in the wall's frame."""
        hydro = self.hydro
        h0, h1, gap_index = key[3], key[4], key[6]
        distance = (2.0 + lattice_gap(gap_index)) * a
        lateral = np.sqrt(distance**2 - (h1 - h0) ** 2)
        snapped = [Body(bodies[cells[0]].mesh, position=(0.0, 0.0, h0)),
                   Body(bodies[cells[1]].mesh, position=(lateral * np.cos(angle), lateral * np.sin(angle), h1))]
        radii = self.radii[list(cells)]
        half_turn = h0 == h1 and snapped[0].mesh is snapped[1].mesh
        flow, grand = hydro._kept(key + (round(angle / ANGLE_UNIT),), snapped,
                                  lambda b: hydro._solved(b, radii, half_turn), store=hydro._pairs)
        q, u = snapshot_matrices(flow, grand, a)
        resistance = np.linalg.inv(q)
        line = np.asarray(snapped[1].position) - np.asarray(snapped[0].position)
        return resistance - generalised(two_spheres.resistance_matrix(self.viscosity, a, line), a), resistance @ u


def lattice_gap(index: int) -> float:
    """The gap of the lattice point ``index``, in radii."""
    return GAP_SMALLEST_SHARE * GAP_STEP**index


def _gap_weights(gap: float):
    """((index, weight), (index + 1, weight)) of the linear interpolation in the gap (in radii)
    between the lattice points around it, extrapolated from the two smallest below them."""
    lower = max(0, int(np.floor(np.log(gap / GAP_SMALLEST_SHARE) / np.log(GAP_STEP) + ROUND_OFF)))
    share = (gap - lattice_gap(lower)) / (lattice_gap(lower + 1) - lattice_gap(lower))
    return (lower, 1.0 - share), (lower + 1, share)


def with_resistance(velocity, angular, basis_velocity, basis_angular, radii, terms):
    """The flow's motion (n, 3) each and the basis's (6n, n, 3) each of cells whose smooth parts
    are these, with resistances added: ``terms`` ((cells (k,), X (6k, 6k), g (6k,) or None) each:
    a close pair's film L with no loads, or a close cluster's correction and its holding loads,
    close_clusters.py). The smooth grand mobility Q (generalised: (U, a Omega) of (F, T / a)) and
    the sum X of the terms combine as (Q^-1 + P^T X P)^-1 = Q - Q P^T (I + X P Q P^T)^-1 X P Q
    (Woodbury; P the rows of the cells in a term, so nothing is inverted but a matrix of their
    size), and the flow's motion u = Q f (f the holding loads) becomes M (f + P^T g) =
    u - Q P^T (I + X P Q P^T)^-1 (X P u - g): a film between cells held still does no work."""
    q, u = generalised_matrices(velocity, angular, basis_velocity, basis_angular, radii)
    cells = sorted({int(c) for term_cells, _, _ in terms for c in term_cells})
    where = {c: k for k, c in enumerate(cells)}
    rows = (6 * np.array(cells)[:, None] + np.arange(6)).ravel()
    added, loads = np.zeros((len(rows), len(rows))), np.zeros(len(rows))
    for term_cells, resistance, term_loads in terms:
        term_rows = (6 * np.array([where[int(c)] for c in term_cells])[:, None] + np.arange(6)).ravel()
        added[np.ix_(term_rows, term_rows)] += resistance
        if term_loads is not None:
            loads[term_rows] += term_loads
    damped = np.eye(len(rows)) + added @ q[np.ix_(rows, rows)]
    right = added @ np.concatenate([q[rows], u[rows, None]], axis=1)
    right[:, -1] -= loads
    correction = q[:, rows] @ np.linalg.solve(damped, right)
    q, u = q - correction[:, :-1], u - correction[:, -1]
    return snapshot_parts(0.5 * (q + q.T), u, radii)
