"""What a boundary-integral operator is, apart from how it is applied (bempp-cl's split of a
boundary operator from its discrete forms; DESIGN.md §2): ``BoundaryOperator`` names the kernel
``kind``, the surfaces (a ``SurfaceGeometry``), the wall, the quadrature and the precision;
``forms.discrete_form`` gives one of its forms (``dense.py``, ``direct_sum.py``,
``treecode_form.py``), chosen by one rule, ``forms.choose_mode``. The forms import this module,
never the reverse.

The kinds (``kernels/assembly.py``) and their self blocks:

* "double_layer", (1/2 + D) q of the Completed Double Layer method (``mobility.py``). For a
  density constant on each element, collocated at the element centres xi_a,

      ((1/2 + D) q)_a = sum_{b in body(a)} I_ab (q_b - q_a) + sum_{b not in body(a)} I_ab q_b,

  I_ab = int_{E_b} Sigma(x, xi_a) . n(x) dS(x) (``kernels/greens.py``). With a density of order
  p > 1 (Lagrange on p x p points per element, ``geometry.py``) I_ab is one block per basis
  function, int_{E_b} Sigma . n L_l dS, and the same identity gives the self block (the basis
  functions sum to one). The first sum is the constant-density identity int_S Sigma . n dS =
  -1/2 on a closed surface (thesis ch. 3.3; Phan-Thien & Fan 1996), which holds for the wall
  kernel too because the image part is regular inside the body; it replaces the singular
  self-element integral and makes the discrete operator annihilate rigid translations exactly.
* "adjoint_double_layer", 1/2 + D* of the traction problem (``traction.py``): I*_ab =
  int_{E_b} of the traction at xi_a of a point force at x, its singular self element taken as
  the double layer's, I*_aa = I_aa = -1/2 - sum_{b != a in body(a)} I_ab (Phan-Thien & Fan
  1996; thesis ch. 3.3): on a sphere in free space the two integrands agree pointwise (r.n(x) =
  -r.n(xi) = r^2 / 2a), elsewhere they differ by the curvature change over one element.
* "single_layer" (the Stokeslet) and "inverse_distance" (with it, the Kelvinlet): no 1/2; their
  weakly singular self element is integrated by Duffy triangles.
* "elastic_rotation", "elastic_dyadic": the two parts of the elastic double layer
  (``elastic/interior.py``), their self blocks from their own rigid-translation identity, as the
  double layer's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...kernels.kinds import KINDS
from ..geometry import SurfaceGeometry

SINGLE_LAYERS = ("single_layer", "inverse_distance")
# kinds whose self block follows from the rigid-translation identity of their own row sums
IDENTITY_KINDS = ("double_layer", "elastic_rotation", "elastic_dyadic")


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


@dataclass(frozen=True, eq=False)
class BoundaryOperator:
    """The operator of one kernel ``kind`` (module docstring) over the elements of ``geometry``
    (scaled units), with the wall's images if ``wall``, integrated with ``quadrature`` in
    ``dtype``; its discrete forms (``forms.discrete_form``) apply it."""

    geometry: SurfaceGeometry
    wall: bool
    quadrature: QuadratureOptions = QuadratureOptions()
    kind: str = "double_layer"
    dtype: str = "float64"

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"operator kind must be one of {KINDS}, got {self.kind!r}")
        if self.dtype not in ("float64", "float32"):
            raise ValueError(f"dtype must be float64 or float32, got {self.dtype!r}")
        object.__setattr__(self, "wall", bool(self.wall))

    @property
    def size(self) -> int:
        """Unknowns: three per collocation point."""
        return 3 * self.geometry.n_points

    def signature(self, device) -> tuple:
        """What makes two operators' element integrals the same function of their elements: a
        kept block (``KeptBlocks``) serves only an operator of the same signature."""
        return (self.kind, self.wall, self.dtype, self.geometry.density_order, self.quadrature, str(device))
