"""``warpbem animate``: a run's GIF has one image per frame (or the number asked for, spread
evenly, first and last included) of the figure's size, and bad options are refused."""

import pytest
from PIL import Image

from warpbem.app import cli, run
from warpbem.app.animate import animate, frame_indices

from .test_scene import BASE, write


def test_frame_indices_spread_evenly_with_both_ends():
    assert frame_indices(4, 200).tolist() == [0, 1, 2, 3]
    picked = frame_indices(1001, 5)
    assert picked.tolist() == [0, 250, 500, 750, 1000]


def test_a_run_animates_frame_by_frame_at_the_figure_size(tmp_path):
    out = tmp_path / "run.h5"
    run.run(write(tmp_path, BASE), out, progress=lambda line: None)  # frames at 0, 0.2, 0.4, 0.6 s
    gif = animate(out, dpi=50)
    assert gif == tmp_path / "run.gif"
    with Image.open(gif) as image:
        assert image.n_frames == 4 and image.size == (8 * 50, 7 * 50)
    assert cli.main(["animate", str(out), "--output", str(tmp_path / "two.gif"), "--frames", "2"]) == 0
    with Image.open(tmp_path / "two.gif") as image:
        assert image.n_frames == 2
    with pytest.raises(ValueError, match="fps 0"):
        animate(out, tmp_path / "bad.gif", fps=0)
