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
