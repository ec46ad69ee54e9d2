"""``warpbem xdmf``: one XDMF grid per frame of a run, at the run's times, with the meshes placed
by the stored positions and orientations; the run file is only read."""

import hashlib
import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from warpbem.app import cli, run, scene, xdmf
from warpbem.surfaces import quad9
from warpbem.surfaces.body import rotation_matrix

from .test_scene import BASE, write


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """Two bodies with different meshes (so the connectivity offsets matter), turning in shear
    (so a transposed rotation would show) and settling: 2 steps, 3 frames."""
    tmp = tmp_path_factory.mktemp("xdmf")
    table = json.loads(json.dumps(BASE))
    table["flow"]["shear_rate"] = 1.0
    table["time"]["end"] = 0.4
    table["bodies"].append({"position": [15e-6, 0.0, 8e-6], "density": 1050.0,
                            "mesh": {"shape": "spheroid", "radius": 4e-6, "aspect_ratio": 0.7, "subdivisions": 1}})
    path = tmp / "run.h5"
    run.run(write(tmp, table), path, progress=lambda line: None)
    return path


def read(reference, folder):
    """The array an XDMF HDF DataItem ('file.h5:/group/name') points to."""
    name, dataset = reference.strip().split(":", 1)
    with h5py.File(folder / name) as f:
        return f[dataset][:]


def test_quad9_node_order_is_vtks_biquadratic_quad():
    """VTK_BIQUADRATIC_QUAD (what ParaView makes of Quadrilateral_9): corners counter-clockwise,
    mid-edge nodes of edges 01, 12, 23, 30, centre; xdmf.py writes our connectivity unchanged."""
    r = quad9.REFERENCE_NODES
    a, b = r[:4] - r[8], np.roll(r[:4], -1, axis=0) - r[8]
    assert np.all(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] > 0)  # counter-clockwise about the centre
    np.testing.assert_array_equal(r[4:8], (r[:4] + np.roll(r[:4], -1, axis=0)) / 2)
    np.testing.assert_array_equal(r[8], r[:4].mean(axis=0))


def test_one_grid_per_frame_with_the_run_s_times_and_placed_meshes(run_file):
    before = hashlib.sha256(run_file.read_bytes()).hexdigest()
    path = xdmf.write(run_file)
    assert path == run_file.with_suffix(".xdmf") and run_file.with_suffix(".xdmf.h5").exists()
    assert hashlib.sha256(run_file.read_bytes()).hexdigest() == before  # the run file is only read

    with h5py.File(run_file) as f:
        time, position, orientation = f["time"][:], f["position"][:], f["orientation"][:]
        meshes = [b.mesh for b in scene.parse(json.loads(f.attrs["scene"]), run_file.parent).bodies]
    assert len(time) == 3 and not np.allclose(orientation[-1, 0], [1, 0, 0, 0])  # the first body turned

    root = ET.parse(path).getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    (series,) = root.find("Domain").findall("Grid")
    assert series.get("GridType") == "Collection" and series.get("CollectionType") == "Temporal"
    grids = series.findall("Grid")
    assert len(grids) == len(time)
    assert [float(g.find("Time").get("Value")) for g in grids] == time.tolist()

    last = grids[-1]
    topology = last.find("Topology")
    n_elements = sum(m.n_elements for m in meshes)
    assert topology.get("TopologyType") == "Quadrilateral_9" and int(topology.get("NumberOfElements")) == n_elements
    connectivity = read(topology.find("DataItem").text, path.parent)
    nodes = read(last.find("Geometry/DataItem").text, path.parent)
    assert connectivity.shape == (n_elements, 9) and nodes.shape == (sum(len(m.nodes) for m in meshes), 3)
    assert connectivity.min() == 0 and connectivity.max() == len(nodes) - 1

    # each body's elements, through the connectivity, land on its own mesh moved by the stored pose
    start = 0
    for i, m in enumerate(meshes):
        expected = m.nodes @ rotation_matrix(orientation[-1, i]).T + position[-1, i]
        placed = nodes[connectivity[start:start + m.n_elements]]
        np.testing.assert_allclose(placed, expected[m.elements], rtol=0, atol=1e-12 * 5e-6)
        start += m.n_elements
    assert read(last.find("Attribute/DataItem").text, path.parent).tolist() == \
        [0] * meshes[0].n_elements + [1] * meshes[1].n_elements
    # the first frame is the initial placement: every frame has its own coordinates
    first = read(grids[0].find("Geometry/DataItem").text, path.parent)
    np.testing.assert_allclose(first[:len(meshes[0].nodes)], meshes[0].nodes + position[0, 0], rtol=0, atol=1e-18)
    assert not np.allclose(first, nodes)


def test_a_run_still_being_written_can_be_read(run_file, tmp_path):
    """The writer of a run holds HDF5's file lock; xdmf reads anyway (frames flushed so far)."""
    copy = tmp_path / "live.h5"
    copy.write_bytes(run_file.read_bytes())
    holder = subprocess.Popen([sys.executable, "-c", f"import h5py, sys; f = h5py.File({str(copy)!r}, 'a');"
                               " print('open', flush=True); sys.stdin.read()"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "open"
        with pytest.raises(OSError, match="lock"):  # what a plain reader meets
            h5py.File(copy, "r")
        grids = ET.parse(xdmf.write(copy)).getroot().findall("Domain/Grid/Grid")
        assert len(grids) == 3
    finally:
        holder.communicate("")
    assert holder.returncode == 0


def test_files_that_are_not_runs_are_refused_by_name(tmp_path, run_file, capsys):
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5")
    with pytest.raises(xdmf.RunFileError, match="notes.h5: not a readable HDF5 file"):
        xdmf.write(text)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["free_velocity"] = np.zeros((2, 3))
    with pytest.raises(xdmf.RunFileError, match=r"other.h5: not a warpbem run file \(no 'time'\)"):
        xdmf.write(other)
    assert not other.with_suffix(".xdmf").exists()
    assert cli.main(["xdmf", str(other)]) == 2
    assert "warpbem xdmf: " in capsys.readouterr().err
    assert cli.main(["xdmf", str(run_file)]) == 0
    assert "run.xdmf" in capsys.readouterr().out
