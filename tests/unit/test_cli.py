"""Every verb given a missing or unreadable file says so in one line naming the file, with a
non-zero exit status and no traceback."""

import h5py
import pytest

from warpbem.app import cli


def one_line(capsys) -> str:
    lines = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("Warp CUDA")]
    assert len(lines) == 1 and "Traceback" not in lines[0], lines
    return lines[0]


@pytest.fixture
def files(tmp_path):
    garbage = tmp_path / "garbage.h5"
    garbage.write_text("not HDF5 at all")
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["numbers"] = [1.0, 2.0]
    (tmp_path / "garbage.toml").write_text("[flow\nshear_rate = ")
    (tmp_path / "a_file").write_text("")
    return tmp_path


@pytest.mark.parametrize("argv, named, problem", [
    (["run", "{d}/missing.toml", "--output", "{d}/out.h5"], "missing.toml", "cannot read the scene"),
    (["run", "{d}/garbage.toml", "--output", "{d}/out.h5"], "garbage.toml", "not valid TOML"),
    (["run", "--resume", "--output", "{d}/missing.h5"], "missing.h5", "no such file"),
    (["run", "--resume", "--output", "{d}/garbage.h5"], "garbage.h5", "not a readable HDF5 file"),
    (["run", "--resume", "--output", "{d}/foreign.h5"], "foreign.h5", "not a warpbem run file"),
    (["plot", "{d}/missing.h5"], "missing.h5", "no such file"),
    (["plot", "{d}/garbage.h5"], "garbage.h5", "not a readable HDF5 file"),
    (["plot", "{d}/foreign.h5"], "foreign.h5", "neither a run"),
    (["sweep", "{d}/missing.toml", "--vary", "flow.viscosity=1e-3,2e-3", "--output-dir", "{d}/sweep"],
     "missing.toml", "cannot read the scene"),
    (["xdmf", "{d}/missing.h5"], "missing.h5", "no such file"),
    (["xdmf", "{d}/garbage.h5"], "garbage.h5", "not a readable HDF5 file"),
    # the output's folder cannot be made where a file of that name is (the system's own words)
    (["demo", "--positions", "1", "--output", "{d}/a_file/demo.h5"], "a_file", "File exists"),
])
def test_bad_files_end_in_one_line_naming_them(files, capsys, argv, named, problem):
    argv = [a.format(d=files) for a in argv]
    assert cli.main(argv) == 2
    line = one_line(capsys)
    assert line.startswith(f"warpbem {argv[0]}: ") and named in line and problem in line


@pytest.mark.parametrize("argv", [
    ["run", "scenes/settling_cell.toml", "--output", "{d}/out.h5", "--device", "cuda:99"],
    ["sweep", "scenes/settling_cell.toml", "--vary", "flow.viscosity=1e-3,2e-3", "--output-dir", "{d}/sweep",
     "--device", "cuda:99"],
    ["demo", "--positions", "1", "--output", "{d}/demo.h5", "--device", "cuda:99"],
])
def test_an_absent_device_ends_in_one_line_naming_the_devices_there_are(tmp_path, capsys, argv):
    argv = [a.format(d=tmp_path) for a in argv]
    assert cli.main(argv) == 2
    line = one_line(capsys)
    assert line.startswith(f"warpbem {argv[0]}: device 'cuda:99' is not available; this machine has: cpu")
    assert not any(tmp_path.iterdir())  # refused before any work: nothing written
