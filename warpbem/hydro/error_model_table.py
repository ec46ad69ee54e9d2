"""The error model of the accuracy target (``accuracy.py``), read from the data file
``error_model_table.json`` beside this module, which benchmarks/error_model.py measured on the
2-core CPU in float64 and wrote (do not edit it: run that benchmark with --write).

SUBDIVISIONS: the library meshes' k measured; WALL_GAPS: h/a - 1 of a sphere above the wall;
PAIR_GAPS: the surface gap / a of two spheres; WALL (a free sphere), SHEAR (its motion in shear
alone), FIXED (a held one), PAIR: (k, p, refinement ratio) -> per gap (relative error, unknowns,
milliseconds of one solve from scratch), None where not measured (over the benchmark's unknowns
limit).
"""

import json
from importlib import resources

DATA_FILE = "error_model_table.json"


def _table(settings: list) -> dict:
    """{(k, p, ratio): a cell per gap} of the data file's list of settings."""
    return {(s["k"], s["p"], s["ratio"]): tuple(None if c is None else tuple(c) for c in s["cells"])
            for s in settings}


_data = json.loads(resources.files(__package__).joinpath(DATA_FILE).read_text())
SUBDIVISIONS = tuple(_data["SUBDIVISIONS"])
WALL_GAPS = tuple(_data["WALL_GAPS"])
PAIR_GAPS = tuple(_data["PAIR_GAPS"])
WALL = _table(_data["WALL"])
SHEAR = _table(_data["SHEAR"])
FIXED = _table(_data["FIXED"])
PAIR = _table(_data["PAIR"])
