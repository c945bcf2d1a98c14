"""A sweep's progress bar, drawn on a terminal only (stderr), as
``drape run`` draws its own; elsewhere (a log, a notebook's captured
output, a pipe) nothing is printed."""

from __future__ import annotations

import sys
import time
from typing import Optional, TextIO


def _clock(seconds: float) -> str:
    seconds = int(seconds)
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"


class Bar:
    """``[#########...........] 9/20 cases, 1 failed  0:42 elapsed, ~0:51 left``.

    ``done`` cases were finished before (a resumed sweep): they count as
    done but not in the time left, which is estimated from the cases this
    sweep ran.
    """

    WIDTH = 30

    def __init__(self, total: int, done: int = 0, enabled: Optional[bool] = None, stream: Optional[TextIO] = None):
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.total = total
        self.done = done
        self.before = done
        self.failed = 0
        self.start = time.monotonic()
        self._draw()

    def update(self, failed: bool = False) -> None:
        """One more case finished."""
        self.done += 1
        self.failed += int(failed)
        self._draw()

    def close(self) -> None:
        """Ends the bar's line."""
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
            self.enabled = False

    def _draw(self) -> None:
        if not self.enabled:
            return
        fraction = self.done / self.total if self.total else 1.0
        filled = int(round(self.WIDTH * fraction))
        elapsed = time.monotonic() - self.start
        ran = self.done - self.before
        left = ""
        if 0 < ran and self.done < self.total:
            left = f", ~{_clock(elapsed / ran * (self.total - self.done))} left"
        failed = f", {self.failed} failed" if self.failed else ""
        line = (
            f"\r[{'#' * filled}{'.' * (self.WIDTH - filled)}] {self.done}/{self.total} cases{failed}"
            f"  {_clock(elapsed)} elapsed{left}"
        )
        self.stream.write(line + "\033[K")
        self.stream.flush()
