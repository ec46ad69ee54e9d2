"""Exact surface gaps: the closest points between two bodies, or between a body and the wall,
found by Newton's method on candidate element pairs (``kernels/contact.py``), and ``Contacts``,
the gaps of one configuration, each pair searched at most once however many users ask.

Candidates are pruned with bounding spheres: each element lies within ``BOUND_FACTOR`` times the
largest distance of its nodes from its centre node (the biquadratic surface bulges a little
beyond its nodes), and the distance between two centre nodes, which lie on the surfaces, bounds
the gap from above. Every pair whose lower bound is below that upper bound is searched.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import runtime
from .quad9 import CENTRE_NODE

WALL = -1  # the id of the wall where a body index is expected (pairs, gaps, contact lists)
BOUND_FACTOR = 1.15
KEPT_MESHES = 64  # meshes whose element spheres GapFinder keeps (the bodies of a patch share one)


@dataclass(frozen=True)
class Gap:
    """Closest approach of ``body`` to ``other`` (a body index, or WALL): surface distance (m),
    the closest points on each (m) and the unit normal from the other's point to the body's."""

    body: int
    other: int
    distance: float
    point: np.ndarray
    other_point: np.ndarray
    normal: np.ndarray


def bounding_spheres(element_nodes):
    """Centre nodes (E, 3) and radii (E,) of spheres that hold each element (BOUND_FACTOR)."""
    centres = element_nodes[:, CENTRE_NODE]
    radii = BOUND_FACTOR * np.linalg.norm(element_nodes - centres[:, None], axis=-1).max(axis=1)
    return centres, radii


def outer_radius(mesh) -> float:
    """Radius of the sphere about the reference point that holds every node of ``mesh`` (m)."""
    return float(np.linalg.norm(mesh.nodes, axis=1).max())


def candidate_pairs(positions, outer_radii, fixed, wall: bool, within: float) -> list[tuple[int, int]]:
    """(i, j) with body i free and j another body or WALL whose bounding spheres (``outer_radii``
    about ``positions``) come closer than ``within`` (m): the only pairs whose surface gap can be
    below ``within``. Each pair of free bodies appears once; fixed bodies are never ``i``."""
    first, second = candidate_arrays(positions, outer_radii, fixed, wall, within)
    return list(zip(first.tolist(), second.tolist()))


def candidate_arrays(positions, outer_radii, fixed, wall: bool, within: float) -> tuple[np.ndarray, np.ndarray]:
    """``candidate_pairs`` as two arrays, the i and the j of each pair in the same order."""
    positions, outer_radii = np.asarray(positions, dtype=float), np.asarray(outer_radii, dtype=float)
    fixed = np.asarray(fixed, dtype=bool)
    free = np.flatnonzero(~fixed)
    # every free body against every body at once (a loop over the free ones, and a loop over the others
    # before it, took most of a step among 1000 fixed cells and 6 ms of a step of 64 free cells)
    gaps = (np.linalg.norm(positions[None, :] - positions[free, None], axis=2) - outer_radii[free, None]
            - outer_radii[None, :])
    others = np.arange(len(positions))
    near = (gaps < within) & (others[None, :] != free[:, None]) & (fixed[None, :] | (others[None, :] > free[:, None]))
    rows, columns = np.nonzero(near)
    first, second = free[rows], others[columns]
    if wall:
        to_wall = free[positions[free, 2] - outer_radii[free] < within]
        first = np.concatenate([to_wall, first])
        second = np.concatenate([np.full(len(to_wall), WALL), second])
    # each free body's wall pair first, then the other bodies in order
    order = np.lexsort((second, first))
    return first[order], second[order]


class GapFinder:
    """Exact gaps between bodies (``Body`` objects) on a Warp device (float64)."""

    def __init__(self, device="cpu"):
        self.device = runtime.resolve_device(device)
        wp = runtime.init()
        from ..kernels.contact import build_contact_kernels

        self.wp = wp
        self.kernels = build_contact_kernels(wp.float64)
        self._spheres: dict = {}  # id(mesh) -> (mesh, its element nodes, their spheres' radii)
        wp.load_module(self.kernels.closest_points.module, device=self.device)

    def _search(self, nodes_a, element_a, nodes_b, element_b):
        from ..kernels import contact

        wp, k = self.wp, self.kernels
        n = len(element_a)
        point_a = wp.zeros(n, dtype=k.vec3, device=self.device)
        point_b = wp.zeros(n, dtype=k.vec3, device=self.device)
        to_wall = nodes_b is None
        nodes_b = nodes_a if to_wall else nodes_b
        contact.closest_points(
            k, self.device, n,
            wp.array(nodes_a.reshape(-1, 3), dtype=k.vec3, device=self.device),
            wp.array(element_a.astype(np.int32), dtype=int, device=self.device),
            wp.array(nodes_b.reshape(-1, 3), dtype=k.vec3, device=self.device),
            wp.array(element_b.astype(np.int32), dtype=int, device=self.device), int(to_wall),
            point_a, point_b)
        return point_a.numpy(), point_b.numpy()

    def to_wall(self, bodies, indices) -> list[Gap]:
        """Closest approach of each body ``indices`` to the wall z = 0, all searched in one kernel
        launch (a launch per cell, with its arrays, took most of the gap search of 64 rolling
        cells; py-spy on scenes/rolling_patch_8x8.toml). A body's candidates, the elements whose
        bounding sphere reaches as low as the lowest centre node, are found from the centre
        nodes' heights alone (the spheres' radii are the mesh's own: a rigid motion keeps them,
        and the bodies of one mesh are taken together), and only they are moved to the world
        frame and searched (moving every element of 256 cells took 20 ms a step)."""
        indices = [int(i) for i in indices]
        if not indices:
            return []
        chosen = [None] * len(indices)  # each body's candidates' nodes in the world frame (k, 9, 3)
        by_mesh: dict = {}
        for place, i in enumerate(indices):
            by_mesh.setdefault(id(bodies[i].mesh), []).append(place)
        for places in by_mesh.values():
            members = [bodies[indices[place]] for place in places]
            local, radii = self._element_spheres(members[0].mesh)
            rotations = np.array([b.rotation() for b in members])
            positions = np.array([b.position for b in members])
            heights = local[:, CENTRE_NODE] @ rotations[:, 2].T + positions[:, 2]  # (elements, bodies)
            low = heights - radii[:, None] <= heights.min(axis=0)
            for column, (place, body) in enumerate(zip(places, members)):
                chosen[place] = local[low[:, column]] @ rotations[column].T + body.position
        counts = [len(c) for c in chosen]
        elements = np.arange(sum(counts))
        pa, pb = self._search(np.concatenate(chosen), elements, None, elements)
        gaps, first = [], 0
        for i, count in zip(indices, counts):
            best = first + int(np.argmin(pa[first:first + count, 2]))
            gaps.append(Gap(i, WALL, float(pa[best, 2]), pa[best], pb[best], np.array([0.0, 0.0, 1.0])))
            first += count
        return gaps

    def _element_spheres(self, mesh):
        """(element nodes (E, 9, 3) in the mesh's frame, their bounding spheres' radii (E,)),
        kept for the last few meshes (a deformable cell's changes every step)."""
        key = id(mesh)
        if key not in self._spheres or self._spheres[key][0] is not mesh:
            if len(self._spheres) >= KEPT_MESHES:
                self._spheres.clear()
            local = mesh.nodes[mesh.elements]
            self._spheres[key] = (mesh, local, bounding_spheres(local)[1])
        return self._spheres[key][1:]

    def between(self, bodies, i: int, j: int) -> Gap:
        """Closest approach of body i to body j, or to the wall z = 0 when j is WALL."""
        if j == WALL:
            return self.to_wall(bodies, [i])[0]
        nodes_i = bodies[i].world_nodes()[bodies[i].mesh.elements]
        centres_i, radii_i = bounding_spheres(nodes_i)
        nodes_j = bodies[j].world_nodes()[bodies[j].mesh.elements]
        centres_j, radii_j = bounding_spheres(nodes_j)
        centre_distance = np.linalg.norm(centres_i[:, None] - centres_j[None], axis=-1)
        lower = centre_distance - radii_i[:, None] - radii_j[None]
        ea, eb = np.nonzero(lower <= centre_distance.min())
        pa, pb = self._search(nodes_i, ea, nodes_j, eb)
        distances = np.linalg.norm(pa - pb, axis=1)
        best = int(np.argmin(distances))
        d = float(distances[best])
        return Gap(i, j, d, pa[best], pb[best], (pa[best] - pb[best]) / d)


class Contacts:
    """The exact gaps of one configuration of bodies (DESIGN.md §3, step 2), computed on demand
    and kept: the step-size rule, every interaction and the frame's ``closest_gap`` share them,
    so no pair is searched twice for the same state.

    ``bodies``: the ``Body`` list; ``outer_radii``: their bounding radii (``outer_radius``);
    ``wall``: the plane z = 0 is there; ``finder``: a ``GapFinder``; ``shapes``: the bodies the
    gaps are measured on, if not ``bodies`` (deformable cells without the flattening of their
    own contact loads: elastic/deformable.py). Pairs are as in ``candidate_pairs``: a free body
    and another body or the wall.
    """

    def __init__(self, bodies, outer_radii, wall: bool, finder: GapFinder, shapes=None):
        self.bodies = list(bodies)
        self.shapes = self.bodies if shapes is None else list(shapes)
        self.positions = np.array([b.position for b in self.bodies])
        self.outer_radii = np.asarray(outer_radii, dtype=float)
        self.fixed = np.array([b.fixed for b in self.bodies])
        self.wall = bool(wall)
        self.finder = finder
        self._gaps: dict[tuple[int, int], Gap] = {}

    def gap(self, i: int, j: int) -> Gap:
        """The exact gap of free body i to body j (or WALL), searched once."""
        if (i, j) not in self._gaps:
            self._gaps[(i, j)] = self.finder.between(self.shapes, i, j)
        return self._gaps[(i, j)]

    def to_wall(self, indices) -> list[Gap]:
        """The exact gaps of free bodies ``indices`` to the wall, those not yet known searched
        together (GapFinder.to_wall)."""
        missing = [int(i) for i in indices if (int(i), WALL) not in self._gaps]
        for gap in self.finder.to_wall(self.shapes, missing):
            self._gaps[(gap.body, WALL)] = gap
        return [self._gaps[(int(i), WALL)] for i in indices]

    def pairs(self, within: float) -> list[tuple[int, int]]:
        return candidate_pairs(self.positions, self.outer_radii, self.fixed, self.wall, within)

    def within(self, distance: float) -> list[Gap]:
        """Exact gaps of every pair whose bounding spheres come closer than ``distance`` (m): all
        pairs whose gap can be below it (some returned gaps may exceed it)."""
        pairs = self.pairs(distance)
        self.to_wall([i for i, j in pairs if j == WALL])
        return [self.gap(i, j) for i, j in pairs]

    def smallest(self, distance: float) -> float:
        """The smallest exact gap (m, >= 0) below ``distance``, else ``distance``."""
        gaps = [g.distance for g in self.within(distance)]
        return float(np.clip(min(gaps, default=distance), 0.0, distance))

    def closest(self, among: str = "all") -> float:
        """The exact smallest gap (m) of a free body to another body or the wall (inf if there is
        none); ``among``: "all" pairs, "bodies" (another body only) or "wall" (the wall only).
        The wall gaps are searched together; pairs of bodies in order of their bounding-sphere
        gap, a lower bound of the exact one, until that bound passes the best gap found."""
        if among not in ("all", "bodies", "wall"):
            raise ValueError(f"closest: among = {among!r}, not 'all', 'bodies' or 'wall'")
        # as arrays: a list of the 32 640 pairs of 256 cells took 33 ms a step
        first, second = candidate_arrays(self.positions, self.outer_radii, self.fixed, self.wall, np.inf)
        if among != "all":
            kept = (second == WALL) == (among == "wall")
            first, second = first[kept], second[kept]
        if among == "wall":  # every free body's, in one launch (GapFinder.to_wall)
            return float(min((g.distance for g in self.to_wall(first.tolist())), default=np.inf))
        # the bounding-sphere gaps at once (a list over the 2016 pairs of 64 cells took 7 ms a frame);
        # the exact gaps' minimum does not depend on the order they are searched in
        positions, radii = np.asarray(self.positions, dtype=float), np.asarray(self.outer_radii, dtype=float)
        other = np.where(second == WALL, first, second)
        bounds = np.where(second == WALL, positions[first, 2] - radii[first],
                          np.linalg.norm(positions[first] - positions[other], axis=1) - radii[first] - radii[other])
        best = np.inf
        for k in np.argsort(bounds, kind="stable"):
            if bounds[k] >= best:
                break
            best = min(best, self.gap(int(first[k]), int(second[k])).distance)
        return float(best)
