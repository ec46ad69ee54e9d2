"""Progress of a long command: one line per item done, ``[done/total] what  ETA 42 s``.

    progress = Progress(len(cases))
    for case in cases:
        ...
        progress.done(f"{case}: {wall:.1f} s")

The ETA is the time per item so far times the items left (none after the last item), in
seconds under two minutes and in minutes above. Plain lines, no dependency: tqdm's
carriage-return bars garble the log files these commands are redirected to.
"""

from __future__ import annotations

import time
from typing import Callable


def _print(line: str) -> None:
    print(line, flush=True)


def eta_text(seconds: float) -> str:
    """'ETA 42 s' under two minutes, 'ETA 3.5 min' above."""
    return f"ETA {seconds:.0f} s" if seconds < 120 else f"ETA {seconds / 60:.1f} min"


class Progress:
    """Counts items done out of ``total`` and reports a line per item through ``report`` (a
    callable taking the line; print, flushed, by default). The clock starts at construction."""

    def __init__(self, total: int, report: Callable[[str], None] = _print):
        if total < 0:
            raise ValueError(f"Progress: total must be >= 0, got {total}")
        self.total = int(total)
        self.count = 0
        self.report = report
        self.started = time.monotonic()

    def line(self, what: str) -> str:
        """The line for the current count (no ETA once every item is done)."""
        text = f"[{self.count}/{self.total}] {what}"
        if 0 < self.count < self.total:
            elapsed = time.monotonic() - self.started
            text += "  " + eta_text(elapsed / self.count * (self.total - self.count))
        return text

    def done(self, what: str) -> str:
        """One more item done (``what``: which, and what came of it): report and return its line."""
        self.count += 1
        text = self.line(what)
        self.report(text)
        return text
