"""Devices: one that the machine lacks is refused by every entry point that takes one, before any
work, with a DeviceError naming the devices there are; a run on the CPU prints nothing of CUDA."""

import subprocess
import sys

import pytest

import warpbem as wb
from warpbem import runtime

ABSENT = "cuda:99"  # no machine this runs on has a hundred GPUs


def test_an_absent_device_is_named_with_those_there_are():
    with pytest.raises(wb.DeviceError, match=r"device 'cuda:99' is not available; this machine has: cpu"):
        runtime.resolve_device(ABSENT)
    assert issubclass(wb.DeviceError, ValueError)
    assert runtime.resolve_device("cpu").is_cpu


def test_every_entry_point_refuses_it_before_any_work():
    cell = wb.mesh.sphere(1.0, 1)
    # two bodies in one place: any work (the placement check first) would raise PlacementError
    overlapping = [wb.Body(cell, position=(0.0, 0.0, 2.0)), wb.Body(cell, position=(0.0, 0.0, 2.0))]
    with pytest.raises(wb.DeviceError):
        wb.MobilitySolver(device=ABSENT)
    with pytest.raises(wb.DeviceError):
        wb.solve_mobility(overlapping, device=ABSENT)
    with pytest.raises(wb.DeviceError):
        wb.solve_traction(overlapping, device=ABSENT)
    with pytest.raises(wb.DeviceError):
        wb.Simulator(wb.Model(meshes=[cell], fixed=[False]), device=ABSENT)


def test_a_solve_on_the_cpu_prints_nothing_of_cuda():
    code = ("import warpbem as wb; cell = wb.mesh.sphere(1.0, 1);"
            " print(wb.solve_mobility([wb.Body(cell, position=(0, 0, 2.0))], 1.0, 1.0, device='cpu').velocity[0, 0])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert float(out.stdout) > 0.0  # it solved: the sphere moves with the shear flow
    assert "CUDA" not in out.stderr, out.stderr
