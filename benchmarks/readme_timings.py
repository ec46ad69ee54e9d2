"""The README's commands timed as a new user runs them: this checkout's files (as they are in the
work tree, `git ls-files`) copied to a fresh folder, a fresh virtual environment there, then

1. install: ``python3 -m venv .venv && .venv/bin/pip install -e '.[plot]'``;
2. the main job with a cold kernel cache (the first run compiles the Warp kernels into the new
   checkout's ``.warp_cache/``): ``warpbem run scenes/recruitment_dome.toml ...``;
3. its chart: ``warpbem plot results/recruitment_dome.h5``;
4. the main job again, the kernels cached (``--overwrite``);
5. the README's scene (``scenes/settling_cell.toml``) and its chart, cached;
6. ``warpbem demo`` (25 positions of the free cell, with its chart), cached.

Each step's wall time and CPU time (user + system, of all its processes), with the machine's
load average (1 min) before and after it, goes to the table printed and to
docs/figures/readme_timings.csv, which the README, docs/getting-started.md and
scenes/recruitment_dome.toml quote. On a shared machine (load above its cores) the wall time
grows with the load and the CPU time much less: it is the better estimate of the wall time on
an idle machine with as many cores as the run uses. pip installs from the index pip is configured with (its
cache as it is), so the install time depends on the network and the cache.

    python benchmarks/readme_timings.py [--keep FOLDER]
"""

import argparse
import csv
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CSV = ROOT / "docs" / "figures" / "readme_timings.csv"
MAIN = ".venv/bin/warpbem run scenes/recruitment_dome.toml --output results/recruitment_dome.h5"
STEPS = [
    ("install", f"{sys.executable} -m venv .venv && .venv/bin/pip install -q -e '.[plot]'"),
    ("main job, cold kernel cache", MAIN),
    ("main job's chart", ".venv/bin/warpbem plot results/recruitment_dome.h5"),
    ("main job, kernels cached", f"{MAIN} --overwrite"),
    ("README scene (settling cell)", ".venv/bin/warpbem run scenes/settling_cell.toml --output results/settling.h5"),
    ("README scene's chart", ".venv/bin/warpbem plot results/settling.h5"),
    ("warpbem demo (25 positions, chart)", ".venv/bin/warpbem demo --output results/demo.h5"),
]


def copy_checkout(target: Path) -> None:
    """The files git tracks, as they are in the work tree (what a clone of them would hold)."""
    names = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True, capture_output=True).stdout
    for name in filter(None, names.decode().split("\0")):
        source = ROOT / name
        if source.is_file():
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target / name)


def cpu_seconds() -> float:
    """User + system CPU time of the finished child processes so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(command: str, folder: Path, environment: dict) -> tuple[float, float, str]:
    """Wall and CPU seconds of ``command`` (a shell line run in ``folder``), and its last line."""
    start, cpu = time.perf_counter(), cpu_seconds()
    result = subprocess.run(command, shell=True, cwd=folder, env=environment, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"{command!r} failed ({result.returncode}):\n{result.stderr[-3000:]}")
    return seconds, cpu_seconds() - cpu, result.stdout.strip().splitlines()[-1] if result.stdout.strip() else ""


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--keep", type=Path, help="run in this (new) folder and keep it (default: a temporary one)")
    args = parser.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="warpbem-readme-"))
    folder.mkdir(parents=True, exist_ok=True)
    copy_checkout(folder)
    # a new user's shell: no cache folder, threads or Python path of this session carried over
    environment = {k: v for k, v in os.environ.items()
                   if k not in ("WARPBEM_CACHE", "PYTHONPATH", "VIRTUAL_ENV", "OMP_NUM_THREADS")}
    rows = []
    try:
        for step, command in STEPS:
            load = os.getloadavg()[0]
            seconds, cpu, last_line = timed(command, folder, environment)
            rows.append({"step": step, "command": command.replace(sys.executable, "python3"),
                         "seconds": round(seconds, 1), "cpu_seconds": round(cpu, 1), "load_before": round(load, 2),
                         "load_after": round(os.getloadavg()[0], 2), "last_line": last_line})
            print(f"{step:38s} {seconds:7.1f} s  cpu {cpu:7.1f} s   load {load:.2f} -> {rows[-1]['load_after']:.2f}"
                  f"   {last_line}", flush=True)
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    with CSV.open("w", newline="") as f:
        f.write(f"# benchmarks/readme_timings.py on {os.cpu_count()} CPU cores, {time.strftime('%Y-%m-%d')}; seconds: wall,"
                " cpu_seconds: user + system of the step's processes; load: the 1-minute load average before and"
                " after each step\n")
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"-> {CSV.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
