"""Charts people read at a glance: a run's side and top views draw the cells to scale."""

import json

import numpy as np
import pytest

import warpbem as wb
from warpbem.app import plotting, run

from .test_scene import BASE, write


def test_outline_is_the_silhouette_of_the_cell():
    """The outline of a 5 um sphere's nodes seen from above: every node inside, the outline on
    the sphere's equator (radius 5 um), enclosing pi a^2 less what its polygon cuts off."""
    a = 5e-6
    nodes = wb.Body(wb.mesh.sphere(a, 4), position=(1e-6, 2e-6, 8e-6)).world_nodes()
    line = plotting.outline(nodes[:, :2])
    assert np.array_equal(line[0], line[-1])  # closed
    radii = np.linalg.norm(line - [1e-6, 2e-6], axis=1)
    np.testing.assert_allclose(radii, a, rtol=1e-9)
    x, y = line[:, 0], line[:, 1]
    area = 0.5 * abs(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1]))
    assert 0.97 < area / (np.pi * a**2) < 1.0


def test_run_chart_has_side_and_top_views_to_scale(tmp_path):
    """Two bodies (one held): four panels; the side and top views have equal axis scales and
    the moving cell's outline drawn at several times, the held one once."""
    table = json.loads(json.dumps(BASE))
    table["flow"]["shear_rate"] = 5.0
    table["bodies"].append({"position": [10e-6, 12e-6, 6e-6], "fixed": True,
                            "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 2}})
    out = tmp_path / "run.h5"
    run.run(write(tmp_path, table), out, progress=lambda line: None)
    fig = plotting.run_figure(out)
    height, lateral, side, top = fig.axes[:4]
    assert "side view" in side.get_title() and "top view" in top.get_title()
    for ax in (side, top):
        assert ax.get_aspect() == 1.0  # "equal": drawn to scale
    labels = [line.get_label() for line in side.get_lines()]
    assert any(label.startswith("body0, outlines at t = 0, ") for label in labels) and "body1 (fixed)" in labels
    outlines = [line for line in top.get_lines() if len(line.get_xdata()) > 5]
    assert len(outlines) == 4 + 1  # 4 snapshots of the moving cell (4 frames), the held cell once
    png = plotting.plot(out)
    assert png == out.with_suffix(".png") and png.stat().st_size > 20_000
    with pytest.raises(plotting.RunFileError, match="neither a run"):
        import h5py

        with h5py.File(tmp_path / "other.h5", "w") as f:
            f["x"] = [1.0]
        plotting.plot(tmp_path / "other.h5")


def test_a_crowded_run_groups_its_cells_in_the_legend(tmp_path):
    """An array of 16 held cells and one moving: the side view's legend names the moving cell
    and the 16 fixed ones in one entry each (not 17 entries), every cell still drawn, and the
    fixed cells' constant heights left out of Z(t)."""
    table = json.loads(json.dumps(BASE))
    table["flow"]["shear_rate"] = 5.0
    table["bodies"][0]["position"] = [-15e-6, 0.0, 20e-6]
    table["arrays"] = [{"count": [4, 4], "pitch": [15e-6, 15e-6], "origin": [0.0, 0.0, 8e-6], "fixed": True,
                        "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 2}}]
    table["time"].update(end=0.2, dt_max=0.1)
    table["solver"] = {"contact_refinement": 0.0}
    out = tmp_path / "array.h5"
    run.run(write(tmp_path, table), out, progress=lambda line: None)
    fig = plotting.run_figure(out)
    height, lateral, side, top = fig.axes[:4]
    labels = [label for label in side.get_legend_handles_labels()[1]]
    assert labels == ["1 moving cells, outlines at t = 0, 0.1, 0.2 s", "16 fixed cells"]
    outlines = [line for line in top.get_lines() if len(line.get_xdata()) > 5]
    assert len(outlines) == 3 + 16  # the moving cell at 3 frames, each held cell once
    assert len(height.get_lines()) == 1
