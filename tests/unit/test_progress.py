"""warpbem.app.progress: done / total lines with an ETA from the time per item so far."""

import pytest

from warpbem.app import progress as progress_module
from warpbem.app.progress import Progress, eta_text


class Clock:
    """A time.monotonic() stand-in moved by hand."""

    def __init__(self, now=1000.0):
        self.now = now

    def __call__(self):
        return self.now


@pytest.fixture
def clock(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    return clock


def test_lines_count_done_over_total_with_the_eta_from_the_time_per_item(clock):
    lines = []
    progress = Progress(10, lines.append)
    for k in range(3):
        clock.now += 10.0
        returned = progress.done(f"case {k}")
    # 3 of 10 done after 30 s: 10 s an item, 7 left
    assert lines == ["[1/10] case 0  ETA 90 s", "[2/10] case 1  ETA 80 s", "[3/10] case 2  ETA 70 s"]
    assert returned == lines[-1] and progress.count == 3 and progress.total == 10


def test_no_eta_on_the_last_item(clock):
    lines = []
    progress = Progress(2, lines.append)
    clock.now += 5.0
    progress.done("a")
    clock.now += 5.0
    progress.done("b")
    assert lines == ["[1/2] a  ETA 5 s", "[2/2] b"]


def test_minutes_above_two_minutes_seconds_below(clock):
    lines = []
    progress = Progress(5, lines.append)
    clock.now += 60.0  # 60 s an item, 4 left: 240 s
    progress.done("slow")
    assert lines == ["[1/5] slow  ETA 4.0 min"]
    assert eta_text(119.4) == "ETA 119 s"
    assert eta_text(120.0) == "ETA 2.0 min"
    assert eta_text(90 * 60) == "ETA 90.0 min"


def test_the_clock_starts_when_the_progress_is_made(clock):
    clock.now = 50.0
    progress = Progress(4, lambda line: None)
    clock.now = 62.0  # 12 s for the first item, 3 left
    assert progress.done("x") == "[1/4] x  ETA 36 s"


def test_default_report_prints_flushed(clock, capsys):
    Progress(3).done("printed")
    assert capsys.readouterr().out == "[1/3] printed  ETA 0 s\n"


def test_a_negative_total_is_refused():
    with pytest.raises(ValueError, match="total must be >= 0"):
        Progress(-1)
