"""Per-solve surface data of all bodies, in scaled units, on the host and on the device.

Lengths are divided by ``length_scale`` (the mean equivalent radius of the bodies) so the
kernels see O(1) numbers in either precision. Elements of all bodies are concatenated, body
after body; ``body_start``/``body_end`` give each element the range of its own body.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import runtime
from ..surfaces import quad9
from ..surfaces.refinement import refine_near_contact


@dataclass(frozen=True, eq=False)
class SurfaceGeometry:
    length_scale: float  # metres per scaled unit
    element_nodes: np.ndarray  # (E, 9, 3) scaled
    body_of_element: np.ndarray  # (E,)
    body_ranges: np.ndarray  # (n_bodies, 2) element index range of each body
    centres: np.ndarray  # (n_bodies, 3) scaled reference points
    collocation: np.ndarray  # (E, 3) element centres (node 8), the collocation points
    collocation_normals: np.ndarray  # (E, 3) unit outward normals there
    parent_element: np.ndarray  # (E,) the element of its body's own mesh each element refines
    element_radius: np.ndarray  # (E,) largest node distance from the centre node
    areas: np.ndarray  # (E,) element areas with the operator's quadrature
    qp_positions: np.ndarray  # (E, Q, 3)
    qp_area_vectors: np.ndarray  # (E, Q, 3) outward normal * Jacobian * weight
    order: int
    unresolved_contacts: dict  # {(body, neighbour or refinement.WALL): gap}, scaled units

    @classmethod
    def from_bodies(cls, bodies, order: int, length_scale: float, wall: bool,
                    contact_refinement: float = 0.0, refine_fixed_at_wall: bool = True) -> "SurfaceGeometry":
        nodes = [b.world_nodes()[b.mesh.elements] / length_scale for b in bodies]
        exempt = None if refine_fixed_at_wall else [b.fixed for b in bodies]
        nodes, unresolved, parents = refine_near_contact(nodes, wall, contact_refinement, wall_exempt=exempt)
        counts = [len(n) for n in nodes]
        element_nodes = np.concatenate(nodes)
        stops = np.cumsum(counts)
        ranges = np.stack([stops - counts, stops], axis=1)
        positions, area_vectors = quad9.surface_quadrature(element_nodes, order)
        centre = element_nodes[:, 8]
        return cls(
            length_scale=length_scale,
            element_nodes=element_nodes,
            body_of_element=np.repeat(np.arange(len(bodies)), counts),
            body_ranges=ranges,
            centres=np.array([b.position for b in bodies]) / length_scale,
            collocation=centre,
            collocation_normals=quad9.centre_normals(element_nodes),
            parent_element=np.concatenate(parents),
            element_radius=np.linalg.norm(element_nodes - centre[:, None], axis=-1).max(axis=1),
            areas=np.linalg.norm(area_vectors, axis=-1).sum(axis=1),
            qp_positions=positions,
            qp_area_vectors=area_vectors,
            order=order,
            unresolved_contacts=unresolved,
        )

    def unchanged_bodies(self, previous: "SurfaceGeometry | None") -> np.ndarray:
        """Per body: True if its elements are exactly those it had in ``previous`` (same place,
        same refinement, same scaling), so data computed from them can be kept."""
        n_bodies = len(self.body_ranges)
        same = np.zeros(n_bodies, dtype=bool)
        if previous is None or previous.length_scale != self.length_scale or previous.order != self.order:
            return same
        for p in range(min(n_bodies, len(previous.body_ranges))):
            a0, a1 = previous.body_ranges[p]
            b0, b1 = self.body_ranges[p]
            same[p] = a1 - a0 == b1 - b0 and np.array_equal(previous.element_nodes[a0:a1], self.element_nodes[b0:b1])
        return same

    def body(self, p: int) -> "SurfaceGeometry":
        """The geometry of body p alone: its elements (refined as here), its own range 0..E_p.
        An operator on it has exactly the diagonal block of body p of an operator on all bodies,
        since an element integral depends only on its element and its pole (and the wall)."""
        start, stop = self.body_ranges[p]
        own = slice(start, stop)
        return SurfaceGeometry(
            length_scale=self.length_scale, element_nodes=self.element_nodes[own],
            body_of_element=np.zeros(stop - start, dtype=self.body_of_element.dtype),
            body_ranges=np.array([[0, stop - start]]), centres=self.centres[p : p + 1],
            collocation=self.collocation[own], collocation_normals=self.collocation_normals[own],
            parent_element=self.parent_element[own],
            element_radius=self.element_radius[own], areas=self.areas[own],
            qp_positions=self.qp_positions[own], qp_area_vectors=self.qp_area_vectors[own], order=self.order,
            unresolved_contacts={})

    def elements_of(self, bodies) -> np.ndarray:
        """Element indices of the given bodies, in order."""
        return np.concatenate([np.arange(*self.body_ranges[p]) for p in bodies] or [np.zeros(0, int)])

    @property
    def n_elements(self) -> int:
        return len(self.collocation)

    def rigid_modes(self, body: int) -> np.ndarray:
        """(3 n, 6) rigid fields at the body's collocation points: e_l, then e_l x (xi - x_c)."""
        start, stop = self.body_ranges[body]
        rho = self.collocation[start:stop] - self.centres[body]
        n = stop - start
        modes = np.zeros((n, 3, 6))
        modes[:, :, :3] = np.eye(3)
        for axis in range(3):
            modes[:, :, 3 + axis] = np.cross(np.eye(3)[axis], rho)
        return modes.reshape(3 * n, 6)

    def to_device(self, kernels, quadrature, device):
        """The ``Surface`` struct the kernels read (kernels/assembly.py), on ``device``."""
        wp = runtime.init()
        dtype = kernels.green.dtype

        def vectors(a):
            return wp.array(np.ascontiguousarray(a.reshape(-1, 3)), dtype=kernels.green.vec3, device=device)

        def scalars(a, kind=dtype):
            return wp.array(np.ascontiguousarray(a), dtype=kind, device=device)

        gauss_x, gauss_w = np.polynomial.legendre.leggauss(self.order)
        counts = self.body_ranges[:, 1] - self.body_ranges[:, 0]
        surf = kernels.Surface()
        surf.poles = vectors(self.collocation)
        surf.pole_normals = vectors(self.collocation_normals)
        surf.nodes = vectors(self.element_nodes)
        surf.centres = vectors(self.collocation)
        surf.radii = scalars(self.element_radius)
        surf.qp_pos = vectors(self.qp_positions)
        surf.qp_area = vectors(self.qp_area_vectors)
        surf.n_qp = self.order**2
        surf.gauss_x = scalars(gauss_x)
        surf.gauss_w = scalars(gauss_w)
        duffy_x, duffy_w = np.polynomial.legendre.leggauss(max(4, 2 * self.order))
        surf.duffy_x = scalars(duffy_x)
        surf.duffy_w = scalars(duffy_w)
        surf.near_factor = dtype(quadrature.near_factor)
        surf.max_level = quadrature.max_level if quadrature.adaptive else 0
        surf.body_start = scalars(np.repeat(self.body_ranges[:, 0], counts).astype(np.int32), int)
        surf.body_end = scalars(np.repeat(self.body_ranges[:, 1], counts).astype(np.int32), int)
        return surf
