"""The accuracy target's error model as shipped (``warpbem/hydro/error_model_table.json``, read by
``error_model_table.py``): complete and well formed where ``accuracy.py`` relies on it, and in
the form benchmarks/error_model.py --write gives it (a number edited by hand beyond the
benchmark's 3 digits, a changed layout, a setting the benchmark lists but the file lacks show
here)."""

import math
import sys
from pathlib import Path

import warpbem as wb
from warpbem.hydro import error_model_table as table

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import error_model  # noqa: E402

TABLES = {"WALL": table.WALL_GAPS, "SHEAR": table.WALL_GAPS, "FIXED": table.WALL_GAPS, "PAIR": table.PAIR_GAPS}


def test_every_table_holds_every_setting_and_gap_with_sound_cells():
    """accuracy._Model reads each table as a (settings x gaps) array: the same settings in every
    table, each (k, p) with its unrefined sibling (ratio 0, read below the refinement threshold),
    a cell per gap, gaps increasing (log-log interpolation); cells with a positive finite error
    and time (their logs are taken) and a whole number of 3-vector unknowns; not measured only at
    the smallest gaps (the benchmark leaves out a setting over its unknowns limit, which the
    contact refinement reaches nearest contact), the unknowns falling as the gap grows."""
    settings = list(table.WALL)
    assert all(list(getattr(table, name)) == settings for name in TABLES)
    assert {(k, p, 0.0) for k, p, _ in settings} <= set(settings)
    assert {k for k, _, _ in settings} == set(table.SUBDIVISIONS)
    for gaps in (table.WALL_GAPS, table.PAIR_GAPS):
        assert gaps[0] > 0 and all(a < b for a, b in zip(gaps, gaps[1:]))
    for name, gaps in TABLES.items():
        for setting, cells in getattr(table, name).items():
            assert len(cells) == len(gaps), (name, setting)
            measured = [c for c in cells if c is not None]
            assert measured and cells[-len(measured):] == tuple(measured), (name, setting)
            for error, unknowns, ms in measured:
                assert 0 < error < math.inf and 0 < ms < math.inf, (name, setting)
                assert isinstance(unknowns, int) and unknowns > 0 and unknowns % 3 == 0, (name, setting)
            unknowns = [c[1] for c in measured]
            assert all(a >= b for a, b in zip(unknowns, unknowns[1:])), (name, setting)


def test_an_unrefined_setting_solves_the_library_sphere_at_every_gap():
    """A cell belongs to its setting: without contact refinement the solve's unknowns are those
    of the k sphere's elements (``wb.mesh.sphere``) with p x p collocation points each and three
    unknowns a point, one sphere at the wall, two in the pair, at every gap."""
    for k in table.SUBDIVISIONS:
        elements = len(wb.mesh.sphere(1.0, k).elements)
        for p in (1, 2):
            for name, spheres in (("WALL", 1), ("SHEAR", 1), ("FIXED", 1), ("PAIR", 2)):
                cells = getattr(table, name)[(k, p, 0.0)]
                assert {c[1] for c in cells if c} == {3 * p * p * elements * spheres}, (name, k, p)


def test_the_benchmark_writes_the_shipped_file_back_unchanged(tmp_path):
    """error_model.py --write --parts keeps the parts it does not measure as the table holds
    them (``kept_rows``): kept whole, they must give the shipped file byte for byte (the same
    settings, the same 3-digit numbers, the same layout)."""
    written = tmp_path / "error_model_table.json"
    error_model.write_table(error_model.kept_rows(error_model.PARTS), written)
    shipped = Path(table.__file__).with_name(table.DATA_FILE)
    assert written.read_text() == shipped.read_text()
