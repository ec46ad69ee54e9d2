"""Per-solve surface data of all bodies, in scaled units, on the host and on the device.

Lengths are divided by ``length_scale`` (the mean equivalent radius of the bodies) so the
kernels see O(1) numbers in either precision. Elements of all bodies are concatenated, body
after body; ``body_start``/``body_end`` give each element the range of its own body.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import runtime
from ..surfaces import quad9
from ..surfaces.refinement import body_gap_share, element_radius, refine_near_contact


@dataclass(frozen=True, eq=False)
class SurfaceGeometry:
    """Elements, and the collocation points of the density on them: p x p per element (its
    ``density_order`` p; p = 1: the element centre), element after element, so the points of
    element e are m e ... m e + m - 1 (m = p^2). The per-point arrays (collocation, normals,
    areas, parent_element, body_ranges) are those of the unknowns; for p = 1 they coincide
    with the elements'."""

    length_scale: float  # metres per scaled unit
    element_nodes: np.ndarray  # (E, 9, 3) scaled
    body_of_element: np.ndarray  # (E,)
    element_ranges: np.ndarray  # (n_bodies, 2) element index range of each body
    centres: np.ndarray  # (n_bodies, 3) scaled reference points
    element_radius: np.ndarray  # (E,) largest node distance from the centre node
    qp_positions: np.ndarray  # (E, Q, 3)
    qp_area_vectors: np.ndarray  # (E, Q, 3) outward normal * Jacobian * weight
    order: int
    unresolved_contacts: dict  # {(body, neighbour or gaps.WALL): gap}, scaled units
    density_order: int  # p
    collocation: np.ndarray  # (N, 3) collocation points, N = E p^2
    collocation_normals: np.ndarray  # (N, 3) unit outward normals there
    areas: np.ndarray  # (N,) integral of each point's basis function (p = 1: the element area)
    parent_element: np.ndarray  # (N,) the element of its body's own mesh each point's element refines

    @classmethod
    def from_bodies(cls, bodies, order: int, length_scale: float, wall: bool,
                    contact_refinement: float = 0.0, refine_fixed_at_wall: bool = True,
                    density_order: int = 1) -> "SurfaceGeometry":
        nodes = [b.world_nodes()[b.mesh.elements] / length_scale for b in bodies]
        exempt = None if refine_fixed_at_wall else [b.fixed for b in bodies]
        nodes, unresolved, parents = refine_near_contact(nodes, wall, contact_refinement, wall_exempt=exempt,
                                                         body_gap_share=body_gap_share(density_order))
        counts = [len(n) for n in nodes]
        element_nodes = np.concatenate(nodes)
        stops = np.cumsum(counts)
        positions, area_vectors = quad9.surface_quadrature(element_nodes, order)
        centre = element_nodes[:, quad9.CENTRE_NODE]
        m = density_order**2
        if density_order == 1:  # the element centres (the centre nodes exactly) and areas
            collocation, normals = centre, quad9.centre_normals(element_nodes)
            areas = np.linalg.norm(area_vectors, axis=-1).sum(axis=1)
        else:
            n, ns, nt = _shapes_at_density_points(density_order)
            collocation = np.einsum("qa,eai->eqi", n, element_nodes).reshape(-1, 3)
            normals = quad9.normals_from_slopes(element_nodes, ns, nt).reshape(-1, 3)
            areas = (np.linalg.norm(area_vectors, axis=-1) @ basis_at_gauss_points(density_order, order)).ravel()
        return cls(
            length_scale=length_scale,
            element_nodes=element_nodes,
            body_of_element=np.repeat(np.arange(len(bodies)), counts),
            element_ranges=np.stack([stops - counts, stops], axis=1),
            centres=np.array([b.position for b in bodies]) / length_scale,
            element_radius=element_radius(element_nodes),
            qp_positions=positions,
            qp_area_vectors=area_vectors,
            order=order,
            unresolved_contacts=unresolved,
            density_order=density_order,
            collocation=collocation,
            collocation_normals=normals,
            areas=areas,
            parent_element=np.repeat(np.concatenate(parents), m),
        )

    @property
    def points_per_element(self) -> int:
        return self.density_order**2

    @property
    def body_ranges(self) -> np.ndarray:
        """(n_bodies, 2) collocation point index range of each body."""
        return self.element_ranges * self.points_per_element

    @property
    def body_of_point(self) -> np.ndarray:
        return np.repeat(self.body_of_element, self.points_per_element)

    def unchanged_bodies(self, previous: "SurfaceGeometry | None") -> np.ndarray:
        """Per body: True if its elements are exactly those it had in ``previous`` (same place,
        same refinement, same scaling, same density), so data computed from them can be kept."""
        n_bodies = len(self.element_ranges)
        same = np.zeros(n_bodies, dtype=bool)
        if (previous is None or previous.length_scale != self.length_scale or previous.order != self.order
                or previous.density_order != self.density_order):
            return same
        for p in range(min(n_bodies, len(previous.element_ranges))):
            a0, a1 = previous.element_ranges[p]
            b0, b1 = self.element_ranges[p]
            same[p] = a1 - a0 == b1 - b0 and np.array_equal(previous.element_nodes[a0:a1], self.element_nodes[b0:b1])
        return same

    def body(self, p: int) -> "SurfaceGeometry":
        """The geometry of body p alone: its elements (refined as here), its own range 0..E_p.
        An operator on it has exactly the diagonal block of body p of an operator on all bodies,
        since an element integral depends only on its element and its pole (and the wall)."""
        start, stop = self.element_ranges[p]
        own = slice(start, stop)
        points = slice(*self.body_ranges[p])
        return SurfaceGeometry(
            length_scale=self.length_scale, element_nodes=self.element_nodes[own],
            body_of_element=np.zeros(stop - start, dtype=self.body_of_element.dtype),
            element_ranges=np.array([[0, stop - start]]), centres=self.centres[p : p + 1],
            element_radius=self.element_radius[own], qp_positions=self.qp_positions[own],
            qp_area_vectors=self.qp_area_vectors[own], order=self.order, unresolved_contacts={},
            density_order=self.density_order, collocation=self.collocation[points],
            collocation_normals=self.collocation_normals[points], areas=self.areas[points],
            parent_element=self.parent_element[points])

    def elements_of(self, bodies) -> np.ndarray:
        """Element indices of the given bodies, in order."""
        return np.concatenate([np.arange(*self.element_ranges[p]) for p in bodies] or [np.zeros(0, int)])

    def points_of(self, bodies) -> np.ndarray:
        """Collocation point (unknown) indices of the given bodies, in order."""
        return np.concatenate([np.arange(*self.body_ranges[p]) for p in bodies] or [np.zeros(0, int)])

    @property
    def n_elements(self) -> int:
        return len(self.element_nodes)

    @property
    def n_points(self) -> int:
        return len(self.collocation)

    def rigid_modes(self, body: int) -> np.ndarray:
        """(3 n, 6) rigid fields at the body's collocation points: e_l, then e_l x (xi - x_c)."""
        start, stop = self.body_ranges[body]
        rho = self.collocation[start:stop] - self.centres[body]
        n = stop - start
        modes = np.zeros((n, 3, 6))
        modes[:, :, :3] = np.eye(3)
        # e_l x rho, written out (three np.cross calls were most of this function's time)
        modes[:, 1, 3], modes[:, 2, 3] = -rho[:, 2], rho[:, 1]
        modes[:, 0, 4], modes[:, 2, 4] = rho[:, 2], -rho[:, 0]
        modes[:, 0, 5], modes[:, 1, 5] = -rho[:, 1], rho[:, 0]
        return modes.reshape(3 * n, 6)

    def to_device(self, kernels, quadrature, device):
        """The ``Surface`` struct the kernels read (kernels/assembly.py), on ``device``."""
        wp = runtime.init()
        dtype = kernels.green.dtype

        # copy=False: on the CPU the kernels read the host arrays where they are (never written;
        # the nine copies took a twentieth of a small solve); elsewhere Warp copies them anyway
        def vectors(a):
            return wp.array(np.ascontiguousarray(a.reshape(-1, 3)), dtype=kernels.green.vec3, device=device, copy=False)

        def scalars(a, kind=dtype):
            return wp.array(np.ascontiguousarray(a), dtype=kind, device=device, copy=False)

        counts = self.body_ranges[:, 1] - self.body_ranges[:, 0]
        surf = kernels.Surface()
        surf.poles = vectors(self.collocation)
        surf.pole_normals = vectors(self.collocation_normals)
        surf.nodes = vectors(self.element_nodes)
        # p = 1: the collocation points are the centre nodes
        surf.centres = surf.poles if self.density_order == 1 else vectors(self.element_nodes[:, quad9.CENTRE_NODE])
        surf.radii = scalars(self.element_radius)
        surf.qp_pos = vectors(self.qp_positions)
        surf.qp_area = vectors(self.qp_area_vectors)
        surf.n_qp = self.order**2
        surf.gauss_x, surf.gauss_w = _gauss_rule_on(self.order, dtype, str(device))
        surf.duffy_x, surf.duffy_w = _gauss_rule_on(max(4, 2 * self.order), dtype, str(device))
        surf.near_factor = dtype(quadrature.near_factor)
        surf.max_level = quadrature.max_level if quadrature.adaptive else 0
        surf.density_x, surf.qp_basis = _density_data_on(self.density_order, self.order, dtype, str(device))
        surf.body_start = scalars(np.repeat(self.element_ranges[:, 0], counts).astype(np.int32), int)
        surf.body_end = scalars(np.repeat(self.element_ranges[:, 1], counts).astype(np.int32), int)
        return surf


@functools.lru_cache(maxsize=None)
def _gauss_rule_on(order: int, dtype, device: str):
    """A 1-D Gauss rule as two device arrays, made once per order, precision and device (never
    written: the kernels only read them)."""
    wp = runtime.init()
    return tuple(wp.array(np.asarray(a), dtype=dtype, device=device) for a in quad9.gauss_legendre(order))


def density_points(density_order: int):
    """(s, t) of the p x p collocation points on the parameter square, index i + p j: the
    Gauss-Legendre points (p = 1: the centre), interior, so a density discontinuous between
    elements needs no conformity with the hanging nodes of the contact refinement."""
    x = quad9.gauss_legendre(density_order)[0]
    s, t = np.meshgrid(x, x, indexing="xy")
    return s.ravel(), t.ravel()


@functools.lru_cache(maxsize=None)
def _shapes_at_density_points(density_order: int):
    """The QUAD9 shape functions and their s and t derivatives ((p^2, 9) each) at the density's
    collocation points (remembered, read-only: the same for every solve)."""
    shapes = quad9.shape_functions(*density_points(density_order))
    for a in shapes:
        a.setflags(write=False)
    return shapes


def density_basis(density_order: int, s, t) -> np.ndarray:
    """(len(s), p^2) Lagrange basis of the density on its collocation points at (s, t)."""
    x = quad9.gauss_legendre(density_order)[0]

    def line(u):
        u = np.asarray(u, dtype=float)[:, None]
        out = np.ones((len(u), len(x)))
        for i in range(len(x)):
            for k in range(len(x)):
                if k != i:
                    out[:, i] *= (u[:, 0] - x[k]) / (x[i] - x[k])
        return out

    ls, lt = line(s), line(t)
    return (lt[:, :, None] * ls[:, None, :]).reshape(len(ls), -1)  # index i + p j


@functools.lru_cache(maxsize=None)
def basis_at_gauss_points(density_order: int, order: int) -> np.ndarray:
    """(order^2, p^2) the density basis at the regular Gauss points of ``surface_quadrature``
    (remembered, read-only)."""
    qp = quad9.gauss_legendre_square(order)[0]
    basis = density_basis(density_order, qp[:, 0], qp[:, 1])
    basis.setflags(write=False)
    return basis


@functools.lru_cache(maxsize=None)
def _density_data_on(density_order: int, order: int, dtype, device: str):
    """The collocation abscissae and the basis at the regular Gauss points, on the device."""
    wp = runtime.init()
    return (wp.array(np.asarray(quad9.gauss_legendre(density_order)[0]), dtype=dtype, device=device),
            wp.array(basis_at_gauss_points(density_order, order), dtype=wp.types.vector(density_order**2, dtype),
                     device=device))
