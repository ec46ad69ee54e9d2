"""The accuracy target checked (issue 27 item 1): ``SolverOptions(accuracy=...)`` at heights h/a =
1.02 ... 3 above the wall (a free sphere, "wall"; its motion in shear alone, as a solve given no
load reads it, "shear"; a held one, "fixed") and at gaps 0.04 ... 4 radii
between two spheres (the error model's data lie between these: benchmarks/error_model.py),
against the exact series.

First the measured front: every setting of the error model solved at each case, its true error
(the quantities of error_model.py) and its time (one solve from scratch, median of 3 after a
warm-up). Then per target accuracy and case: the setting the target chooses for the case's
bodies on the k = 4 library sphere (as MobilitySolver chooses it; its solve is the front's
solve of that setting), its error estimate, its true error, estimate / true, and its time
against the cheapest setting of the front that reaches the accuracy. Targets: the true error
within the accuracy wherever the target does not warn that it cannot reach it (issue 45); the
estimate within a factor 3 of the true error; the chosen setting costs at most 2 times the
cheapest (issue 27). ``--calibrate`` derives the safety margins of ``accuracy.MARGINS`` from
the check (``calibrate``); ``--validate`` solves the chosen settings alone at gaps between the
check's (VALIDATION), cases the margins were not fitted to.

    python benchmarks/accuracy_target.py [--accuracies 1e-2 1e-3 1e-4] [--parts wall fixed pair]
    python benchmarks/accuracy_target.py --front results/bench/accuracy_front.csv   # choices only
    python benchmarks/accuracy_target.py --front docs/figures/accuracy_front.csv --calibrate
    python benchmarks/accuracy_target.py --front docs/figures/accuracy_front.csv --add-density 3 --calibrate
    python benchmarks/accuracy_target.py --validate [--accuracies 1e-2 1e-3]

Writes results/bench/accuracy_target.csv, accuracy_front.csv and accuracy_target.png (estimate
against true error; true error against the accuracy; cost against the cheapest), with
--validate accuracy_validation.csv.
"""

import argparse
import csv
import itertools
import warnings

import numpy as np

import warpbem as wb
from common import output, print_table, pyplot, write_csv
from error_model import (part_bodies, part_errors, settings, solve_time, table_errors, unknowns_of, MAX_UNKNOWNS,
                         TABLE_PARTS)
from warpbem.app.progress import Progress
from warpbem.hydro import accuracy

CASES = {"wall": (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0),  # h/a - 1, a free sphere (and "shear")
         "fixed": (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0),  # h/a - 1, a held sphere
         "pair": (0.04, 0.1, 0.2, 0.4, 1.0, 2.0, 4.0)}  # surface gap / a
# gaps other than the check's and the error model's (benchmarks/error_model.py)
VALIDATION = {"wall": (0.04, 0.08, 0.13, 0.25, 0.4, 0.85, 1.3),
              "fixed": (0.04, 0.08, 0.13, 0.25, 0.4, 0.85, 1.3),
              "pair": (0.07, 0.15, 0.25, 0.5, 0.8, 1.7, 3.5)}
LIBRARY_MESH = wb.mesh.sphere(1.0, 4)  # what a user builds; the target rebuilds it at its k


def true_errors(part: str, gap: float, mesh, options) -> dict:
    """{table part: the largest relative error of its quantities} of a measured part
    (error_model.py: "wall" gives "wall" and "shear")."""
    errors, _ = part_errors(part, mesh, gap, options)
    return {name: max(errors[q] for q in quantities) for name, quantities in table_errors(part, errors).items()}


def front(part: str, gap: float, density_orders=None) -> list[dict]:
    """Every setting of the error model at this case (of ``density_orders`` only, if given): true
    error (of each table part it gives) and time."""
    rows = []
    for k, p, ratio in settings():
        if density_orders is not None and p not in density_orders:
            continue
        mesh, options = wb.mesh.sphere(1.0, k), wb.SolverOptions(density_order=p, contact_refinement=ratio)
        if unknowns_of(part, mesh, gap, options) > MAX_UNKNOWNS:
            continue
        errors, ms = true_errors(part, gap, mesh, options), 1e3 * solve_time(part, mesh, gap, options)
        rows += [{"part": name, "gap": gap, "k": k, "p": p, "ratio": ratio, "error": error, "ms": ms}
                 for name, error in errors.items()]
    return rows


def measured_front(cases, density_orders=None) -> list[dict]:
    """``front`` at every case (of ``density_orders``' settings only, if given)."""
    rows, progress = [], Progress(len(cases))
    for part, gap in cases:
        rows += front(part, gap, density_orders)
        progress.done(f"{part} gap {gap}" + ("" if density_orders is None else f", density orders {density_orders}"))
    return rows


def chosen_for(part: str, gap: float, target: float):
    """The target's choice for the case's bodies on the library mesh, as ``MobilitySolver`` makes
    it (its solve is then the front's solve of that setting: the same meshes, the same options;
    "shear": a solve given no load)."""
    bodies = part_bodies(part, LIBRARY_MESH, gap)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", wb.AccuracyWarning)
        chosen = accuracy.choose_for(bodies, part != "pair", target, unloaded=part == "shear")
    return chosen, any(issubclass(w.category, wb.AccuracyWarning) for w in caught)


def check(fronts: list[dict], checked: list[tuple], accuracies) -> list[dict]:
    """Per case of ``checked`` and accuracy: the target's choice, its estimate and bound, the true
    error and time of its solve on the measured ``fronts``, and the cheapest setting reaching it."""
    rows = []
    for (part, gap), target in itertools.product(checked, accuracies):
        measured = {(r["k"], r["p"], r["ratio"]): r for r in fronts if r["part"] == part and r["gap"] == gap}
        chosen, warned = chosen_for(part, gap, target)
        solved = measured[chosen.subdivisions, chosen.density_order, chosen.contact_refinement]
        reaching = [r for r in measured.values() if r["error"] <= target]
        cheapest = min(reaching, key=lambda r: r["ms"]) if reaching else None
        rows.append({"part": part, "gap": gap, "accuracy": target, "k": chosen.subdivisions,
                     "p": chosen.density_order, "ratio": chosen.contact_refinement, "estimate": chosen.error_estimate,
                     "bound": chosen.error_bound, "error": solved["error"],
                     "estimate/error": chosen.error_estimate / solved["error"],
                     "ms": solved["ms"], "cheapest": "-" if cheapest is None else
                     f"{cheapest['k']}/{cheapest['p']}/{cheapest['ratio']:g}",
                     "cheapest_ms": np.nan if cheapest is None else cheapest["ms"],
                     "cost/cheapest": np.nan if cheapest is None else solved["ms"] / cheapest["ms"],
                     "warned": "yes" if warned else ""})
    return rows


def validate(parts, accuracies) -> list[dict]:
    """Per case of VALIDATION and accuracy: the target's choice solved alone (its true error by
    the quantities of error_model.py), against the accuracy."""
    rows, cases = [], [(part, gap, target) for part in parts for gap in VALIDATION[part] for target in accuracies]
    progress = Progress(len(cases))
    for part, gap, target in cases:
        for name in TABLE_PARTS[part]:
            chosen, warned = chosen_for(name, gap, target)
            mesh = wb.mesh.sphere(1.0, chosen.subdivisions)
            options = wb.SolverOptions(density_order=chosen.density_order, contact_refinement=chosen.contact_refinement)
            error = true_errors(part, gap, mesh, options)[name]
            rows.append({"part": name, "gap": gap, "accuracy": target, "k": chosen.subdivisions,
                         "p": chosen.density_order, "ratio": chosen.contact_refinement,
                         "estimate": chosen.error_estimate, "bound": chosen.error_bound, "error": error,
                         "error/accuracy": error / target, "warned": "yes" if warned else ""})
        progress.done(f"{part} gap {gap}, accuracy {target:g}")
    return rows


def margin_floors(fronts: list[dict], checked: list[tuple], largest_estimate: float = 1e-2) -> dict:
    """Per table, (unrefined, refined): the 95th percentile of true error / estimate over every
    setting of the front at the table's cases whose estimate is within ``largest_estimate``,
    those whose contact refinement splits elements at the case's gap apart."""
    ratios = {}
    for name, gap in checked:
        part = "wall" if name == "shear" else name
        terms = accuracy.scene_terms(part_bodies(part, LIBRARY_MESH, gap), name != "pair", True, name == "shear")
        estimates = accuracy.scene_costs(terms)[0].max(axis=0)
        refined = np.any([t.model.refined_at(t.gap)[accuracy._mapped(t)] for t in terms], axis=0)
        true = {(r["k"], r["p"], r["ratio"]): r["error"] for r in fronts if r["part"] == name and r["gap"] == gap}
        for s, setting in enumerate(accuracy.WALL_MODEL.settings):
            if setting in true and estimates[s] <= largest_estimate:
                ratios.setdefault((name, bool(refined[s])), []).append(true[setting] / estimates[s])
    return {name: tuple(float(np.quantile(ratios[name, kind], 0.95)) for kind in (False, True))
            for name in dict.fromkeys(name for name, _ in checked)}


def calibrate(fronts: list[dict], checked: list[tuple], accuracies, largest: float = 5.0) -> dict:
    """Per table, the margins (unrefined, refined; ``accuracy.MARGINS``) on a grid of 0.1 from
    the floors of ``margin_floors`` up: the smallest unrefined margin from which every larger one
    up to ``largest``, with the refined margin at ``largest``, leaves no case of the table above
    its accuracy but those the target warns it cannot reach; then, with it, the smallest refined
    margin from which every larger one does so. The margins in use are put back."""
    grid = np.round(np.arange(1.0, largest + 1e-9, 0.1), 1)
    floors = margin_floors(fronts, checked)
    margins = {}
    for name in dict.fromkeys(part for part, _ in checked):
        model, cases = getattr(accuracy, f"{name.upper()}_MODEL"), [case for case in checked if case[0] == name]
        kept = model.margins

        def smallest_passing(candidates, margins_of):
            for margin in candidates[::-1]:  # from the largest down, while every one passes
                model.margins = margins_of(margin)
                if any(r["error"] > r["accuracy"] and not r["warned"] for r in check(fronts, cases, accuracies)):
                    return float(round(margin + 0.1, 1))
            return float(candidates[0])

        unrefined = smallest_passing(grid[grid >= floors[name][0] - 1e-9], lambda m: (m, largest))
        refined = smallest_passing(grid[grid >= max(unrefined, floors[name][1]) - 1e-9], lambda m: (unrefined, m))
        margins[name] = (unrefined, refined)
        model.margins = kept
    print("95th percentiles of true / estimate (unrefined, refined): "
          + ", ".join(f"{name} {a:.2f}, {b:.2f}" for name, (a, b) in floors.items()))
    return margins


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--accuracies", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    parser.add_argument("--parts", nargs="+", choices=tuple(CASES), default=list(CASES))
    parser.add_argument("--front", help="a front measured before (accuracy_front.csv): only the choices are made")
    parser.add_argument("--add-density", type=int, nargs="+",
                        help="with --front: measure the front of these density orders' settings (added to the"
                             " error model since) and write the merged front")
    parser.add_argument("--calibrate", action="store_true",
                        help="print the safety margins per table (unrefined, refined) derived from the check")
    parser.add_argument("--validate", action="store_true",
                        help="only the chosen settings at gaps between the check's (VALIDATION)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", wb.ContactResolutionWarning)
    if args.validate:
        rows = validate(args.parts, args.accuracies)
        print_table(rows, {"estimate": "{:.2e}", "bound": "{:.2e}", "error": "{:.2e}", "error/accuracy": "{:.2f}"})
        over = [r for r in rows if r["error"] > r["accuracy"]]
        print(f"true error above the accuracy: {len(over)} of {len(rows)}, {sum(not r['warned'] for r in over)} of"
              f" them without a warning (at most {max(r['error/accuracy'] for r in rows):.2f} times)")
        print(f"table: {write_csv('accuracy_validation.csv', rows)}")
        return
    cases = [(part, gap) for part in args.parts for gap in CASES[part]]
    checked = [(name, gap) for part, gap in cases for name in TABLE_PARTS[part]]
    fronts = []
    if args.front:
        with open(args.front) as f:
            fronts = [{**r, "gap": float(r["gap"]), "k": int(r["k"]), "p": int(r["p"]), "ratio": float(r["ratio"]),
                       "error": float(r["error"]), "ms": float(r["ms"])} for r in csv.DictReader(f)]
    if not args.front or args.add_density:  # measure the front, or the added orders' part of it
        fronts = [r for r in fronts if r["p"] not in args.add_density] + measured_front(cases, args.add_density)
        print(f"front: {write_csv('accuracy_front.csv', fronts)}")
    if args.calibrate:
        print(f"margins: {calibrate(fronts, checked, args.accuracies)} (in use: {accuracy.MARGINS})")
    rows = check(fronts, checked, args.accuracies)
    print_table(rows, {"estimate": "{:.2e}", "bound": "{:.2e}", "error": "{:.2e}", "estimate/error": "{:.2f}",
                       "ms": "{:.1f}", "cheapest_ms": "{:.1f}", "cost/cheapest": "{:.2f}"})
    within = [r for r in rows if 1 / 3 <= r["estimate/error"] <= 3]
    judged = [r for r in rows if r["cheapest"] != "-"]
    over = [r for r in rows if r["error"] > r["accuracy"]]
    cost = np.array([r["cost/cheapest"] for r in judged])
    print(f"estimate within a factor 3 of the true error: {len(within)} of {len(rows)};"
          f" true error within the bound: {sum(r['error'] <= r['bound'] for r in rows)} of {len(rows)};"
          f" cost within 2 x the cheapest reaching the accuracy: {sum(cost <= 2)} of {len(judged)}"
          f" (geometric mean {np.exp(np.mean(np.log(cost))):.2f}; chosen {sum(r['ms'] for r in judged):.0f} ms in all)")
    print(f"true error above the accuracy: {sum(r in over for r in judged)} of the {len(judged)} cases a measured"
          f" setting reaches, {sum(not r['warned'] for r in over)} of them without a warning; at most"
          f" {max(r['error'] / r['accuracy'] for r in judged):.2f} times; the target warned in"
          f" {sum(bool(r['warned']) for r in rows)} of {len(rows)}")
    print(f"table: {write_csv('accuracy_target.csv', rows)}")
    chart(rows)


def chart(rows: list[dict]) -> None:
    plt = pyplot()
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(15, 4.2))
    for part, marker in (("wall", "o"), ("shear", "D"), ("fixed", "^"), ("pair", "s")):
        for target, colour in zip(sorted({r["accuracy"] for r in rows}, reverse=True), ("C0", "C1", "C2", "C3")):
            mine = [r for r in rows if r["part"] == part and r["accuracy"] == target]
            left.loglog([r["error"] for r in mine], [r["estimate"] for r in mine], marker, color=colour,
                        label=f"{part}, accuracy {target:g}", mfc="none" if part == "pair" else colour)
            middle.loglog([r["gap"] for r in mine], [r["error"] / r["accuracy"] for r in mine], marker, color=colour,
                          mfc="none" if part == "pair" else colour)
            right.semilogx([r["gap"] for r in mine], [r["cost/cheapest"] for r in mine], marker + "-", color=colour,
                           mfc="none" if part == "pair" else colour)
    span = np.array(left.get_xlim())
    for factor, style in ((1, "k-"), (3, "k--"), (1 / 3, "k--")):
        left.plot(span, factor * span, style, lw=0.8)
    left.set(xlabel="true relative error", ylabel="estimate", title="estimate against the exact series (--: 3x, 1/3)")
    middle.axhline(1.0, color="k", lw=0.8)
    middle.set(xlabel="gap / a (wall: h/a - 1)", ylabel="true relative error / accuracy asked",
               title="true error / accuracy (above 1: where the target warned)")
    right.axhline(2.0, color="k", ls="--", lw=0.8)
    right.set(xlabel="gap / a (wall: h/a - 1)", ylabel="time / cheapest reaching the accuracy",
              title="cost against the measured front (--: 2x)")
    left.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(output("accuracy_target.png"), dpi=120)
    print(f"chart: {output('accuracy_target.png')}")


if __name__ == "__main__":
    main()
