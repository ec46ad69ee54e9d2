"""Exact surface gaps: the closest points between two bodies, or between a body and the wall,
found by Newton's method on candidate element pairs (``kernels/contact.py``).

Candidates are pruned with bounding spheres: each element lies within ``BOUND_FACTOR`` times the
largest distance of its nodes from its centre node (the biquadratic surface bulges a little
beyond its nodes), and the distance between two centre nodes, which lie on the surfaces, bounds
the gap from above. Every pair whose lower bound is below that upper bound is searched.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import runtime

WALL = -1
BOUND_FACTOR = 1.15


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


def _spheres(element_nodes):
    centres = element_nodes[:, 8]
    radii = BOUND_FACTOR * np.linalg.norm(element_nodes - centres[:, None], axis=-1).max(axis=1)
    return centres, radii


def outer_radius(mesh) -> float:
    """Radius of the sphere about the reference point that holds every node of ``mesh`` (m)."""
    return float(np.linalg.norm(mesh.nodes, axis=1).max())


def candidate_pairs(positions, outer_radii, fixed, wall: bool, within: float) -> list[tuple[int, int]]:
    """(i, j) with body i free and j another body or WALL whose bounding spheres (``outer_radii``
    about ``positions``) come closer than ``within`` (m): the only pairs whose surface gap can be
    below ``within``. Each pair of free bodies appears once; fixed bodies are never ``i``."""
    pairs = []
    for i in np.flatnonzero(~np.asarray(fixed, dtype=bool)):
        if wall and positions[i][2] - outer_radii[i] < within:
            pairs.append((int(i), WALL))
        for j in range(len(positions)):
            if j == i or (not fixed[j] and j < i):
                continue
            if np.linalg.norm(np.subtract(positions[i], positions[j])) - outer_radii[i] - outer_radii[j] < within:
                pairs.append((int(i), j))
    return pairs


class GapFinder:
    """Exact gaps between bodies (``Body`` objects) on a Warp device (float64)."""

    def __init__(self, device="cpu"):
        self.device = runtime.resolve_device(device)
        wp = runtime.init()
        from .kernels.contact import build_contact_kernels

        self.wp = wp
        self.kernels = build_contact_kernels(wp.float64)
        wp.load_module(self.kernels.closest_points.module, device=self.device)

    def _search(self, nodes_a, element_a, nodes_b, element_b):
        wp, k = self.wp, self.kernels
        n = len(element_a)
        point_a = wp.zeros(n, dtype=k.vec3, device=self.device)
        point_b = wp.zeros(n, dtype=k.vec3, device=self.device)
        to_wall = nodes_b is None
        nodes_b = nodes_a if to_wall else nodes_b
        wp.launch(k.closest_points, dim=n, device=self.device, inputs=[
            wp.array(nodes_a.reshape(-1, 3), dtype=k.vec3, device=self.device),
            wp.array(element_a.astype(np.int32), dtype=int, device=self.device),
            wp.array(nodes_b.reshape(-1, 3), dtype=k.vec3, device=self.device),
            wp.array(element_b.astype(np.int32), dtype=int, device=self.device), int(to_wall),
            point_a, point_b])
        return point_a.numpy(), point_b.numpy()

    def between(self, bodies, i: int, j: int) -> Gap:
        """Closest approach of body i to body j, or to the wall z = 0 when j is WALL."""
        nodes_i = bodies[i].world_nodes()[bodies[i].mesh.elements]
        centres_i, radii_i = _spheres(nodes_i)
        if j == WALL:
            upper = centres_i[:, 2].min()
            candidates = np.flatnonzero(centres_i[:, 2] - radii_i <= upper)
            pa, pb = self._search(nodes_i, candidates, None, candidates)
            best = int(np.argmin(pa[:, 2]))
            return Gap(i, WALL, float(pa[best, 2]), pa[best], pb[best], np.array([0.0, 0.0, 1.0]))
        nodes_j = bodies[j].world_nodes()[bodies[j].mesh.elements]
        centres_j, radii_j = _spheres(nodes_j)
        centre_distance = np.linalg.norm(centres_i[:, None] - centres_j[None], axis=-1)
        lower = centre_distance - radii_i[:, None] - radii_j[None]
        ea, eb = np.nonzero(lower <= centre_distance.min())
        pa, pb = self._search(nodes_i, ea, nodes_j, eb)
        distances = np.linalg.norm(pa - pb, axis=1)
        best = int(np.argmin(distances))
        d = float(distances[best])
        return Gap(i, j, d, pa[best], pb[best], (pa[best] - pb[best]) / d)
