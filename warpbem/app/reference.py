"""The scene-file reference (``docs/scene-reference.md``), generated from the options'
declarations (``warpbem/options.py``), so that it cannot drift from what the parser accepts;
``tests/unit/test_reference.py`` checks that the checked-in file is current.

    python -m warpbem.app.reference > docs/scene-reference.md
"""

from __future__ import annotations

from ..dynamics.model import StepPolicy
from ..elastic.deformable import DeformationOptions
from ..forces.bond_model import BondOptions
from ..forces.repulsion import Repulsion
from ..hydro.options import Flow, SolverOptions
from ..options import reference_rows
from .scene import ArrayOptions, BodySpec, MeshOptions, Physics, RunSettings

# (scene table, declared classes, what the table is)
TABLES = (
    ("flow", (Flow,), "The undisturbed shear flow above the wall (`shear_rate` is required)."),
    ("physics", (Physics,), "What the scene switches on; nothing else is modelled."),
    ("time", (RunSettings, StepPolicy), "The run's length, its frames and the adaptive step (`end` is required)."),
    ("solver", (SolverOptions,), "The boundary-element solves and their reuse across time steps."),
    ("repulsion", (Repulsion,), "Electrostatic repulsion, thesis eq. 3.1 (on with `physics.repulsion`)."),
    ("adhesion", (BondOptions,), "Receptor-ligand bonds, thesis ch. 4 and Table 4.1 (on with `physics.adhesion`)."),
    ("deformation", (DeformationOptions,), "Deformable cells (bodies with `deformable = true`)."),
    ("bodies", (BodySpec,), "One `[[bodies]]` entry per body, each with a `[bodies.mesh]` table."),
    ("bodies.mesh", (MeshOptions,), "A body's mesh (`shape` is required)."),
    ("arrays", (ArrayOptions,), "A grid of alike bodies (any `[[bodies]]` key but `position`, and a mesh)."),
)


def scene_reference() -> str:
    """The Markdown reference of every declared scene key: unit, default, allowed values, meaning."""
    lines = ["# Scene-file reference", "",
             "Generated from the options' declarations by `python -m warpbem.app.reference`; do not edit by hand.",
             "Units are SI. A default of `-` is resolved from the context, as the meaning says.",
             "A value outside its plausible magnitudes was most likely typed in another unit (6 for 6 um) and is",
             "refused, unless the scene says `any_scale = true` before its first table.", ""]
    for section, classes, what in TABLES:
        rows = [row for cls in classes for row in reference_rows(cls, section)]
        lines += [f"## [{section}]", "", what, "", "| key | unit | default | allowed | meaning |",
                  "|---|---|---|---|---|", *rows, ""]
    return "\n".join(lines)


if __name__ == "__main__":
    print(scene_reference(), end="")
