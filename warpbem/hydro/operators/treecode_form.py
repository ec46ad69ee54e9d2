"""The treecode form of the double layer (``treecode.py``): the near field exactly (element
integrals with the adaptive quadrature and the self blocks; stored per leaf when it fits, else
recomputed in every product), the far field of the double layer and of point forces at the
``point_sources`` by interpolation, in O(N)."""

from __future__ import annotations

import numpy as np

from ... import runtime
from ...kernels import integrals
from ...surfaces.quad9 import CENTRE_NODE
from ..geometry import SurfaceGeometry, basis_at_gauss_points
from ..treecode import FarField, TreecodeOptions
from .dense import assembled_alone
from .description import BoundaryOperator, dof_indices
from .discrete import DiscreteOperator


def quadrature_strengths(geometry: SurfaceGeometry, density: np.ndarray) -> np.ndarray:
    """(n_qp, 9) the treecode's strengths of a density: at every regular quadrature point y_s
    the density there (its basis, ``basis_at_gauss_points``) times the area vector n_s w_s,
    component 3 k + i = q_i a_k (the far field of an element is its plain Gauss sum)."""
    values = np.asarray(density, dtype=np.float64).reshape(geometry.n_elements, geometry.points_per_element, 3)
    at_qp = np.einsum("ql,eli->eqi", basis_at_gauss_points(geometry.density_order, geometry.order), values)
    return np.einsum("eqk,eqi->eqki", geometry.qp_area_vectors, at_qp).reshape(-1, 9)


class TreecodeOperator(DiscreteOperator):
    """The double layer of ``description`` by the treecode on ``device`` (``treecode``: its
    ``TreecodeOptions``), summing the point forces at ``point_sources`` with it."""

    mode = "treecode"

    def __init__(self, description: BoundaryOperator, device, point_sources=None,
                 treecode: TreecodeOptions | None = None):
        if description.kind != "double_layer":
            raise ValueError(f"the treecode sums the double layer only, not {description.kind!r}")
        super().__init__(description, device, point_sources)
        options = treecode or TreecodeOptions()
        geo = self.geometry
        n_qp = geo.qp_positions.shape[1]
        far = FarField(self.kernels, self.device, geo.element_nodes[:, CENTRE_NODE], geo.collocation,
                       np.arange(geo.n_points) // geo.points_per_element, geo.qp_positions.reshape(-1, 3),
                       np.repeat(np.arange(geo.n_elements), n_qp), self.point_sources, options)
        self.far_field = far
        group = self._point_group = far.group_of_target()
        self._near_elements = far.near_lists(far.leaf_of_element)
        self.device_lists("near_elements", (group, *self._near_elements))
        self.device_lists("near_poles", (group, *far.near_lists(far.leaf_of_pole)))
        m = geo.points_per_element
        counts = far.targets["stops"] - far.targets["starts"]
        near_bytes = 9 * m * int(counts @ np.diff(self._near_elements[0])) * np.dtype(self.np_dtype).itemsize
        limit = options.near_memory_fraction * runtime.total_memory(self.device)
        self.near_field_stored = options.near_field == "stored" or (options.near_field == "auto" and near_bytes <= limit)
        self.near_field_bytes = near_bytes
        self._near_blocks = None

    def near_blocks(self) -> list:
        """The near field assembled once, per occupied leaf: (its points' unknowns, its near
        elements' unknowns, the dense block between them on the host), self blocks left out."""
        if self._near_blocks is None:
            wp = runtime.init()
            geo, seg = self.geometry, self.far_field.targets
            starts, elements = self._near_elements
            m = geo.points_per_element
            self._near_blocks = []
            for g, (a, b) in enumerate(zip(seg["starts"], seg["stops"])):
                rows = seg["order"][a:b]
                cols = elements[starts[g] : starts[g + 1]]
                block = wp.empty((3 * len(rows), 3 * m * len(cols)), dtype=self.kernels.green.dtype, device=self.device)
                integrals.assemble_entries(self.kernels, self.device, self.surface, rows, cols, block, compact=True)
                points = (m * cols[:, None] + np.arange(m)).ravel()
                self._near_blocks.append((dof_indices(rows), dof_indices(points), block.numpy()))
        return self._near_blocks

    def _stored_near_sum(self, density: np.ndarray) -> np.ndarray:
        n = self.geometry.n_points
        out = np.einsum("aij,aj->ai", self.self_blocks().numpy(), density.reshape(n, 3)).ravel().astype(np.float64)
        for rows, cols, block in self.near_blocks():
            out[rows] += block @ density[cols]
        return out

    def apply(self, density: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        """Near field exactly (element integrals, self blocks), far field by the treecode, of the
        double layer and of the point forces ``pole_forces`` at ``point_sources`` (one (3,) each)."""
        density = np.asarray(density, dtype=self.np_dtype)
        out = (self._stored_near_sum(density) if self.near_field_stored
               else self._listed_sum(density, self._lists["near_elements"]))
        strengths = quadrature_strengths(self.geometry, density)
        if pole_forces is not None:
            pole_forces = np.asarray(pole_forces, dtype=np.float64).reshape(-1, 3)
            out += self._pole_sum(self.geometry.collocation, self.point_sources, pole_forces, "near_poles").ravel()
        return out + self.far_field.apply(strengths, pole_forces).ravel()

    def point_sources_velocity(self, pole_forces: np.ndarray) -> np.ndarray:
        """(n_points, 3) velocity (scaled, viscosity 1) at the collocation points of forces at
        the ``point_sources`` (near poles directly, far ones by the tree)."""
        pole_forces = np.asarray(pole_forces, dtype=np.float64).reshape(-1, 3)
        near = self._pole_sum(self.geometry.collocation, self.point_sources, pole_forces, "near_poles")
        return near + self.far_field.apply(np.zeros((self.far_field.n_qp, 9)), pole_forces)

    def diagonal_blocks(self, bodies) -> dict:
        """{p: body p's own block}: cut from the stored near field where it holds all of p's
        elements, else assembled for the body alone (assembling 1024 bodies alone took longer
        than their near field)."""
        out = {}
        for p in bodies:
            block = self._block_from_near_field(p)
            out[p] = block if block is not None else assembled_alone(self, p)
        return out

    def _block_from_near_field(self, body: int):
        """Body p's block cut from the stored near field (its self blocks added), or None where
        it is not stored or lacks some of p's elements (a body wider than a leaf)."""
        if not self.near_field_stored:
            return None
        geo = self.geometry
        m = geo.points_per_element
        starts, elements = self._near_elements
        own = np.arange(*geo.element_ranges[body])
        a0, a1 = geo.body_ranges[body]
        groups = self._point_group[a0:a1]
        position = self.far_field.position_in_leaf
        out = np.empty((3 * (a1 - a0), 3 * (a1 - a0)))
        blocks = self.near_blocks()
        for g in np.unique(groups):
            cols = elements[starts[g] : starts[g + 1]]
            at = np.minimum(np.searchsorted(cols, own), len(cols) - 1)
            if not np.array_equal(cols[at], own):
                return None
            points = np.flatnonzero(groups == g) + a0
            columns = (m * at[:, None] + np.arange(m)).ravel()
            out[dof_indices(points - a0)] = blocks[g][2][np.ix_(dof_indices(position[points]), dof_indices(columns))]
        n = a1 - a0
        i, k = np.arange(n)[:, None, None], np.arange(3)
        out[3 * i + k[None, :, None], 3 * i + k[None, None, :]] = self.self_blocks().numpy()[a0:a1]
        return out
