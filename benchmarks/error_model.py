"""The measured error model behind the accuracy target (issue 27 item 1,
``warpbem/hydro/accuracy.py``): a sphere's mobility error and solve time against its gap to
the wall, for every setting the target chooses among (mesh subdivisions k, density order p,
contact refinement ratio).

Per setting and gap, the solve's error against the exact series of
``tests/verification/sphere_wall_series.py``, all quantities from one system
(``MobilitySolver.solve_loads``), and the time of one solve from scratch (new bodies from an
existing mesh, the set-up included; median of 3 after a warm-up; one timing above 1 s):

* wall: a sphere at gap h/a - 1 above the wall; the largest relative error of five quantities:
  the free sphere in shear, U and Omega (Goldman, Cox & Brenner 1967b); the parallel
  mobilities mu_xx^tt and mu_yy^rr (the inverse of O'Neill's 1964 and Dean & O'Neill's 1963
  resistance matrix); the normal mobility 1 / (6 pi lambda) (Brenner 1961);
* shear: the same solves' U and Omega alone (the larger error), the error of a free body's motion
  in the flow when no load is given (the solve measured for the time is that one);
* fixed: a sphere held at gap h/a - 1 above the wall in shear; the larger relative error of
  the force and the torque that hold it (Goldman, Cox & Brenner 1967b: the fixed sphere's f*
  and t*), the error of a fixed body's holding load (an adherent cell's) where "wall" is a free
  body's motion;
* pair: two spheres at a surface gap (in radii) in unbounded fluid, pushed along their line of
  centres together (Stimson & Jeffery 1926) and towards each other (Maude 1961, Brenner 1961);
  the larger relative error of their two velocities.

The gaps lie between those the target is checked at (h/a 1.02 ... 3 at the wall, gaps 0.04 ...
4 between two spheres), so that the check (tests/verification/test_accuracy_target.py) tests
the model's interpolation, not its own data points.

    python benchmarks/error_model.py            # results/bench/error_model.csv
    python benchmarks/error_model.py --write    # and warpbem/hydro/error_model_table.json
    python benchmarks/error_model.py --write --fill-missing   # only the cells the table lacks
"""

import argparse
import json
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import warpbem as wb
from common import print_table, write_csv
from warpbem.app.progress import Progress

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "verification"))
import sphere_wall_series as series  # noqa: E402

WALL_GAPS = (0.015, 0.03, 0.07, 0.15, 0.3, 0.7, 1.5, 3.0)  # h/a - 1
PAIR_GAPS = (0.03, 0.06, 0.14, 0.3, 0.6, 1.4, 3.0, 6.0)  # surface gap / a
SUBDIVISIONS = (2, 3, 4, 6)
# refinement ratios by density order: the bilinear density's unknowns grow 4 times faster under
# refinement, and its ratio 3 takes 37 000 unknowns (131 s) at h/a = 1.015 on the k = 2 sphere; the
# biquadratic one's 2.25 times faster again, and it resolves the gap with fewer splits (two k = 4
# spheres 0.05 radius apart pushed together, measured_pair: 1.7e-3 off the exact at ratio 0.35
# with 6 480 unknowns, against 4.5e-3 for the bilinear density at its default 1.1 with 9 792)
RATIOS = {1: (0.0, 0.3, 1.1, 3.0), 2: (0.0, 0.3, 0.6, 1.1), 3: (0.0, 0.2, 0.35, 0.5)}
PARTS = ("wall", "fixed", "pair")  # measured; "shear" comes with "wall"
TABLE_PARTS = {"wall": ("wall", "shear"), "fixed": ("fixed",), "pair": ("pair",)}
SHEAR_QUANTITIES = ("U", "Omega")
# settings larger than this at a gap are left out: a dense system of N unknowns takes 8 N^2 bytes, and
# the largest measured, 20 736 (k = 6, p = 2, ratio 1.1 at h/a = 1.015), 7 GB and 16-18 s a solve
MAX_UNKNOWNS = 21000
TABLE = ROOT / "warpbem" / "hydro" / "error_model_table.json"
TABLE_NAMES = ("wall", "shear", "fixed", "pair")  # the tables of the data file, in its order
ABOUT = ("The error model of the accuracy target (warpbem/hydro/accuracy.py), measured by benchmarks/error_model.py on"
         " the 2-core CPU, float64; do not edit: run it with --write. The fields: warpbem/hydro/error_model_table.py")
CELL = ("relative error", "unknowns", "milliseconds of one solve from scratch")  # a measured cell's fields


def exact_mobility(h: float) -> dict:
    """The five quantities at h/a = h for a = 1, mu = 1, gdot = 1 (module docstring)."""
    r, pi = series.parallel_resistance(h), np.pi
    mobility = np.linalg.inv([[6 * pi * r["Ft"], -6 * pi * r["Fr"]], [-8 * pi * r["Tt"], 8 * pi * r["Tr"]]])
    free = series.free_sphere_in_shear(h)
    return {"U": free["U_over_gdot_h"] * h, "Omega": free["Omega_over_gdot"], "mu_xx": mobility[0, 0],
            "mu_rr": mobility[1, 1], "mu_zz": 1.0 / (6 * pi * series.brenner_lambda(h))}


def exact_pair(gap: float) -> dict:
    """The two velocities for a unit force on each sphere (a = 1, mu = 1)."""
    return {"together": 1.0 / (6 * np.pi * series.stimson_jeffery_lambda(1.0 + gap / 2)),
            "approaching": 1.0 / (6 * np.pi * series.approaching_spheres_lambda(1.0 + gap / 2))}


def exact_fixed(h: float) -> dict:
    """The fluid's force and torque on a sphere held at h/a = h in shear (a = 1, mu = 1, gdot = 1)."""
    loads = series.fixed_sphere_in_shear(h)
    return {"F": 6 * np.pi * h * loads["f_star"], "T": 4 * np.pi * loads["t_star"]}


def measured_fixed(mesh, gap: float, options) -> tuple[dict, object]:
    """The fluid's force and torque on the held sphere: minus the load that holds it."""
    solution = wb.solve_mobility(part_bodies("fixed", mesh, gap), shear_rate=1.0, viscosity=1.0, options=options)
    return {"F": -solution.force[0, 0], "T": -solution.torque[0, 1]}, solution


def pair_bodies(mesh, gap: float) -> list:
    return [wb.Body(mesh, position=(-1.0 - gap / 2, 0, 0)), wb.Body(mesh, position=(1.0 + gap / 2, 0, 0))]


def part_bodies(part: str, mesh, gap: float) -> list:
    """The bodies of a part's scene: a sphere free or held at h/a = 1 + gap, or two spheres."""
    if part == "pair":
        return pair_bodies(mesh, gap)
    return [wb.Body(mesh, position=(0, 0, 1.0 + gap), fixed=part == "fixed")]


def measured_pair(mesh, gap: float, options) -> tuple[dict, object]:
    """The two velocities from one system (and the first solution)."""
    solver = wb.MobilitySolver(0.0, 1.0, wall=False, options=options, keep_systems=False)
    zero = [[0.0, 0.0, 0.0]] * 2
    pushes = [[[1, 0, 0], [1, 0, 0]], [[1, 0, 0], [-1, 0, 0]]]
    together, approaching = solver.solve_loads(pair_bodies(mesh, gap), pushes, [zero, zero])
    return {"together": together.velocity[0, 0], "approaching": approaching.velocity[0, 0]}, together


def measured_mobility(mesh, h: float, options) -> tuple[dict, object]:
    """The five quantities from one system of the solver (and the first solution)."""
    solver = wb.MobilitySolver(1.0, 1.0, options=options, keep_systems=False)
    zero = [[0.0, 0.0, 0.0]]
    background, fx, fz, ty = solver.solve_loads([wb.Body(mesh, position=(0, 0, h))], [[[1, 0, 0]], [[0, 0, 1]], zero],
                                                [zero, zero, [[0, 1, 0]]], with_background=True)
    return ({"U": background.velocity[0, 0], "Omega": background.angular_velocity[0, 1], "mu_xx": fx.velocity[0, 0],
             "mu_rr": ty.angular_velocity[0, 1], "mu_zz": fz.velocity[0, 2]}, background)


def solve_time(part: str, mesh, gap: float, options) -> float:
    """Seconds of one solve from scratch (module docstring's protocol) of a ``part``'s scene."""
    def solve():
        t = time.perf_counter()
        if part == "pair":
            wb.solve_mobility(pair_bodies(mesh, gap), viscosity=1.0, wall=False, forces=[[1, 0, 0], [-1, 0, 0]],
                              options=options)
        else:
            wb.solve_mobility(part_bodies(part, mesh, gap), shear_rate=1.0, viscosity=1.0, options=options)
        return time.perf_counter() - t

    first = solve()  # compiles and warms up
    return first if first > 1.0 else statistics.median(solve() for _ in range(3))


def settings() -> list[tuple[int, int, float]]:
    return [(k, p, ratio) for k in SUBDIVISIONS for p in RATIOS for ratio in RATIOS[p]]


def unknowns_of(part: str, mesh, gap: float, options) -> int:
    """The solve's unknowns without solving (the refined geometry alone)."""
    from warpbem.hydro.geometry import SurfaceGeometry

    resolved = options.resolved()
    geometry = SurfaceGeometry.from_bodies(part_bodies(part, mesh, gap), resolved.quadrature_order, 1.0,
                                           part != "pair", resolved.contact_refinement, True, resolved.density_order)
    return 3 * len(geometry.collocation)


def part_errors(part: str, mesh, gap: float, options) -> tuple[dict, object]:
    """({quantity: its relative error against the exact series}, the first solution) of a
    measured part's scene at ``gap`` (module docstring)."""
    if part == "wall":
        exact, (values, first) = exact_mobility(1.0 + gap), measured_mobility(mesh, 1.0 + gap, options)
    elif part == "fixed":
        exact, (values, first) = exact_fixed(1.0 + gap), measured_fixed(mesh, gap, options)
    else:
        exact, (values, first) = exact_pair(gap), measured_pair(mesh, gap, options)
    return {q: abs(values[q] / exact[q] - 1) for q in values}, first


def table_errors(part: str, errors: dict) -> dict:
    """{table part: the quantities of ``errors`` it bounds} for a measured ``part``."""
    return {name: SHEAR_QUANTITIES if name == "shear" else tuple(errors) for name in TABLE_PARTS[part]}


def missing(part: str, setting: tuple, gap: float) -> bool:
    """Whether the table holds no cell of a measured ``part`` (its first table) at ``setting`` and
    ``gap`` (or not the setting at all: a setting added to ``settings``)."""
    from warpbem.hydro import error_model_table as table

    gaps = table.PAIR_GAPS if part == "pair" else table.WALL_GAPS
    cells = getattr(table, TABLE_PARTS[part][0].upper()).get(setting)
    return cells is None or cells[gaps.index(gap)] is None


def kept_rows(parts) -> list[dict]:
    """The rows of ``parts`` as the table now holds them (a --write that measures other parts)."""
    from warpbem.hydro import error_model_table as table

    rows = []
    for part in (name for measured in parts for name in TABLE_PARTS[measured]):
        gaps = table.PAIR_GAPS if part == "pair" else table.WALL_GAPS
        for (k, p, ratio), cells in getattr(table, part.upper()).items():
            rows += [{"part": part, "k": k, "p": p, "ratio": ratio, "gap": g, "error": c[0], "unknowns": c[1],
                      "ms": c[2]} for g, c in zip(gaps, cells) if c is not None]
    return rows


def write_table(rows: list[dict], path: Path = TABLE) -> None:
    """The rows as the data file the accuracy target reads (``table_text``), each cell's error
    and time to 3 digits."""
    tables = {}
    for part in TABLE_NAMES:
        gaps, table = PAIR_GAPS if part == "pair" else WALL_GAPS, {}
        for setting in settings():
            by_gap = {r["gap"]: r for r in rows if r["part"] == part and (r["k"], r["p"], r["ratio"]) == setting}
            table[setting] = tuple(None if g not in by_gap else (float(f"{by_gap[g]['error']:.3g}"),
                                                                by_gap[g]["unknowns"], float(f"{by_gap[g]['ms']:.3g}"))
                                   for g in gaps)
        tables[part.upper()] = table
    path.write_text(table_text(tables))


def table_text(tables: dict) -> str:
    """The data file (JSON) of ``tables`` ({"WALL", "SHEAR", "FIXED", "PAIR": {(k, p, ratio): a cell
    per gap}}), loaded by ``warpbem/hydro/error_model_table.py`` (its docstring: the fields): one
    cell a line, so that a new measurement shows in a diff cell by cell; numbers in Python's
    shortest repr, read back to the same float."""
    def setting_text(setting: tuple, cells: tuple) -> str:
        k, p, ratio = setting
        return (f'    {{"k": {k}, "p": {p}, "ratio": {json.dumps(ratio)}, "cells": [\n'
                + ",\n".join(f"      {json.dumps(c)}" for c in cells) + "\n    ]}")

    fields = [f'"about": {json.dumps(ABOUT)}', f'"cell": {json.dumps(CELL)}',
              f'"SUBDIVISIONS": {json.dumps(SUBDIVISIONS)}', f'"WALL_GAPS": {json.dumps(WALL_GAPS)}',
              f'"PAIR_GAPS": {json.dumps(PAIR_GAPS)}']
    fields += [f'"{name.upper()}": [\n' + ",\n".join(setting_text(*item) for item in tables[name.upper()].items())
               + "\n  ]" for name in TABLE_NAMES]
    return "{\n  " + ",\n  ".join(fields) + "\n}\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"write {TABLE.relative_to(ROOT)}")
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS),
                        help="the parts to measure; with --write the others are kept from the table as it is")
    parser.add_argument("--fill-missing", action="store_true",
                        help="measure only the cells the table lacks; with --write every other cell is kept as it is")
    args = parser.parse_args()
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)  # the settings without refinement, on purpose
    cases = [(part, s, g) for part in args.parts for s in settings()
             for g in (PAIR_GAPS if part == "pair" else WALL_GAPS) if not args.fill_missing or missing(part, s, g)]
    rows, progress = [], Progress(len(cases))
    for part, (k, p, ratio), gap in cases:
        mesh = wb.mesh.sphere(1.0, k)
        options = wb.SolverOptions(density_order=p, contact_refinement=ratio)
        what = f"{part}, k = {k}, p = {p}, ratio {ratio}, gap {gap}"
        if unknowns_of(part, mesh, gap, options) > MAX_UNKNOWNS:
            progress.done(f"{what}: over {MAX_UNKNOWNS} unknowns, left out")
            continue
        errors, first = part_errors(part, mesh, gap, options)
        ms = 1e3 * solve_time(part, mesh, gap, options)
        for name, quantities in table_errors(part, errors).items():
            worst = max(quantities, key=errors.get)
            rows.append({"part": name, "k": k, "p": p, "ratio": ratio, "gap": gap,
                         "unknowns": first.solution_vector.size, "error": errors[worst], "worst": worst, "ms": ms})
        progress.done(f"{what}: {max(errors.values()):.1e} ({max(errors, key=errors.get)}), {ms:.1f} ms")
    if rows:  # none where --fill-missing finds every missing cell over the limit
        print_table(rows, {"error": "{:.2e}", "ms": "{:.1f}"})
        print(f"table: {write_csv('error_model.csv', rows)}")
    if args.write:
        write_table(rows + kept_rows(PARTS if args.fill_missing else [p for p in PARTS if p not in args.parts]))
        print(f"model: {TABLE}")


if __name__ == "__main__":
    main()
