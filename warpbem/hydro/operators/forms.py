"""An operator's discrete form by name (``discrete_form``), and the one rule that picks it for
"auto" (``choose_mode``): dense while the matrix takes at most DENSE_MEMORY_SHARE of the device's
total memory, else the treecode (the double layer) or the direct sum (the other kinds). A solver
decides it once, when it is built (``MobilitySolver``), and reports it.

It sits above the forms (``dense.py``, ``direct_sum.py``, ``treecode_form.py``) and the
description (``description.py``): none of them imports it, and the description imports no form."""

from __future__ import annotations

from ... import runtime
from ..options import OPERATOR_MODES
from .dense import DenseOperator
from .description import BoundaryOperator
from .direct_sum import DirectSumOperator
from .discrete import DiscreteOperator
from .treecode_form import TreecodeOperator

MODES = tuple(m for m in OPERATOR_MODES if m != "auto")  # the discrete forms; "auto": choose_mode
DENSE_MEMORY_SHARE = 0.25  # dense while one matrix takes at most this share of the memory


def choose_mode(size: int, dtype: str = "float64", device="cpu", kind: str = "double_layer") -> str:
    """The one rule for "auto" (module docstring), for an operator of ``size`` unknowns: "dense"
    while the matrix takes at most DENSE_MEMORY_SHARE of the device's total memory (room for the
    solver's factored blocks, and for a second matrix in the steps whose kept blocks cannot move
    in place, ``kept_blocks.py``), else "treecode" for the double layer, "matrix_free" for the
    other kinds. From the total, not the free memory: the free memory falls with the run's own
    kept systems, and a run that chose by it switched to matrix-free part-way."""
    itemsize = 8 if dtype == "float64" else 4
    if size**2 * itemsize <= DENSE_MEMORY_SHARE * runtime.total_memory(runtime.resolve_device(device)):
        return "dense"
    return "treecode" if kind == "double_layer" else "matrix_free"


def discrete_form(operator: BoundaryOperator, mode: str = "auto", device="cpu", *, kept=None, treecode=None,
                  point_sources=None) -> DiscreteOperator:
    """``operator`` applied as ``mode`` ("dense", "matrix_free": the direct sum, "treecode", or
    "auto": ``choose_mode``) on ``device``. ``kept``: the ``KeptBlocks`` store a dense form takes
    unmoved bodies' blocks from and leaves its own in; ``treecode``: the ``TreecodeOptions``;
    ``point_sources``: (P, 3) poles whose point forces the forms sum with the layer (the CDL's
    completions)."""
    if mode == "auto":
        mode = choose_mode(operator.size, operator.dtype, device, operator.kind)
    if mode not in MODES:
        raise ValueError(f"operator mode must be one of {OPERATOR_MODES}, got {mode!r}")
    if mode == "treecode":
        return TreecodeOperator(operator, device, point_sources, treecode)
    if mode == "dense":
        return DenseOperator(operator, device, point_sources, kept)
    return DirectSumOperator(operator, device, point_sources)
