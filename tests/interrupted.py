"""A run killed after a number of frames, as Ctrl-C would kill it (tests only)."""

import pytest

from warpbem.app import run


class Stop(Exception):
    """Raised from the progress callback: the run's interruption."""


def run_killed_after(frames: int, path, output) -> None:
    """Run scene ``path`` into ``output`` and stop it once ``frames`` progress lines were shown
    (the frames written before it stay in the file)."""
    seen = []

    def stop(line):
        seen.append(line)
        if len(seen) == frames:
            raise Stop

    with pytest.raises(Stop):
        run.run(path, output, progress=stop)
