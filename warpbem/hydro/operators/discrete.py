"""What every discrete form of a ``BoundaryOperator`` shares: a SciPy ``LinearOperator`` on host
float64 vectors (``apply``, and ``to_dense`` for tests), its self blocks, each body's own block
(the preconditioner's), and the sums that do not depend on the form: point forces at points
(the CDL's completions) and the layer's field off the surfaces. Launches go through the
launchers of ``kernels/integrals.py``."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from ... import runtime
from ...kernels import integrals
from .description import IDENTITY_KINDS, SINGLE_LAYERS, BoundaryOperator


class DiscreteOperator(spla.LinearOperator):
    """One discrete form of ``description`` on ``device`` (subclasses: dense, direct sum,
    treecode), with ``point_sources`` (P, 3) whose point forces it can sum with the layer."""

    mode = ""

    def __init__(self, description: BoundaryOperator, device, point_sources=None):
        from ...kernels.assembly import build_kernels  # the top-level kernels/ folder, installed as warpbem.kernels

        runtime.init()
        self.description = description
        self.geometry, self.wall, self.quadrature = description.geometry, description.wall, description.quadrature
        self.kind = description.kind
        self.device = runtime.resolve_device(device)
        self.np_dtype = np.float64 if description.dtype == "float64" else np.float32
        dtype = runtime.dtype_of(description.dtype)
        self.kernels = build_kernels(dtype, self.wall, self.kind, self.geometry.density_order)
        # the self blocks are the double layer's in the kinds without an identity of their own
        self.self_block_kernels = build_kernels(dtype, self.wall)
        self.size = description.size
        self.surface = self.geometry.to_device(self.kernels, self.quadrature, self.device)
        self.point_sources = np.zeros((0, 3)) if point_sources is None else np.asarray(point_sources, dtype=float)
        self._lists = {}
        self._diagonal = None
        # per body: whether its blocks came from a KeptBlocks store (the dense form's only)
        self.reused_bodies = np.zeros(len(self.geometry.body_ranges), dtype=bool)
        super().__init__(np.float64, (self.size, self.size))

    # -- the product ------------------------------------------------------------------------
    def apply(self, density: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        """This operator applied to a host vector of length ``size`` (for the double layer
        (1/2 + D) q), a float64 host vector. ``pole_forces`` (one force per ``point_sources``
        pole, scaled, viscosity 1): their Stokeslets in the same sum, by the treecode only."""
        raise NotImplementedError

    def _matvec(self, x):
        return self.apply(np.ravel(x))

    def to_dense(self) -> np.ndarray:
        """The (size, size) float64 matrix of this form: here its product with every unit
        vector (tests; the dense form gives its assembled matrix)."""
        unit = np.zeros(self.size)
        columns = np.empty((self.size, self.size))
        for j in range(self.size):
            unit[j] = 1.0
            columns[:, j] = self.apply(unit)
            unit[j] = 0.0
        return columns

    def _refuse_pole_forces(self, pole_forces) -> None:
        if pole_forces is not None:
            raise ValueError("pole forces are summed by the treecode only; use point_force_velocity")

    def _listed_sum(self, density: np.ndarray, lists) -> np.ndarray:
        """The element integrals over the listed elements of each point's group, and the self
        blocks: every element for the direct sum, the near field for the treecode."""
        n = self.geometry.n_points
        return integrals.apply_listed(self.kernels, self.device, self.surface, self.self_blocks(),
                                      np.asarray(density, dtype=self.np_dtype).reshape(n, 3), lists)

    def device_lists(self, name: str, lists) -> tuple:
        """Device copies of one lists triple (``kernels/integrals.py``), made once per name."""
        if name not in self._lists:
            self._lists[name] = integrals.device_lists(lists, self.device)
        return self._lists[name]

    # -- blocks -----------------------------------------------------------------------------
    def self_blocks(self):
        """(n_points,) device 3x3 diagonal blocks: for the identity kinds minus the sum over the
        other elements of the same body (of the double layer for the adjoint), for the single
        layers the Duffy integral (``description.py``)."""
        if self._diagonal is None:
            singular = self.kind in SINGLE_LAYERS
            own = self.kernels if self.kind in IDENTITY_KINDS else self.self_block_kernels
            kernel = self.kernels.self_blocks if singular else own.same_body_row_sums
            self._diagonal = integrals.self_blocks(self.kernels, self.device, self.surface, self.geometry.n_points,
                                                   kernel, 1.0 if singular else -1.0)
        return self._diagonal

    def body_alone(self, body: int) -> BoundaryOperator:
        """This operator on body p's elements alone: its diagonal block (``geometry.body``)."""
        d = self.description
        return BoundaryOperator(self.geometry.body(body), d.wall, d.quadrature, d.kind, d.dtype)

    def diagonal_blocks(self, bodies) -> dict:
        """{p: the (3 E_p, 3 E_p) host float64 block of this operator for body p's own elements}:
        cut from the dense form's matrix, assembled for the body alone by the others
        (``dense.assembled_alone``)."""
        raise NotImplementedError

    # -- point forces and the field off the surfaces ----------------------------------------
    def point_force_tensors(self, targets: np.ndarray, poles: np.ndarray) -> np.ndarray:
        """(T, P, 3, 3) Green's tensors G(target, pole) (scaled units, viscosity 1): the
        velocities of several load cases on the same few poles from one launch."""
        return integrals.point_force_tensors(self.kernels, self.device, targets, poles)

    def point_force_velocity(self, targets: np.ndarray, poles: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """sum_p G(target, pole_p) force_p at every target (scaled units, viscosity 1)."""
        return self._pole_sum(targets, poles, forces, integrals.every_item(len(targets), len(poles)))

    def _pole_sum(self, targets, poles, forces, lists) -> np.ndarray:
        """sum over each target's listed poles (a name of ``device_lists`` or a host triple) of G f."""
        on_device = self._lists[lists] if isinstance(lists, str) else integrals.device_lists(lists, self.device)
        return integrals.point_force_velocity(self.kernels, self.device, targets, poles, forces, on_device)

    def field_at(self, targets: np.ndarray, density: np.ndarray, pole_forces: np.ndarray | None = None,
                 element_lists=None, pole_lists=None) -> np.ndarray:
        """(T, 3) the layer of ``density`` (scaled, viscosity 1), with the Stokeslets of
        ``pole_forces`` at the ``point_sources``, at points off the surfaces (kernel
        ``field_at_points``: nearly singular element integrals adaptive): over every element and
        pole, or over the listed ones per target (``element_lists``, ``pole_lists``: (group of
        each target, CSR starts, items), as ``FarField.near_lists``)."""
        n = len(targets)
        lists = element_lists or integrals.every_item(n, self.geometry.n_elements)
        velocity = integrals.field_at_points(
            self.kernels, self.device, self.surface, np.ascontiguousarray(density, dtype=self.np_dtype).reshape(-1, 3),
            np.ascontiguousarray(targets, dtype=self.np_dtype), lists)
        if pole_forces is not None:
            pole_lists = pole_lists or integrals.every_item(n, len(self.point_sources))
            velocity += self._pole_sum(targets, self.point_sources, pole_forces, pole_lists)
        return velocity
