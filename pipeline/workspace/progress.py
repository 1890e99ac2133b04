"""Progress of long work as log lines: ``what k/N (p %), m:ss elapsed, about m:ss left``.

One line per step when ``every`` is 0 (a sweep's jobs), else at most one line per ``every``
seconds plus the last step (a job's chunks: a dense grid has thousands of them). The time left
is the mean time per step so far times the steps left.
"""

from __future__ import annotations

import logging
import time


class Progress:
    def __init__(self, what: str, total: int, logger: logging.Logger, every: float = 0.0,
                 clock=time.monotonic):
        self.what, self.total, self.log, self.every, self.clock = what, total, logger, every, clock
        self.done = 0
        self.start = self.last = clock()

    def step(self, detail: str = "") -> None:
        """One more step finished; ``detail`` ends the line (e.g. the job's result)."""
        self.done += 1
        if self.total <= 1:  # one step needs no progress
            return
        now = self.clock()
        if self.done < self.total and now - self.last < self.every:
            return
        self.last = now
        elapsed = now - self.start
        left = elapsed / self.done * (self.total - self.done)
        self.log.info("%s %d/%d (%.0f%%), %s elapsed%s%s", self.what, self.done, self.total,
                      100.0 * self.done / self.total, clock_text(elapsed),
                      f", about {clock_text(left)} left" if self.done < self.total else "",
                      f": {detail}" if detail else "")


def clock_text(seconds: float) -> str:
    """``m:ss`` (``h:mm:ss`` from an hour)."""
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"
