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


@pytest.fixture(scope="module")
def two_bodies(tmp_path_factory):
    """A run of a free cell 3 um above the wall in shear and a held one 12 um beside it in y and
    4 um higher (centres (0, 0, 8) and (10, 12, 12) um, radius 5 um): 4 frames."""
    tmp_path = tmp_path_factory.mktemp("two_bodies")
    table = json.loads(json.dumps(BASE))
    table["flow"]["shear_rate"] = 5.0
    table["bodies"].append({"position": [10e-6, 12e-6, 12e-6], "fixed": True,
                            "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 2}})
    out = tmp_path / "run.h5"
    run.run(write(tmp_path, table), out, progress=lambda line: None)
    return out


def test_run_chart_has_side_and_top_views_to_scale(two_bodies, tmp_path):
    """Two bodies (one held): five panels; the side and top views have equal axis scales and
    the moving cell's outline drawn at several times, the held one once, each body named."""
    out = two_bodies
    fig = plotting.run_figure(out)
    height, lateral, gap, side, top = fig.axes[:5]
    assert "side view" in side.get_title() and "top view" in top.get_title()
    for ax in (side, top):
        assert ax.get_aspect() == 1.0  # "equal": drawn to scale
        assert [text.get_text().split("\n")[0] for text in ax.texts if "\n" in text.get_text()] == ["body0", "body1"]
    labels = [line.get_label() for line in side.get_lines()]
    assert any(label.startswith("body0, outlines at t = 0, ") for label in labels) and "body1 (fixed)" in labels
    outlines = [line for line in top.get_lines() if len(line.get_xdata()) > 5]
    assert len(outlines) == 4 + 1  # 4 snapshots of the moving cell (4 frames), the held cell once
    png = plotting.plot(out, tmp_path / "run.png")
    assert png == tmp_path / "run.png" and png.stat().st_size > 20_000
    with pytest.raises(plotting.RunFileError, match="neither a run"):
        import h5py

        with h5py.File(tmp_path / "other.h5", "w") as f:
            f["x"] = [1.0]
        plotting.plot(tmp_path / "other.h5")


def test_the_frames_gaps_to_the_nearest_body_and_to_the_wall_are_the_spheres(two_bodies):
    """The frame's gap columns at the start, against the geometry of two 5 um spheres: to the
    wall z - a = 3 um, to the held cell |c_1 - c_0| - 2 a = sqrt(10^2 + 12^2 + 4^2) - 10 um
    to 1e-3 a (the k = 2 meshes' surfaces between their nodes, on the sphere, sag inwards: 0 and
    4e-4 a measured); closest_gap is the smaller of the two at every frame."""
    import h5py

    with h5py.File(two_bodies, "r") as f:
        body, wall, closest = f["closest_body_gap"][:], f["wall_gap"][:], f["closest_gap"][:]
    assert wall[0] == pytest.approx(3e-6, abs=1e-3 * 5e-6)
    assert body[0] == pytest.approx((np.sqrt(10**2 + 12**2 + 4**2) - 10) * 1e-6, abs=1e-3 * 5e-6)
    np.testing.assert_array_equal(closest, np.minimum(body, wall))


def test_the_gap_panel_plots_and_names_both_gaps_or_says_the_file_has_only_the_closest(two_bodies, tmp_path):
    """The gap panel's lines are the file's columns (nm) under legend entries naming them; a
    file written before the two columns is plotted with its closest gap, the legend saying so."""
    import shutil

    import h5py

    fig = plotting.run_figure(two_bodies)
    gap = fig.axes[2]
    with h5py.File(two_bodies, "r") as f:
        columns = {"gap to the nearest body": f["closest_body_gap"][:], "gap to the wall": f["wall_gap"][:]}
        closest = f["closest_gap"][:]
    handles, labels = gap.get_legend_handles_labels()
    assert labels == list(columns) and [text.get_text() for text in gap.get_legend().get_texts()] == labels
    for line, label in zip(handles, labels):
        np.testing.assert_array_equal(line.get_ydata(), columns[label] * 1e9)
    old = tmp_path / "old.h5"
    shutil.copy(two_bodies, old)
    with h5py.File(old, "a") as f:
        del f["closest_body_gap"], f["wall_gap"]
    (line,), (label,) = plotting.run_figure(old).axes[2].get_legend_handles_labels()
    assert label == "closest gap, to a body or the wall (file without the separate gaps)"
    np.testing.assert_array_equal(line.get_ydata(), closest * 1e9)


def test_farther_bodies_are_drawn_behind_the_nearer_ones(two_bodies):
    """Seen from -y the held cell (y = 12 um) is behind the free one (y = 0): its fill lies under
    every outline of the free cell; seen from above it is higher (z = 12 against 8 um), so in the
    top view the order turns round. Fills are translucent, so the one behind shows through."""
    import h5py

    with h5py.File(two_bodies, "r") as f:
        position = f["position"][:]
    fig = plotting.run_figure(two_bodies)
    side, top = fig.axes[3:5]
    for ax, depth, farther in ((side, 1, 1.0), (top, 2, -1.0)):
        fills = sorted((p for p in ax.patches if p.get_gid()), key=lambda p: p.get_zorder())
        assert len(fills) == 4 + 1 and all(p.get_alpha() < 0.5 for p in fills)
        where = [tuple(int(w) for w in p.get_gid().split()[1::2]) for p in fills]  # (body, frame)
        depths = [farther * position[frame, body, depth] for body, frame in where]
        assert depths == sorted(depths, reverse=True)  # the farthest first
    assert [b for b, _ in where] == [0, 0, 0, 0, 1]  # the top view: the held cell (higher) last
    side_order = [int(p.get_gid().split()[1]) for p in sorted((p for p in side.patches if p.get_gid()),
                                                              key=lambda p: p.get_zorder())]
    assert side_order == [1, 0, 0, 0, 0]


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
    height, lateral, gap, side, top = fig.axes[:5]
    labels = [label for label in side.get_legend_handles_labels()[1]]
    assert labels == ["1 moving cells, outlines at t = 0, 0.1, 0.2 s", "16 fixed cells"]
    outlines = [line for line in top.get_lines() if len(line.get_xdata()) > 5]
    assert len(outlines) == 3 + 16  # the moving cell at 3 frames, each held cell once
    assert len(height.get_lines()) == 1
