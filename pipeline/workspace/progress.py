"""Progress of long work as log lines: ``what k/N (p %), m:ss elapsed, about m:ss left``.

One line per step when ``every`` is 0 (a sweep's jobs), else at most one line per ``every``
seconds plus the last step (a job's chunks: a dense grid has thousands of them). The time left
is the mean time per step since the first times the steps left (the first step carries the
start: workers, caches, a first compile), once STABLE_STEPS are done; before, the cost model's
estimate where the caller gives one ("by the cost model"), else the mean so far. A job's first
chunks measured on a loaded machine said 7 h for a 12-minute job.
"""

from __future__ import annotations

import logging
import time


STABLE_STEPS = 3  # steps done before the measured rate (the first step aside) replaces the estimate


class Progress:
    def __init__(self, what: str, total: int, logger: logging.Logger, every: float = 0.0,
                 clock=time.monotonic, estimate: float | None = None):
        self.what, self.total, self.log, self.every, self.clock = what, total, logger, every, clock
        self.estimate = estimate  # seconds for every step, by the cost model
        self.done = 0
        self.start = self.last = clock()
        self.first = self.start  # when the first step ended

    def step(self, detail: str = "") -> None:
        """One more step finished; ``detail`` ends the line (e.g. the job's result)."""
        self.done += 1
        if self.total <= 1:  # one step needs no progress
            return
        now = self.clock()
        if self.done == 1:
            self.first = now
        if self.done < self.total and now - self.last < self.every:
            return
        self.last = now
        self.log.info("%s %d/%d (%.0f%%), %s elapsed%s%s", self.what, self.done, self.total,
                      100.0 * self.done / self.total, clock_text(now - self.start),
                      self._left(now) if self.done < self.total else "", f": {detail}" if detail else "")

    def _left(self, now: float) -> str:
        steps = self.total - self.done
        if self.done >= STABLE_STEPS:
            return f", about {clock_text((now - self.first) / (self.done - 1) * steps)} left"
        if self.estimate is not None:
            return f", about {clock_text(self.estimate * steps / self.total)} left by the cost model"
        return f", about {clock_text((now - self.start) / self.done * steps)} left"


def clock_text(seconds: float) -> str:
    """``m:ss`` (``h:mm:ss`` from an hour)."""
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"
