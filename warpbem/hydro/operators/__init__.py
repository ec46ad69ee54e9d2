"""Boundary-integral operators: a description (``BoundaryOperator``: kernel kind, surfaces, wall,
quadrature, precision) apart from its discrete forms (dense, direct sum, treecode; each a SciPy
``LinearOperator`` with ``to_dense``), the form of a description by name and the one rule that
picks it (``discrete_form``, ``choose_mode``) and the store of kept blocks of unmoved bodies
(``KeptBlocks``). DESIGN.md §2. Each module imports only modules before it in this order:
description, kept_blocks, discrete (what every form shares), dense, direct_sum and
treecode_form, forms."""

from .dense import DenseOperator
from .description import IDENTITY_KINDS, KINDS, SINGLE_LAYERS, BoundaryOperator, QuadratureOptions, dof_indices
from .direct_sum import DirectSumOperator
from .discrete import DiscreteOperator
from .forms import choose_mode, discrete_form
from .kept_blocks import KeptBlocks
from .treecode_form import TreecodeOperator, quadrature_strengths

__all__ = ["BoundaryOperator", "QuadratureOptions", "choose_mode", "discrete_form", "dof_indices", "KINDS",
           "SINGLE_LAYERS", "IDENTITY_KINDS", "DiscreteOperator", "DenseOperator", "DirectSumOperator",
           "TreecodeOperator", "KeptBlocks", "quadrature_strengths"]
