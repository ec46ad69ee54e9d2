"""Fast summation of the far field of the double layer and of point forces above the wall.

The operator's product sums, at every collocation point x_a, the element integrals of all
elements (``kernels/assembly.py``). Far from x_a an element integral is its plain Gauss sum,
so the far field is a sum over quadrature points y_s with strengths Q_s = q(y_s) (x) n_s w_s
(the double layer is linear in n dS), plus the completion's point forces F at their poles:

    u_j(x) = sum_s Sigma_ijk(y_s, x) Q_s,ik + sum_poles G_ji(x, y) F_i.

This module evaluates that far field by interpolation on a tree of boxes, in the manner of the
black-box fast multipole method (Fong & Darve 2009, J. Comput. Phys. 228, 8712), which, like the
barycentric Lagrange treecode (Wang, Krasny & Tlupova 2020, Commun. Comput. Phys. 28, 1415),
needs nothing of the kernel but its values, so the Blake (1971) wall images come for free:

* boxes: a uniform quadtree in the wall's plane (x, y), every box spanning the whole height
  range of the scene, so its domain is [box +- margin] x [z_lo, z_hi], the margin the largest
  lateral offset of an element's points from its centre (an element belongs to the box of its
  centre). Leaves are no narrower than the height range, so no box is taller than wide;
* in each box, Chebyshev points (first kind) in x, y and z, the far field of its sources
  represented by strengths at them (anterpolation: Q_m = sum_s L_m(y_s) Q_s with L_m the
  tensor Lagrange basis), and the far field felt in the box by the velocities at them
  (interpolated to the targets by L_m(x)); children pass strengths to parents and parents
  velocities to children by the same interpolation;
* one error parameter, the ``tolerance``: the number of points per direction and level is the
  fewest for which the worst-placed far point's interpolation error, rho^-p with rho its
  Bernstein-ellipse parameter (``FarField.points_per_direction``), is within the tolerance
  (times CALIBRATION), so flat, narrow or wide boxes get what they need, and upper levels fewer;
* the kernel is translation invariant along the wall (it depends on x1 - y1, x2 - y2, x3, y3)
  and every box of a level has the same points up to a lateral shift, so the interactions
  between a box's points and those of a box of its interaction list (the children of its
  parent's neighbours that are not its own neighbours: 40 offsets per level) are matrices per
  offset, computed once by a Warp kernel; by the symmetries of the square 7 of them give all 40
  (points permuted, components rotated), and each is kept as its truncated singular value
  factors (the far field between separated boxes has low numerical rank: Fong & Darve 2009,
  sec. 3.3), applied with BLAS;
* the near field, a leaf's own and its 8 neighbours' elements, is left to the exact element
  integrals (adaptive, self terms: ``operators/treecode_form.py``), the points of a leaf sharing one
  list of near elements.

The error of a product against the direct sum is tabulated over the tolerance in docs/benchmarks.md
("Large arrays") and checked in ``tests/unit/test_treecode.py``: at or below the tolerance for
the double layer; the point forces alone, whose far field is a larger share of their whole,
up to a few times it. Singularities below the boxes do not occur: the wall images x* lie below
z = 0, at least as far from a source box as x itself (|y - x*| >= |y - x| for y3, x3 > 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import runtime
from ..kernels import integrals
from ..options import option, validate

NEAR_FIELD_MODES = ("auto", "stored", "recomputed")
STRENGTHS = 12  # per source: 9 double-layer components (density (x) area vector), 3 of a point force
# Points per direction: enough that the geometric decay rho^-p of the interpolation error of the
# worst-placed pair (the Bernstein-ellipse parameter rho of the nearest far target) falls to
# tolerance / CALIBRATION. The product's error sits well below that worst case (most of it is
# near field; most far pairs are farther): CALIBRATION was set once so that the hardest array
# tried, 11 x 11 spheres whose leaves are only as wide as the scene is high, stays below the
# tolerance (4e-7 at 1e-6; 1e-7 on 8 x 8 and 16 x 16); the docs/benchmarks.md ("Large arrays") reports the
# error over the tolerance.
CALIBRATION = 0.1
MAX_POINTS = 14
# interaction matrices are truncated to the singular values above this share of the tolerance
# (relative to the largest): the far field between well-separated boxes has low numerical rank
# (Fong & Darve 2009, sec. 3.3), which cuts the cost of every interaction several times
RANK_SHARE = 0.1


@dataclass(frozen=True)
class TreecodeOptions:
    """tolerance: the one error parameter, the relative error of a product aimed at (the
    Chebyshev points per direction in each box follow from it and from the box's geometry,
    ``FarField.points_per_direction``; measured errors: docs/benchmarks.md "Large arrays"); near_field: "stored" (the exact near-field blocks assembled once
    and applied with BLAS), "recomputed" (their element integrals recomputed in every product,
    memory O(N) with a small constant), or "auto": stored while they take at most
    ``near_memory_fraction`` of the device's memory.

    Examples
    --------
    A large array's solves through the treecode, its far field to 1e-4 (``SolverOptions``
    carries it to every solve):

    >>> import warpbem as wb
    >>> options = wb.SolverOptions(operator="treecode", treecode=wb.TreecodeOptions(tolerance=1e-4))
    >>> options.treecode.near_field
    'auto'
    >>> wb.TreecodeOptions(near_field="sometimes")
    Traceback (most recent call last):
    ...
    warpbem.options.OptionError: near_field: 'sometimes' is not one of 'auto', 'stored', 'recomputed'
    """

    tolerance: float = option(1e-6, "relative error of a far-field product aimed at (the Chebyshev points per"
                              " direction in each box follow from it)", low=1e-12, high=0.1)
    near_field: str = option("auto", "near-field blocks: stored (assembled once, applied with BLAS), recomputed"
                             " (in every product, memory O(N)) or auto (stored while they fit"
                             " near_memory_fraction of the device's memory)", choices=NEAR_FIELD_MODES)
    near_memory_fraction: float = option(0.25, "with near_field = 'auto', the share of the device's memory the"
                                         " stored near field may take", low=0.0, high=1.0)

    def __post_init__(self):
        validate(self)


def chebyshev_points(p: int) -> np.ndarray:
    """The p Chebyshev points of the first kind on [-1, 1] (symmetric: x_{p-1-a} = -x_a)."""
    return np.cos((2 * np.arange(p) + 1) * np.pi / (2 * p))


def lagrange_basis(u: np.ndarray, p: int) -> np.ndarray:
    """(len(u), p) Lagrange basis on the Chebyshev points at u in [-1, 1], by the barycentric
    formula (Berrut & Trefethen 2004, eq. 4.2 with the first-kind weights of eq. 5.3)."""
    nodes = chebyshev_points(p)
    weights = (-1.0) ** np.arange(p) * np.sin((2 * np.arange(p) + 1) * np.pi / (2 * p))
    diff = np.asarray(u, dtype=float)[:, None] - nodes[None, :]
    exact = diff == 0.0
    diff[exact] = 1.0
    terms = weights / diff
    basis = terms / terms.sum(axis=1, keepdims=True)
    hit = exact.any(axis=1)
    basis[hit] = exact[hit].astype(float)
    return basis


class LateralTree:
    """The quadtree of boxes (module docstring): levels 0 (one box) to ``levels``, box (i, j) of
    level l covering [x0 + i s_l, x0 + (i + 1) s_l] x [y0 + j s_l, ...], s_l = side / 2^l.
    margins: {"sources": ..., "targets": ...}, how far their points reach beyond their box."""

    def __init__(self, element_centres: np.ndarray, extra_points: np.ndarray, margins: dict,
                 z_range: tuple):
        lateral = np.concatenate([element_centres[:, :2], extra_points[:, :2]])
        self.origin = lateral.min(axis=0)
        extent = float((lateral.max(axis=0) - self.origin).max())
        self.margins = margins
        self.z_range = (float(z_range[0]), float(z_range[1]))
        height = self.z_range[1] - self.z_range[0]
        # no box taller than wide, and wide enough that far boxes are apart beyond the margins
        leaf = max(height, 3.0 * (margins["sources"] + margins["targets"]), 1e-12)
        self.side = max(extent * (1.0 + 1e-9), leaf)
        self.levels = int(np.floor(np.log2(self.side / leaf)))

    def box_side(self, level: int) -> float:
        return self.side / 2**level

    def leaf_of(self, points: np.ndarray) -> np.ndarray:
        """(n, 2) integer leaf indices (i, j) of lateral positions."""
        n = 2**self.levels
        index = np.floor((points[:, :2] - self.origin) / self.box_side(self.levels)).astype(int)
        return np.clip(index, 0, n - 1)

    def box_centre(self, level: int, index: np.ndarray) -> np.ndarray:
        return self.origin + (np.asarray(index) + 0.5) * self.box_side(level)

    def half_widths(self, level: int, side: str) -> np.ndarray:
        """(3,) half widths of the interpolation domain of every box of ``level`` for its
        ``side`` ("sources" or "targets")."""
        lateral = 0.5 * self.box_side(level) + self.margins[side]
        return np.array([lateral, lateral, 0.5 * (self.z_range[1] - self.z_range[0])])

    def local_coordinates(self, level: int, index: np.ndarray, points: np.ndarray, side: str) -> np.ndarray:
        """Points mapped to [-1, 1]^3 of the domains of their boxes ``index`` (n, 2)."""
        centre = np.column_stack([self.box_centre(level, index), np.full(len(index), 0.5 * sum(self.z_range))])
        return (points - centre) / self.half_widths(level, side)


def interaction_offsets(level_parity: tuple) -> list:
    """Offsets (di, dj) of the boxes of the interaction list of a box of parity (i % 2, j % 2):
    children of its parent's neighbours (|parent offset| <= 1) that are not its neighbours."""
    pi, pj = level_parity
    out = []
    for di in range(-3, 4):
        for dj in range(-3, 4):
            if max(abs(di), abs(dj)) <= 1:
                continue
            if abs((pi + di) // 2) <= 1 and abs((pj + dj) // 2) <= 1:
                out.append((di, dj))
    return out


def square_symmetries() -> list:
    """The 8 symmetries of the square as 3x3 matrices (signed permutations of x, y; z kept)."""
    out = []
    for swap in (False, True):
        for sx in (1, -1):
            for sy in (1, -1):
                r = np.eye(3)
                if swap:
                    r[[0, 1]] = r[[1, 0]]
                out.append(np.diag([sx, sy, 1.0]) @ r)
    return out


def canonical_offsets() -> dict:
    """{offset: (canonical offset c, index k of the symmetry R in ``square_symmetries``)} with
    R c = offset, 0 <= c_y <= c_x: the 40 interaction offsets fall into 7 classes, so 7
    matrices per level, not 40."""
    offsets = sorted({o for parity in ((0, 0), (0, 1), (1, 0), (1, 1)) for o in interaction_offsets(parity)})
    out = {}
    for o in offsets:
        c = tuple(sorted((abs(o[0]), abs(o[1])), reverse=True))
        for k, r in enumerate(square_symmetries()):
            if np.array_equal(r[:2, :2] @ np.array(c), np.array(o)):
                out[o] = (c, k)
                break
    return out


def strength_transform(r: np.ndarray) -> np.ndarray:
    """(12, 12) H with H s the strength s rotated by r: q (x) a -> (r q) (x) (r a) in the
    double-layer components 3 k + i (q_i a_k), r F for the point force."""
    h = np.zeros((STRENGTHS, STRENGTHS))
    h[:9, :9] = np.kron(r, r)
    h[9:, 9:] = r
    return h


class FarField:
    """The far field at the collocation points of sources at the quadrature points of the
    elements and at point-force poles, for one geometry (module docstring).

    element_of_target / element_of_source: the element each target / quadrature source belongs
    to (their box is that of its centre); poles: (P, 3) point-force positions (their own box);
    cover: points the tree's boxes must reach besides these (laterally and in height), for
    targets given later (``segments_at``)."""

    def __init__(self, kernels, device, element_centres, targets, element_of_target,
                 sources, element_of_source, poles, options: TreecodeOptions, cover: np.ndarray | None = None):
        self.options = options
        self.kernels = kernels
        self.device = device
        self.dtype = np.float64 if kernels.green.dtype == runtime.init().float64 else np.float32
        cover = np.zeros((0, 3)) if cover is None else np.asarray(cover, dtype=float).reshape(-1, 3)
        all_points = np.concatenate([targets, sources, poles, cover])
        # an element's points lie in its box widened by their largest lateral offset from its centre
        margins = {side: float(np.linalg.norm(points[:, :2] - element_centres[owner, :2], axis=1).max(initial=0.0))
                   for side, points, owner in (("sources", sources, element_of_source),
                                               ("targets", targets, element_of_target))}
        self.tree = tree = LateralTree(element_centres, np.concatenate([poles, cover]), margins,
                                       (all_points[:, 2].min(), all_points[:, 2].max()))
        n = 2**tree.levels
        self.points = [self.points_per_direction(level) for level in range(tree.levels + 1)]
        leaf_of_element = tree.leaf_of(element_centres)
        self.leaf_of_element = leaf_of_element[:, 0] * n + leaf_of_element[:, 1]
        target_leaf = leaf_of_element[element_of_target]
        source_leaf = np.concatenate([leaf_of_element[element_of_source], tree.leaf_of(poles)])
        self.n_qp, self.n_poles = len(sources), len(poles)
        self.targets = self._segments(target_leaf, targets, n, "targets")
        self.sources = self._segments(source_leaf, np.concatenate([sources, poles]), n, "sources")
        self.has_far_field = tree.levels >= 2
        if self.has_far_field:
            self.transfer = {side: [self._child_interpolation(level, side) for level in range(tree.levels)]
                             for side in ("sources", "targets")}
            self.offsets = canonical_offsets()
            # per symmetry R: R itself (velocities) and H(R) (strengths), in the kernels' precision
            self.symmetries = [(r.astype(self.dtype), strength_transform(r).astype(self.dtype))
                               for r in square_symmetries()]
            self.interactions = {level: self._interaction_matrices(level) for level in range(2, tree.levels + 1)}
            self.permutations = {level: self._proxy_permutations(level) for level in range(2, tree.levels + 1)}
            # with a cover, targets given later may lie in any box: the far field reaches every one
            self.occupied = self._occupied_boxes(every_target=len(cover) > 0)

    def points_per_direction(self, level: int) -> tuple:
        """(lateral, vertical) Chebyshev points per direction in the boxes of ``level``: the
        fewest with rho^-p <= tolerance / CALIBRATION, rho the Bernstein-ellipse parameter of the
        nearest far point in that direction (Trefethen 2013, Approximation Theory ch. 8). A far
        point lies at least the gap between far boxes (less both margins) from the domain in x or
        y; the kernel's singularity along a line through the domain is then at worst that gap off
        the line's axis (an imaginary offset b in units of the half width: rho = b + sqrt(b^2 +
        1)), worse than the gap along the line (rho = x + sqrt(x^2 - 1), x = 1 + b)."""
        tree = self.tree
        gap = tree.box_side(level) - tree.margins["sources"] - tree.margins["targets"]
        half = np.maximum(tree.half_widths(level, "sources"), tree.half_widths(level, "targets"))
        b = gap / np.maximum(half[[0, 2]], 1e-12)
        rhos = b + np.sqrt(b * b + 1.0)
        want = np.log(CALIBRATION / self.options.tolerance)
        return tuple(int(np.clip(np.ceil(want / np.log(rho)), 2, MAX_POINTS)) for rho in rhos)

    def _segments(self, leaf: np.ndarray, points: np.ndarray, n: int, side: str) -> dict:
        """Points sorted by leaf, with each occupied leaf's range and interpolation weights."""
        flat = leaf[:, 0] * n + leaf[:, 1]
        order = np.argsort(flat, kind="stable")
        boxes, starts = np.unique(flat[order], return_index=True)
        stops = np.append(starts[1:], len(order))
        level = self.tree.levels
        lateral_points, vertical_points = self.points[level]
        u = self.tree.local_coordinates(level, leaf[order], points[order], side)
        lx, ly = (lagrange_basis(u[:, k], lateral_points) for k in range(2))
        lateral = (lx[:, :, None] * ly[:, None, :]).reshape(len(order), lateral_points**2)
        return dict(order=order, boxes=boxes, starts=starts, stops=stops, lateral=lateral,
                    vertical=lagrange_basis(u[:, 2], vertical_points))

    def covers(self, points: np.ndarray) -> np.ndarray:
        """Per point: whether it lies in the tree's domain (its leaves laterally, the height
        range of the boxes), where ``segments_at`` interpolates and does not extrapolate."""
        tree = self.tree
        lateral = (points[:, :2] - tree.origin) / tree.side
        return (np.all((lateral >= 0.0) & (lateral <= 1.0), axis=1)
                & (points[:, 2] >= tree.z_range[0]) & (points[:, 2] <= tree.z_range[1]))

    def segments_at(self, points: np.ndarray) -> dict:
        """Targets given now (``covers`` them), each in the leaf of its own lateral position:
        their interpolation weights for ``interpolate``."""
        if not self.covers(points).all():
            raise ValueError("targets outside the tree's domain: build it with them in ``cover``")
        return self._segments(self.tree.leaf_of(points), points, 2**self.tree.levels, "targets")

    def _child_interpolation(self, level: int, side: str):
        """T_lateral (2, a, A): the parent's (``level``) basis A at the child's point a, c the
        child's position in its parent along one lateral direction; T_z (c, C) likewise in z
        (the same interval, other points)."""
        (pl, pz), (cl, cz) = self.points[level], self.points[level + 1]
        parent, child = self.tree.half_widths(level, side)[0], self.tree.half_widths(level + 1, side)[0]
        quarter = 0.25 * self.tree.box_side(level)
        lateral = np.stack([lagrange_basis((sign * quarter + chebyshev_points(cl) * child) / parent, pl)
                            for sign in (-1, 1)])
        return lateral, lagrange_basis(chebyshev_points(cz), pz)

    def _proxies(self, level: int, side: str, shift=(0, 0)) -> np.ndarray:
        """(p_l^2 p_z, 3) Chebyshev points of the domain of box ``shift`` relative to a box
        centred at the lateral origin, index (a p_l + b) p_z + c for (x, y, z)."""
        lateral_points, vertical_points = self.points[level]
        half = self.tree.half_widths(level, side)
        width = self.tree.box_side(level)
        x, y, z = np.meshgrid(chebyshev_points(lateral_points) * half[0] + shift[0] * width,
                              chebyshev_points(lateral_points) * half[1] + shift[1] * width,
                              chebyshev_points(vertical_points) * half[2] + 0.5 * sum(self.tree.z_range),
                              indexing="ij")
        return np.column_stack([x.ravel(), y.ravel(), z.ravel()])

    def _interaction_matrices(self, level: int) -> dict:
        """{canonical offset c: (right (12 P, r), left (3 P, r))}, the truncated factors K ~ left
        @ right.T of the velocities K (3 P, 12 P) at a box's points per unit strength at the
        points of the box offset by c (Warp kernel ``proxy_interactions``): left the leading
        left singular vectors (from the eigenvectors of K K^T), right = K^T left. The other
        offsets follow by symmetry (``_proxy_permutations``)."""
        targets = self._proxies(level, "targets")
        out = {}
        for offset in sorted({c for c, unused in self.offsets.values()}):
            k = integrals.proxy_interactions(self.kernels, self.device, targets, self._proxies(level, "sources", offset),
                                             STRENGTHS)
            values, vectors = np.linalg.eigh(k @ k.T)
            sigma = np.sqrt(np.maximum(values[::-1], 0.0))
            rank = max(1, int(np.count_nonzero(sigma > RANK_SHARE * self.options.tolerance * sigma[0])))
            left = np.ascontiguousarray(vectors[:, ::-1][:, :rank])
            out[offset] = ((k.T @ left).astype(self.dtype), left.astype(self.dtype))
        return out

    def _proxy_permutations(self, level: int) -> dict:
        """{symmetry index: pi} with R x_t = x_pi(t) for the points x_t of a box centred at the
        lateral origin (Chebyshev points are symmetric, so R permutes them). The kernel is
        equivariant, K(R x, R y) = R K(x, y) H(R)^T, so the matrix of offset R c is
        K_{Rc}[pi(t), pi(j)] = R K_c[t, j] H^T (both boxes' points permuted alike)."""
        lateral_points, vertical_points = self.points[level]
        a, b, c = np.meshgrid(np.arange(lateral_points), np.arange(lateral_points), np.arange(vertical_points),
                              indexing="ij")
        centred = np.stack([a.ravel(), b.ravel()]) - 0.5 * (lateral_points - 1)
        out = {}
        for k, r in enumerate(square_symmetries()):
            moved = np.rint(r[:2, :2] @ centred + 0.5 * (lateral_points - 1)).astype(int)
            out[k] = (moved[0] * lateral_points + moved[1]) * vertical_points + c.ravel()
        return out

    def _occupied_boxes(self, every_target: bool = False) -> list:
        """Per level: boolean (n, n) grids of boxes holding sources and of boxes holding targets
        (``every_target``: every box counts as holding targets)."""
        out = []
        for level in range(self.tree.levels + 1):
            n = 2**level
            shrink = 2 ** (self.tree.levels - level)
            grids = []
            for seg in (self.sources, self.targets):
                leaf = seg["boxes"]
                i, j = leaf // 2**self.tree.levels // shrink, leaf % 2**self.tree.levels // shrink
                grid = np.zeros((n, n), dtype=bool)
                grid[i, j] = True
                grids.append(grid)
            if every_target:
                grids[1][:] = True
            out.append(grids)
        return out

    @property
    def ranks(self) -> dict:
        """{level: the ranks of its truncated interaction matrices}."""
        return {level: [a.shape[1] for a, unused in m.values()] for level, m in getattr(self, "interactions", {}).items()}

    @property
    def memory_bytes(self) -> int:
        """Bytes held: the interaction matrices and the interpolation weights."""
        held = sum(a.nbytes + b.nbytes for level in getattr(self, "interactions", {}).values() for a, b in level.values())
        return held + sum(seg[k].nbytes for seg in (self.sources, self.targets) for k in ("lateral", "vertical"))

    @property
    def position_in_leaf(self) -> np.ndarray:
        """The position of every target among its leaf's targets (in ``targets["order"]``)."""
        seg = self.targets
        position = np.empty(len(seg["order"]), dtype=int)
        position[seg["order"]] = np.arange(len(seg["order"])) - np.repeat(seg["starts"], seg["stops"] - seg["starts"])
        return position

    def group_of_target(self, segments: dict | None = None) -> np.ndarray:
        """The occupied leaf (its index in ``near_lists``) of every target, in the given order
        (of ``segments``, default the tree's targets)."""
        seg = self.targets if segments is None else segments
        group = np.empty(len(seg["order"]), dtype=np.int32)
        group[seg["order"]] = np.repeat(np.arange(len(seg["boxes"])), seg["stops"] - seg["starts"])
        return group

    def near_lists(self, leaf_of_item: np.ndarray, segments: dict | None = None):
        """CSR lists (starts, items) of the items (elements or poles, by their flat leaf index)
        in each occupied target leaf's own and 8 neighbouring leaves: its near field, the part
        the far field leaves out (the leaves of ``segments``, default the tree's targets)."""
        n = 2**self.tree.levels
        order = np.argsort(leaf_of_item, kind="stable")
        sorted_leaves = leaf_of_item[order]
        lists = []
        for box in (self.targets if segments is None else segments)["boxes"]:
            i, j = divmod(int(box), n)
            chunks = []
            for di in (-1, 0, 1):
                if 0 <= i + di < n:
                    lo = (i + di) * n + max(j - 1, 0)
                    hi = (i + di) * n + min(j + 1, n - 1)
                    a, b = np.searchsorted(sorted_leaves, [lo, hi + 1])
                    chunks.append(order[a:b])
            lists.append(np.sort(np.concatenate(chunks)))
        starts = np.concatenate([[0], np.cumsum([len(c) for c in lists])]).astype(np.int32)
        return starts, np.concatenate(lists).astype(np.int32)

    @property
    def leaf_of_pole(self) -> np.ndarray:
        seg = self.sources
        flat = np.empty(len(seg["order"]), dtype=np.int64)
        flat[seg["order"]] = np.repeat(seg["boxes"], seg["stops"] - seg["starts"])
        return flat[self.n_qp :]

    def apply(self, qp_strengths: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray:
        """(T, 3) far-field velocity (times viscosity) at the targets of quadrature-point
        strengths (n_qp, 9) and pole forces (n_poles, 3), in the targets' given order."""
        if not self.has_far_field:
            return np.zeros((len(self.targets["order"]), 3))
        return self.interpolate(self.local_values(qp_strengths, pole_forces), self.targets)

    def local_values(self, qp_strengths: np.ndarray, pole_forces: np.ndarray | None = None) -> np.ndarray | None:
        """(n_leaves, p_l^2, 3 p_z) far-field velocities at every leaf's Chebyshev points (the far
        field felt in the leaf, to ``interpolate`` to any point in it), or None without a far
        field (fewer than 3 levels)."""
        if not self.has_far_field:
            return None
        levels = self.tree.levels
        strengths = np.zeros((self.n_qp + self.n_poles, STRENGTHS))
        strengths[: self.n_qp, :9] = qp_strengths
        if pole_forces is not None:
            strengths[self.n_qp :, 9:] = pole_forces
        n = 2**levels
        pl, pz = self.points[levels]
        leaf = np.zeros((n * n, pl * pl, pz * STRENGTHS))
        seg = self.sources
        w = strengths[seg["order"]]
        for box, a, b in zip(seg["boxes"], seg["starts"], seg["stops"]):  # anterpolation (P2M)
            vertical = (seg["vertical"][a:b, :, None] * w[a:b, None, :]).reshape(b - a, pz * STRENGTHS)
            leaf[box] = seg["lateral"][a:b].T @ vertical
        multipoles = {levels: leaf.reshape(n, n, pl, pl, pz, STRENGTHS)}
        for level in range(levels - 1, 1, -1):  # children to parents (M2M)
            multipoles[level] = self._to_parent(multipoles[level + 1], self.transfer["sources"][level])
        local = None
        for level in range(2, levels + 1):
            received = self._interactions_at(level, multipoles.pop(level))
            if local is not None:  # parents to children (L2L)
                received += self._to_children(local, self.transfer["targets"][level - 1])
            local = received
        return local.reshape(n * n, pl * pl, pz * 3)

    def interpolate(self, values: np.ndarray | None, segments: dict) -> np.ndarray:
        """(T, 3) the far field of ``local_values`` at the targets of ``segments`` (L2P), in
        their given order (zero without a far field)."""
        n_targets = len(segments["order"])
        if values is None:
            return np.zeros((n_targets, 3))
        pz = self.points[self.tree.levels][1]
        sorted_out = np.zeros((n_targets, 3))
        for box, a, b in zip(segments["boxes"], segments["starts"], segments["stops"]):
            u = (segments["lateral"][a:b] @ values[box]).reshape(b - a, pz, 3)
            sorted_out[a:b] = np.einsum("tc,tcj->tj", segments["vertical"][a:b], u)
        out = np.zeros((n_targets, 3))
        out[segments["order"]] = sorted_out
        return out

    def _interactions_at(self, level: int, multipoles: np.ndarray) -> np.ndarray:
        """Velocities at the points of every box of ``level`` from the boxes of its interaction
        list (M2L): per offset R c, the factors of class c with their points permuted and their
        components rotated (``_proxy_permutations``), two thin BLAS products."""
        m = 2**level
        pl, pz = self.points[level]
        size = pl * pl * pz
        flat = multipoles.reshape(m, m, size * STRENGTHS).astype(self.dtype, copy=False)
        local = np.zeros((m, m, size * 3), dtype=self.dtype)
        source_grid, target_grid = self.occupied[level]
        ii, jj = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
        for offset, (canonical, k) in self.offsets.items():
            si, sj = ii + offset[0], jj + offset[1]
            ok = (si >= 0) & (si < m) & (sj >= 0) & (sj < m) & target_grid
            ok &= (np.abs(si // 2 - ii // 2) <= 1) & (np.abs(sj // 2 - jj // 2) <= 1)
            ok[ok] &= source_grid[si[ok], sj[ok]]
            if not ok.any():
                continue
            right, left = self.interactions[level][canonical]
            pi = self.permutations[level][k]
            r, h = self.symmetries[k]
            rank = right.shape[1]
            # K_{Rc}[pi(t), pi(j)] = R K_c[t, j] H^T: rotate the factors' components, permute their points
            right_o = np.empty((size, STRENGTHS, rank), dtype=self.dtype)
            right_o[pi] = np.einsum("ab,jbr->jar", h, right.reshape(size, STRENGTHS, rank))
            left_o = np.empty((size, 3, rank), dtype=self.dtype)
            left_o[pi] = np.einsum("ab,tbr->tar", r, left.reshape(size, 3, rank))
            local[ok] += (flat[si[ok], sj[ok]] @ right_o.reshape(-1, rank)) @ left_o.reshape(-1, rank).T
        return local.reshape(m, m, pl, pl, pz, 3).astype(np.float64)

    @staticmethod
    def _to_parent(children: np.ndarray, transfer) -> np.ndarray:
        """Parents' strengths from their children's: sum over the children of the transposed
        interpolation in x, y (child position c) and z."""
        lateral, vertical = transfer
        n2 = children.shape[0]
        c = children.reshape(n2 // 2, 2, n2 // 2, 2, *children.shape[2:])
        out = 0.0
        for cx in (0, 1):
            for cy in (0, 1):
                out = out + np.einsum("aA,bB,cC,ijabcr->ijABCr", lateral[cx], lateral[cy], vertical,
                                      c[:, cx, :, cy], optimize=True)
        return out

    @staticmethod
    def _to_children(parents: np.ndarray, transfer) -> np.ndarray:
        """Children's velocities at their points interpolated from their parents'."""
        lateral, vertical = transfer
        n = parents.shape[0]
        a, c = lateral.shape[1], vertical.shape[0]
        out = np.zeros((n, 2, n, 2, a, a, c, parents.shape[-1]))
        for cx in (0, 1):
            for cy in (0, 1):
                out[:, cx, :, cy] = np.einsum("aA,bB,cC,ijABCr->ijabcr", lateral[cx], lateral[cy], vertical,
                                              parents, optimize=True)
        return out.reshape(2 * n, 2 * n, a, a, c, parents.shape[-1])
