"""Packaging promises: importing warpbem loads no Warp (so compiles nothing, touches no
device), and the kernels ship as warpbem.kernels."""

import subprocess
import sys


def test_import_touches_no_device():
    code = "import sys, warpbem; assert 'warp' not in sys.modules, 'warp imported'; print(warpbem.__version__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "0.1.0"


def test_kernels_are_a_subpackage():
    import warpbem.kernels.assembly as assembly
    import warpbem.kernels.greens as greens

    assert callable(assembly.build_kernels) and callable(greens.make_green_functions)
