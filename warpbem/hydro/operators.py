"""The boundary-integral operators of the solves, one class for every kernel kind: the double
layer of the Completed Double Layer method, (1/2 + D) q (below), its adjoint, the single layers
and the elastic double layer's parts.

For a density q constant on each element and collocation at the element centres xi_a,

    ((1/2 + D) q)_a = sum_{b in body(a)} I_ab (q_b - q_a) + sum_{b not in body(a)} I_ab q_b,

with I_ab = int_{E_b} Sigma(x, xi_a) . n(x) dS(x) (``kernels/greens.py``). With a density of
order p > 1 (Lagrange on p x p points per element, ``geometry.py``) the unknowns are the values
at those points, I_ab becomes one block per basis function, int_{E_b} Sigma . n L_l dS, and the
same identity gives the self block (the basis functions sum to one). The first sum is the
constant-density identity int_S Sigma . n dS = -1/2 on a closed surface (thesis ch. 3.3;
Phan-Thien & Fan 1996), which holds for the wall kernel too because the image part is regular
inside the body; it replaces the singular self-element integral, and makes the discrete
operator annihilate rigid translations exactly.

The same class gives the adjoint operator (1/2 + D*) of the traction problem (``kind =
"adjoint_double_layer"``, ``traction.py``): I*_ab = int_{E_b} of the traction at xi_a of a point
force at x (``kernels/assembly.py``), and its singular self element taken as the double
layer's, I*_aa = I_aa = -1/2 - sum_{b != a in body(a)} I_ab (Phan-Thien & Fan 1996; thesis ch.
3.3): on a sphere in free space the two integrands agree pointwise (r.n(x) = -r.n(xi) = r^2 /
2a), elsewhere they differ by the curvature change over one element.

The single layers (``kind = "single_layer"``, the Stokeslet; ``"inverse_distance"``, for the
Kelvinlet) have no 1/2: their weakly singular self element is integrated by Duffy triangles.
The two parts of the elastic double layer (``"elastic_rotation"``, ``"elastic_dyadic"``,
``warpbem/elastic/interior.py``) take their self blocks from their own rigid-translation
identity, as the double layer does.

Applied as an assembled dense matrix (Warp assembly, NumPy BLAS on CPU, a Warp kernel on
CUDA), matrix-free (the direct sum: Warp recomputes the element integrals in every product), or
by the treecode (``treecode.py``: the near field exactly, stored or recomputed, the far field of
the double layer and of point forces at ``point_sources`` by interpolation, O(N)).
``mode="auto"`` follows one rule, ``choose_operator``: dense while the matrix takes at most a
quarter of the device's total memory, else the treecode (the double layer) or matrix-free (other
kinds); a ``MobilitySolver`` decides it once, at its first solve, for all later ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import runtime
from ..kernels.launch import launch_rows
from .geometry import SurfaceGeometry, basis_at_gauss_points
from .options import OPERATOR_MODES
from .treecode import FarField, TreecodeOptions


def dof_indices(points: np.ndarray) -> np.ndarray:
    """Unknown indices 3a, 3a+1, 3a+2 of the given collocation points."""
    return (3 * np.asarray(points)[:, None] + np.arange(3)).ravel()


@dataclass(frozen=True)
class QuadratureOptions:
    """order: Gauss points per direction on an element (and on each sub-panel). The default 2
    (2x2 points) gives the solver the same accuracy as the seed's 3x3 at about 60 % of the
    cost (benchmarks/pareto.py): the error of the piecewise-constant density dominates, and
    with adaptive subdivision 2x2 keeps element integrals within 2e-4 at any gap;
    adaptive: subdivide elements near a pole or its wall image (else plain Gauss);
    near_factor: subdivide while distance < near_factor * panel radius;
    max_level: deepest quadtree level of the subdivision."""

    order: int = 2
    adaptive: bool = True
    near_factor: float = 3.0
    max_level: int = 10

    def __post_init__(self):
        if int(self.order) != self.order or not 1 <= self.order <= 10:
            raise ValueError(f"quadrature order must be an integer in [1, 10], got {self.order!r}")
        if not np.isfinite(self.near_factor) or self.near_factor <= 0:
            raise ValueError(f"near_factor must be positive, got {self.near_factor!r}")
        if int(self.max_level) != self.max_level or not 0 <= self.max_level <= 24:
            raise ValueError(f"max_level must be an integer in [0, 24], got {self.max_level!r}")


SINGLE_LAYERS = ("single_layer", "inverse_distance")
# kinds whose self block follows from the rigid-translation identity of their own row sums
IDENTITY_KINDS = ("double_layer", "elastic_rotation", "elastic_dyadic")


DENSE_MEMORY_SHARE = 0.25  # "auto": dense while one matrix takes at most this share of the memory
DENSE_HEADROOM = 0.03  # a dense matrix's buffer (CPU) has room for this share more unknowns


def choose_operator(size: int, dtype: str = "float64", device="cpu", kind: str = "double_layer") -> str:
    """The one rule for ``mode="auto"``, an operator of ``size`` unknowns from the device's total
    memory: "dense" while the matrix takes at most DENSE_MEMORY_SHARE of it (room for the
    solver's factored blocks, and for a second matrix in the steps whose kept block cannot move
    in place, ``_moved_kept_block``), else "treecode" for the double layer, "matrix_free" for
    the other kinds. From the total, not the free memory: the free memory falls with the run's
    own kept systems, and a run that chose by it switched to matrix-free part-way."""
    itemsize = 8 if dtype == "float64" else 4
    device = runtime.resolve_device(device)
    if size**2 * itemsize <= DENSE_MEMORY_SHARE * runtime.total_memory(device):
        return "dense"
    return "treecode" if kind == "double_layer" else "matrix_free"


def quadrature_strengths(geometry: SurfaceGeometry, density: np.ndarray) -> np.ndarray:
    """(n_qp, 9) the treecode's strengths of a density: at every regular quadrature point y_s
    the density there (its basis, ``basis_at_gauss_points``) times the area vector n_s w_s,
    component 3 k + i = q_i a_k (the far field of an element is its plain Gauss sum)."""
    values = np.asarray(density, dtype=np.float64).reshape(geometry.n_elements, geometry.points_per_element, 3)
    at_qp = np.einsum("ql,eli->eqi", basis_at_gauss_points(geometry.density_order, geometry.order), values)
    return np.einsum("eqk,eqi->eqki", geometry.qp_area_vectors, at_qp).reshape(-1, 9)


class DoubleLayerOperator:
    """A boundary-integral operator of one kernel ``kind`` (``kernels/assembly.py``: the double
    layer, by default, its adjoint, the single layers, the elastic double layer's parts) over
    the elements of ``geometry``, dense or matrix-free, with its self blocks (module docstring)."""

    def __init__(self, geometry: SurfaceGeometry, wall: bool, quadrature: QuadratureOptions,
                 dtype: str = "float64", device="cpu", mode: str = "auto", previous: "DoubleLayerOperator | None" = None,
                 kind: str = "double_layer", treecode: TreecodeOptions | None = None,
                 point_sources: np.ndarray | None = None):
        if mode not in OPERATOR_MODES:
            raise ValueError(f"operator mode must be one of {OPERATOR_MODES}, got {mode!r}")
        if mode == "treecode" and kind != "double_layer":
            raise ValueError(f"the treecode sums the double layer only, not {kind!r}")
        from ..kernels.assembly import build_kernels  # the top-level kernels/ folder, installed as warpbem.kernels

        self._wp = runtime.init()
        self.wall = bool(wall)
        self.device = runtime.resolve_device(device)
        self.dtype_name = dtype
        self.np_dtype = np.float64 if dtype == "float64" else np.float32
        self.kind = kind
        self.kernels = build_kernels(runtime.dtype_of(dtype), bool(wall), kind, geometry.density_order)
        # the self blocks are the double layer's in either kind (module docstring)
        self.self_block_kernels = build_kernels(runtime.dtype_of(dtype), bool(wall))
        self.geometry = geometry
        self.quadrature = quadrature
        self.size = 3 * geometry.n_points
        self.surface = geometry.to_device(self.kernels, quadrature, self.device)
        self.mode = choose_operator(self.size, dtype, self.device, kind) if mode == "auto" else mode
        self.point_sources = np.zeros((0, 3)) if point_sources is None else np.asarray(point_sources, dtype=float)
        self._lists = {}
        self.far_field = self._far_field(treecode or TreecodeOptions()) if mode == "treecode" else None
        self._matrix = None
        self._buffer = None  # the memory behind _matrix (it may be larger: DENSE_HEADROOM)
        self._diagonal = None
        self.reused_bodies = self._bodies_unchanged_since(previous)
        self._previous = previous if self.reused_bodies.any() else None

    def _bodies_unchanged_since(self, previous) -> np.ndarray:
        """Bodies whose blocks can be copied from ``previous`` instead of assembled: same
        elements (fixed adherent cells, "model no more than a scene needs"), same kernels."""
        if (previous is None or previous.mode != "dense" or self.mode != "dense"
                or previous.kernels is not self.kernels or previous.quadrature != self.quadrature
                or previous.device != self.device):
            return np.zeros(len(self.geometry.body_ranges), dtype=bool)
        return self.geometry.unchanged_bodies(previous.geometry)

    def assemble(self):
        """The dense matrix of this operator, self blocks included (Warp array on its device)."""
        if self._matrix is not None:
            return self._matrix
        wp = self._wp
        kept = np.flatnonzero(self.reused_bodies)
        moved = np.flatnonzero(~self.reused_bodies)
        kept_rows = self.geometry.points_of(kept)
        moved_rows = self.geometry.points_of(moved)
        previous = self._previous
        gather = len(kept_rows) > 0  # the kept bodies' blocks copied from the previous matrix
        # update the previous matrix in place, its buffer handed over, so a run holds one matrix,
        # not two: as it is where the kept bodies kept their places, or with their block moved
        # where the moving ones changed their element counts (contact refinement)
        matrix = None
        if previous is not None and previous._matrix is not None:
            same = (previous.geometry.n_points == self.geometry.n_points
                    and np.array_equal(previous.geometry.body_ranges[kept], self.geometry.body_ranges[kept]))
            matrix = previous._matrix if same else self._moved_kept_block(previous, kept)
            if matrix is not None:
                self._buffer = previous._buffer
                previous._matrix = previous._buffer = None  # it would assemble afresh if asked again
                gather = False  # their blocks are where they belong
        if matrix is None:
            # every entry is written below (gathered, assembled or a self block): no zero fill,
            # which on the CPU cost as much as the assembly itself for 1632 elements (192 MB);
            # on the CPU room for a few per cent more unknowns, for the moves above
            capacity = int((self.size * (1.0 + DENSE_HEADROOM)) ** 2) if self.device.is_cpu else self.size**2
            self._buffer = wp.empty(capacity, dtype=self.kernels.green.dtype, device=self.device)
            matrix = self._buffer[: self.size**2].reshape((self.size, self.size))

        def indices(a):
            return wp.array(np.ascontiguousarray(a, dtype=np.int32), dtype=int, device=self.device)

        if gather:
            src = indices(self._previous.geometry.points_of(kept))
            dst = indices(kept_rows)
            old = self._previous.assemble()
            launch_rows(self.kernels.gather_entries, len(kept_rows),
                                lambda start, stop: [start, old, src, src, matrix, dst, dst],
                                self.device, extra_dim=len(kept_rows))
            del old
            self._previous._matrix = self._previous._buffer = None  # superseded: free it now
        # rows: collocation points; columns: elements, each filling the columns of its points
        for rows, cols in ((moved_rows, np.arange(self.geometry.n_elements)), (kept_rows, self.geometry.elements_of(moved))):
            if len(rows) and len(cols):
                r, c = indices(rows), indices(cols)
                launch_rows(self.kernels.assemble_entries, len(rows),
                                    lambda start, stop: [start, self.surface, r, c, 0, matrix],
                                    self.device, extra_dim=len(cols))
        if self.device.is_cpu:
            self._host_self_blocks(matrix.numpy(), moved)
        else:  # on the device: the matrix never goes through the host
            self._device_self_blocks(matrix, moved)
        self._matrix = matrix
        self._previous = None  # the old matrix may now be freed
        return matrix

    def _host_self_blocks(self, host: np.ndarray, moved) -> None:
        """The moved bodies' self blocks written into the host matrix (a view of it on the CPU):
        from the identity by a BLAS product, or the single layers' Duffy blocks."""
        if self.kind not in IDENTITY_KINDS:
            a = self.geometry.points_of(moved)[:, None, None]
            k = np.arange(3)
            host[3 * a + k[None, :, None], 3 * a + k[None, None, :]] = self._self_blocks().numpy()[a[:, 0, 0]]
            return
        for p in moved:  # kept bodies brought theirs along
            start, stop = self.geometry.body_ranges[p]
            n = stop - start
            block = host[3 * start : 3 * stop, 3 * start : 3 * stop]  # a view: only its diagonal is written
            # row 3a + j, component i: sum over the body's elements b of (I_ab)_ji, the zero self block
            # included; as a product with stacked identities, so BLAS does it (a strided reduction
            # took as long as the whole threaded assembly of a refined sphere)
            row_sums = (block @ np.tile(np.eye(3, dtype=block.dtype), (n, 1))).reshape(n, 3, 3)
            a, k = np.arange(n)[:, None, None], np.arange(3)
            block[3 * a + k[None, :, None], 3 * a + k[None, None, :]] = -row_sums

    def _device_self_blocks(self, matrix, moved) -> None:
        """The same with Warp kernels on the matrix where it is (identity_self_blocks,
        write_self_blocks), for CUDA; on the CPU the BLAS product above is faster."""
        points = self.geometry.points_of(moved)
        if not len(points):
            return
        wp = self._wp
        listed = wp.array(points.astype(np.int32), dtype=int, device=self.device)
        if self.kind in IDENTITY_KINDS:
            launch_rows(self.kernels.identity_self_blocks, len(points),
                                lambda start, stop: [start, self.surface, listed, matrix], self.device)
        else:
            blocks = self._self_blocks()
            launch_rows(self.kernels.write_self_blocks, len(points),
                                lambda start, stop: [start, listed, blocks, matrix], self.device)

    def _moved_kept_block(self, previous, kept):
        """The previous matrix's buffer with its kept block (the bodies that did not change)
        moved to where this layout puts it, or None where that cannot be done in place: on a
        GPU, kept bodies not contiguous, no room, or the block moving one way while the matrix
        grows the other. Each entry moves at most as far as the block's shift, all the same way,
        so rows copied in that order never overwrite one not yet read."""
        if not self.device.is_cpu or len(kept) == 0 or not np.array_equal(kept, np.arange(kept[0], kept[-1] + 1)):
            return None
        old, new = previous.geometry.body_ranges[kept], self.geometry.body_ranges[kept]
        shift = 3 * int(new[0, 0] - old[0, 0])
        before, size = previous.size, self.size
        if size**2 > previous._buffer.shape[0] or (shift > 0 and size < before) or (shift < 0 and size > before):
            return None
        first, last = 3 * int(old[0, 0]), 3 * int(old[-1, 1])
        flat = previous._buffer.numpy()
        rows = range(first, last) if size <= before and shift <= 0 else range(last - 1, first - 1, -1)
        for r in rows:  # NumPy copies through a buffer where a row overlaps itself
            start = (r + shift) * size + first + shift
            flat[start : start + last - first] = flat[r * before + first : r * before + last]
        return previous._buffer[: size**2].reshape((size, size))

    def diagonal_blocks(self, bodies) -> dict:
        """{p: the (3 E_p, 3 E_p) host float64 block of this operator for body p's own elements}: cut
        from the assembled matrix (one copy off a GPU), or, matrix-free, assembled for each body
        alone (its block fits where the whole matrix does not)."""
        bodies = list(bodies)
        if not bodies:
            return {}
        ranges = self.geometry.body_ranges
        if self.mode == "dense":
            host = self.assemble().numpy()
            return {p: np.array(host[3 * ranges[p][0] : 3 * ranges[p][1], 3 * ranges[p][0] : 3 * ranges[p][1]],
                                dtype=np.float64) for p in bodies}
        out = {}
        for p in bodies:
            block = self._block_from_near_field(p) if self.mode == "treecode" else None
            out[p] = block if block is not None else DoubleLayerOperator(
                self.geometry.body(p), self.wall, self.quadrature, self.dtype_name, self.device, "dense",
                kind=self.kind).assemble().numpy().astype(np.float64)
        return out

    def _block_from_near_field(self, body: int):
        """Body p's block cut from the treecode's stored near field (its self blocks added), or
        None where it is not stored or lacks some of p's elements (a body wider than a leaf):
        assembling 1024 bodies alone took longer than their near field."""
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
            out[dof_indices(points - a0)] = blocks[g][3][np.ix_(dof_indices(position[points]), dof_indices(columns))]
        n = a1 - a0
        i, k = np.arange(n)[:, None, None], np.arange(3)
        out[3 * i + k[None, :, None], 3 * i + k[None, None, :]] = self._self_blocks().numpy()[a0:a1]
        return out

    def _self_blocks(self):
        """Diagonal blocks: for the double layer and its adjoint -(sum over the other elements
        of the same body) of the double layer; for the single layers the Duffy integral."""
        if self._diagonal is None:
            wp = self._wp
            n = self.geometry.n_points
            blocks = wp.zeros(n, dtype=self.kernels.green.mat33, device=self.device)
            singular = self.kind in SINGLE_LAYERS
            own = self.kernels if self.kind in IDENTITY_KINDS else self.self_block_kernels
            kernel = self.kernels.self_blocks if singular else own.same_body_row_sums
            launch_rows(kernel, n, lambda start, stop: [start, self.surface, blocks[start:stop]], self.device)
            self._diagonal = wp.array(blocks.numpy() * (1.0 if singular else -1.0), dtype=self.kernels.green.mat33,
                                      device=self.device)
        return self._diagonal

    def matvec(self, density: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        """This operator applied to a host vector q of length 3 E (for the double layer (1/2 + D) q);
        returns a float64 host vector. With the
        treecode, ``pole_forces`` (one force per ``point_sources`` pole, scaled, viscosity 1) adds
        their Stokeslets in the same sum."""
        wp = self._wp
        if pole_forces is not None and self.mode != "treecode":
            raise ValueError("pole forces are summed by the treecode only; use point_force_velocity")
        density = np.asarray(density, dtype=self.np_dtype)
        if self.mode == "dense":
            matrix = self.assemble()
            if self.device.is_cpu:
                return np.asarray(matrix.numpy() @ density, dtype=np.float64)
            return self.device_matvec(density).numpy().astype(np.float64)
        return self._listed_sum(density) if self.mode == "matrix_free" else self._treecode_matvec(density, pole_forces)

    def device_matvec(self, density):
        """The assembled matrix times ``density`` by the Warp kernel ``dense_matvec`` where the
        matrix lives (a device array; one thread block per row), the product on CUDA; on the CPU
        it checks the kernel against BLAS (tests)."""
        from ..kernels.assembly import MATVEC_BLOCK

        wp = self._wp
        self.assemble()
        entries = self._buffer[: self.size**2]  # the matrix, flat (row-major, no gaps)
        x = wp.array(np.asarray(density, dtype=self.np_dtype), dtype=self.kernels.green.dtype, device=self.device)
        out = wp.zeros(self.size, dtype=self.kernels.green.dtype, device=self.device)
        wp.launch_tiled(self.kernels.dense_matvec, dim=[self.size], inputs=[entries, self.size, x, out],
                        block_dim=MATVEC_BLOCK, device=self.device)
        return out

    def _device_lists(self, name: str, group, starts, items):
        """Device copies of one group/CSR list triple (``apply_matrix_free``), made once."""
        if name not in self._lists:
            wp = self._wp
            self._lists[name] = tuple(wp.array(np.ascontiguousarray(a, dtype=np.int32), dtype=int, device=self.device)
                                      for a in (group, starts, items))
        return self._lists[name]

    def _listed_sum(self, density: np.ndarray, lists: str = "direct") -> np.ndarray:
        """The element integrals of the listed elements of each point's group, and the self
        blocks: all elements for the direct sum, the near field for the treecode."""
        wp = self._wp
        diagonal = self._self_blocks()
        n = self.geometry.n_points
        if lists == "direct":
            group, starts, items = self._device_lists("direct", np.zeros(n), [0, self.geometry.n_elements],
                                                      np.arange(self.geometry.n_elements))
        else:
            group, starts, items = self._lists[lists]
        vec3 = self.kernels.green.vec3
        q = wp.array(density.reshape(n, 3), dtype=vec3, device=self.device)
        out = wp.zeros(n, dtype=vec3, device=self.device)
        launch_rows(
            self.kernels.apply_matrix_free, n,
            lambda start, stop: [start, self.surface, diagonal, q, group, starts, items, out[start:stop]],
            self.device,
        )
        return out.numpy().reshape(-1).astype(np.float64)

    def _far_field(self, options: TreecodeOptions) -> FarField:
        """The treecode of this geometry and its near lists (``treecode.py``)."""
        geo = self.geometry
        n_qp = geo.qp_positions.shape[1]
        far = FarField(self.kernels, self.device, geo.element_nodes[:, 8], geo.collocation,
                       np.arange(geo.n_points) // geo.points_per_element, geo.qp_positions.reshape(-1, 3),
                       np.repeat(np.arange(geo.n_elements), n_qp), self.point_sources, options)
        group = self._point_group = far.group_of_target()
        self._near_elements = far.near_lists(far.leaf_of_element)
        self._device_lists("near_elements", group, *self._near_elements)
        self._device_lists("near_poles", group, *far.near_lists(far.leaf_of_pole))
        m = geo.points_per_element
        counts = far.targets["stops"] - far.targets["starts"]
        near_bytes = 9 * m * int(counts @ np.diff(self._near_elements[0])) * np.dtype(self.np_dtype).itemsize
        limit = options.near_memory_fraction * runtime.total_memory(self.device)
        self.near_field_stored = options.near_field == "stored" or (options.near_field == "auto" and near_bytes <= limit)
        self.near_field_bytes = near_bytes
        self._near_blocks = None
        return far

    def near_blocks(self) -> list:
        """The treecode's near field assembled once, per occupied leaf: (its points' unknowns,
        its near elements' unknowns, the dense block between them), self blocks left out."""
        if self._near_blocks is None:
            wp = self._wp
            geo, seg = self.geometry, self.far_field.targets
            starts, elements = self._near_elements
            m = geo.points_per_element
            self._near_blocks = []
            for g, (a, b) in enumerate(zip(seg["starts"], seg["stops"])):
                rows = seg["order"][a:b]
                cols = elements[starts[g] : starts[g + 1]]
                block = wp.empty((3 * len(rows), 3 * m * len(cols)), dtype=self.kernels.green.dtype, device=self.device)
                r = wp.array(rows.astype(np.int32), dtype=int, device=self.device)
                c = wp.array(cols.astype(np.int32), dtype=int, device=self.device)
                launch_rows(self.kernels.assemble_entries, len(rows),
                                    lambda start, stop: [start, self.surface, r, c, 1, block], self.device,
                                    extra_dim=len(cols))
                points = (m * cols[:, None] + np.arange(m)).ravel()
                self._near_blocks.append((dof_indices(rows), dof_indices(points), block, block.numpy()))
        return self._near_blocks

    def _stored_near_sum(self, density: np.ndarray) -> np.ndarray:
        n = self.geometry.n_points
        out = np.einsum("aij,aj->ai", self._self_blocks().numpy(), density.reshape(n, 3)).ravel().astype(np.float64)
        for rows, cols, unused, block in self.near_blocks():
            out[rows] += block @ density[cols]
        return out

    def _treecode_matvec(self, density: np.ndarray, pole_forces) -> np.ndarray:
        """Near field exactly (element integrals, self blocks), far field by the treecode, of the
        double layer and of the point forces at ``point_sources`` (one force (3,) per pole)."""
        geo = self.geometry
        out = self._stored_near_sum(density) if self.near_field_stored else self._listed_sum(density, "near_elements")
        strengths = quadrature_strengths(geo, density)
        if pole_forces is not None:
            pole_forces = np.asarray(pole_forces, dtype=np.float64).reshape(-1, 3)
            out += self._pole_sum(self.geometry.collocation, self.point_sources, pole_forces, "near_poles").ravel()
        return out + self.far_field.apply(strengths, pole_forces).ravel()

    def point_force_tensors(self, targets: np.ndarray, poles: np.ndarray) -> np.ndarray:
        """(T, P, 3, 3) Green's tensors G(target, pole) (scaled units, viscosity 1): the
        velocities of several load cases on the same few poles from one launch."""
        wp = self._wp
        vec3 = self.kernels.green.vec3
        t = wp.array(np.ascontiguousarray(targets), dtype=vec3, device=self.device)
        p = wp.array(np.ascontiguousarray(poles), dtype=vec3, device=self.device)
        out = wp.empty((len(targets), len(poles)), dtype=self.kernels.green.mat33, device=self.device)
        # a few poles: light work, not worth the thread pool below some thousand targets
        launch_rows(self.kernels.point_force_tensors, len(targets),
                            lambda start, stop: [start, t, p, out[start:stop]], self.device, extra_dim=len(poles),
                            threaded=len(targets) * len(poles) > 20000)
        return out.numpy().astype(np.float64)

    def point_force_velocity(self, targets: np.ndarray, poles: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """sum_p G(target, pole_p) force_p at every target (scaled units, viscosity 1)."""
        n = len(targets)
        lists = (np.zeros(n), [0, len(poles)], np.arange(len(poles)))
        return self._pole_sum(targets, poles, forces, lists)

    def point_sources_velocity(self, pole_forces: np.ndarray) -> np.ndarray:
        """(n_points, 3) velocity (scaled, viscosity 1) at the collocation points of forces at
        the ``point_sources`` (treecode: near poles directly, far ones by the tree)."""
        pole_forces = np.asarray(pole_forces, dtype=np.float64).reshape(-1, 3)
        near = self._pole_sum(self.geometry.collocation, self.point_sources, pole_forces, "near_poles")
        return near + self.far_field.apply(np.zeros((self.far_field.n_qp, 9)), pole_forces)

    def field_at(self, targets: np.ndarray, density: np.ndarray, pole_forces: np.ndarray | None = None,
                 element_lists=None, pole_lists=None) -> np.ndarray:
        """(T, 3) the double layer of ``density`` (scaled, viscosity 1), with the Stokeslets of
        ``pole_forces`` at the ``point_sources``, at points off the surfaces (kernel
        ``field_at_points``: nearly singular element integrals adaptive): over every element and
        pole, or over the listed ones per target (``element_lists``, ``pole_lists``: (group of
        each target, CSR starts, items), as ``FarField.near_lists``)."""
        wp = self._wp
        n = len(targets)
        every = np.zeros(n)
        group, starts, items = element_lists or (every, [0, self.geometry.n_elements], np.arange(self.geometry.n_elements))
        lists = [wp.array(np.ascontiguousarray(a, dtype=np.int32), dtype=int, device=self.device)
                 for a in (group, starts, items)]
        vec3 = self.kernels.green.vec3
        t = wp.array(np.ascontiguousarray(targets, dtype=self.np_dtype), dtype=vec3, device=self.device)
        q = wp.array(np.ascontiguousarray(density, dtype=self.np_dtype).reshape(-1, 3), dtype=vec3, device=self.device)
        out = wp.zeros(n, dtype=vec3, device=self.device)
        launch_rows(self.kernels.field_at_points, n,
                            lambda start, stop: [start, self.surface, q, t, *lists, out[start:stop]], self.device)
        velocity = out.numpy().astype(np.float64)
        if pole_forces is not None:
            pole_lists = pole_lists or (every, [0, len(self.point_sources)], np.arange(len(self.point_sources)))
            velocity += self._pole_sum(targets, self.point_sources, pole_forces, pole_lists)
        return velocity

    def _pole_sum(self, targets, poles, forces, lists) -> np.ndarray:
        """sum over each target's listed poles (a name of ``_lists`` or a triple) of G f."""
        wp = self._wp
        vec3 = self.kernels.green.vec3
        group, starts, items = self._lists[lists] if isinstance(lists, str) else (
            wp.array(np.ascontiguousarray(a, dtype=np.int32), dtype=int, device=self.device) for a in lists)
        t = wp.array(np.ascontiguousarray(targets), dtype=vec3, device=self.device)
        p = wp.array(np.ascontiguousarray(poles), dtype=vec3, device=self.device)
        f = wp.array(np.ascontiguousarray(forces), dtype=vec3, device=self.device)
        out = wp.zeros(len(targets), dtype=vec3, device=self.device)
        launch_rows(
            self.kernels.point_force_velocity, len(targets),
            lambda start, stop: [start, t, p, f, group, starts, items, out[start:stop]], self.device,
        )
        return out.numpy().astype(np.float64)
