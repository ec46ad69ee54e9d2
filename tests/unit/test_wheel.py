"""The package as a user installs it: a wheel built from the checkout (a normal, non-editable
install) into a fresh virtual environment outside the checkout, where ``import warpbem``,
``warpbem --help`` and a tiny scene must work. The editable install of the test command
would hide a subpackage missing from the wheel (``warpbem.elastic`` once was)."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py

from tests.verification.sphere_wall_series import free_sphere_in_shear

ROOT = Path(__file__).resolve().parents[2]
TINY_SCENE = """
[flow]
shear_rate = 100.0
viscosity = 1.2e-3

[time]
end = 2.0e-4
dt_max = 1.0e-4

[[bodies]]
name = "free"
position = [0.0, 0.0, 7.0e-6]
mesh = { shape = "sphere", radius = 5.0e-6, subdivisions = 2 }
"""


def _run(args, cwd, env, timeout=900):
    out = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert out.returncode == 0, f"{' '.join(map(str, args))} failed:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    return out.stdout


def test_wheel_installs_and_runs_outside_the_checkout(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["WARPBEM_CACHE"] = str(tmp_path / "kernel_cache")  # nothing compiled by the checkout is reused
    # built from a copy: setuptools' build/ folder in the checkout would keep files since removed
    source = tmp_path / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".venv", ".warp_cache", "build", "results",
                                                                 "*.egg-info", "__pycache__"))
    wheels = tmp_path / "wheels"
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", wheels, source], tmp_path, env)
    (wheel,) = wheels.glob("warpbem-*.whl")
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv], tmp_path, env)
    python, warpbem = venv / "bin" / "python", venv / "bin" / "warpbem"
    _run([python, "-m", "pip", "install", "-q", wheel], tmp_path, env)

    work = tmp_path / "work"  # outside the checkout: only the installed package can be imported
    work.mkdir()
    where = _run([python, "-c", "import warpbem, warpbem.elastic, warpbem.kernels; print(warpbem.__file__)"],
                 work, env)
    assert Path(where.strip()).is_relative_to(venv), f"imported from {where.strip()}, not the fresh venv"
    assert "usage: warpbem" in _run([warpbem, "--help"], work, env)
    (work / "tiny.toml").write_text(textwrap.dedent(TINY_SCENE))
    _run([warpbem, "run", "tiny.toml", "--output", "tiny.h5"], work, env)
    with h5py.File(work / "tiny.h5", "r") as f:
        time = f["time"][:]
        start, end = f["position"][0, 0], f["position"][-1, 0]
    # the start frame and one per step of dt_max up to end = 2 dt_max
    assert len(time) == 3 and abs(time[-1] - 2.0e-4) < 1e-12
    # a free sphere in wall shear travels with the flow at U = X gdot h, X = 0.8938 at h/a = 1.4
    # (Goldman, Cox & Brenner 1967b, Chem. Eng. Sci. 22:653; the exact bipolar series of
    # tests/verification/sphere_wall_series.py), and at a constant height (no lift in Stokes
    # flow). The k = 2 mesh errs by +0.47 % in U here (k = 3: +0.42 %, k = 4: +0.24 %; this scene
    # run in the checkout): 1 % allowed, twice the discretisation error
    travel, exact = end[0] - start[0], free_sphere_in_shear(1.4)["U_over_gdot_h"] * 100.0 * 7.0e-6 * 2.0e-4
    assert abs(travel / exact - 1) < 0.01, travel / exact - 1
    assert abs(end[2] - start[2]) < 1e-3 * travel and abs(end[1] - start[1]) < 1e-3 * travel
