"""Resident memory of long runs (issue 26 item 5): a deformable, an adhesive and a deformable
adhesive run, each stepped in a process of its own, its resident set size (RSS) read after
steps 50, 200 and 500, and its peak.

Cases (the scenes at k = 4, run past their end where they stop before 500 steps):
- deformable: a 0.5 kPa free cell passing an adherent sphere (scenes/fig5_14_18_deformable_free.toml,
  bodies.0.deformable = true), 1 ms steps;
- adhesive: fig. 4.9's rigid cell rolling on soft bonds (scenes/fig4_09_11_soft_bonds.toml), 20 us steps;
- deformable + adhesive: the 4 kPa compliant rolling cell (scenes/fig4_07_11_compliant_rolling.toml),
  20 us steps: the runs that grew to 5-7 GB over 500 steps before the fix of 944f8b3.

    python benchmarks/memory.py [--cases deformable adhesive "deformable + adhesive"] [--steps 50 200 500]

Prints the table with each run's peak against PEAK_BOUND_MB (and exits with status 1 if a peak
passes it), writes results/bench/memory.csv and memory.png (RSS against step; --name changes the
name). With PYTHONPATH pointing at another checkout the child processes measure that
checkout's code (the commit before the fix, 944f8b3^: CHANGELOG.md; the table: docs/benchmarks.md).
"""

import argparse
import json
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

from common import output, print_table, pyplot, save_chart, write_csv
from warpbem.app.progress import Progress

SCENES = Path(__file__).resolve().parent.parent / "scenes"
CASES = {"deformable": ("fig5_14_18_deformable_free.toml", ["bodies.0.deformable=true", "time.end=1.0"]),
         "adhesive": ("fig4_09_11_soft_bonds.toml", ["time.end=0.02"]),
         "deformable + adhesive": ("fig4_07_11_compliant_rolling.toml", [])}
SAMPLE_EVERY = 10  # steps between RSS samples for the chart
# The peak resident memory a run of one cell at k = 4 stays under (MB): 883-1230 MB for the three
# cases over 500 steps, 2242-6293 MB at 944f8b3^, 1.2 GB for the k = 2 run of
# tests/unit/test_memory.py (3.6 GB at 944f8b3^; the test bounds only its growth, which does not
# depend on the machine as the absolute peak does)
PEAK_BOUND_MB = 2048


def resident_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20


def peak_mb() -> float:
    """VmHWM: this process image's high-water mark (ru_maxrss would also keep the parent's from
    before the exec)."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM:")) / 2**10


def one_case(name: str, last_step: int) -> None:
    """Step case ``name`` to ``last_step`` in this process, printing one JSON line per sample."""
    from warpbem.app import scene as scenes
    from warpbem.dynamics.simulator import Simulator

    warnings.simplefilter("ignore")  # the scenes' known mesh-resolution warnings, not what this measures
    path, overrides = CASES[name]
    scene = scenes.load(SCENES / path, overrides)
    state, sim = scene.initial_state(), Simulator(scene.model, "cpu")
    started = time.perf_counter()
    for step in range(1, last_step + 1):
        state, _ = sim.step(state, scene.next_stop(state.time))
        if step % SAMPLE_EVERY == 0 or step == last_step:
            print(json.dumps({"step": step, "rss_mb": resident_mb(), "peak_mb": peak_mb(),
                              "wall_s": time.perf_counter() - started}), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--steps", type=int, nargs="+", default=[50, 200, 500])
    parser.add_argument("--name", default="memory", help="the table's and chart's file name, without suffix")
    parser.add_argument("--one", help=argparse.SUPPRESS)  # the child process's case
    args = parser.parse_args()
    if args.one:
        return one_case(args.one, max(args.steps))
    progress, rows, samples = Progress(len(args.cases)), [], {}
    for name in args.cases:
        child = subprocess.run([sys.executable, __file__, "--one", name, "--steps", *map(str, args.steps)],
                               capture_output=True, text=True, check=True)
        samples[name] = [json.loads(line) for line in child.stdout.splitlines() if line.startswith("{")]
        at = {s["step"]: s for s in samples[name]}
        row = {"case": name}
        for step in args.steps:
            nearest = at[min(at, key=lambda k: abs(k - step))]
            row[f"rss_{step}_mb"] = nearest["rss_mb"]
        peak = samples[name][-1]["peak_mb"]
        row.update(peak_mb=peak, peak_bound_mb=PEAK_BOUND_MB, within_bound="yes" if peak < PEAK_BOUND_MB else "NO",
                   wall_s=samples[name][-1]["wall_s"])
        rows.append(row)
        progress.done(f"{name}: {row['wall_s']:.0f} s")
    print_table(rows, {k: "{:.0f}" for k in rows[0] if k not in ("case", "within_bound")})
    over = [r["case"] for r in rows if r["within_bound"] != "yes"]
    print(f"peak resident memory over {PEAK_BOUND_MB} MB: {', '.join(over)}" if over else
          f"every peak under the bound of {PEAK_BOUND_MB} MB")
    print(f"table: {write_csv(args.name + '.csv', rows)}")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.8))
    for name, points in samples.items():
        ax.plot([p["step"] for p in points], [p["rss_mb"] for p in points], label=name)
    ax.set_xlabel("step")
    ax.set_ylabel("resident memory [MB]")
    ax.set_ylim(bottom=0)
    print(f"chart: {save_chart(fig, output(args.name + '.png'), [ax], legend_size=8)}")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
