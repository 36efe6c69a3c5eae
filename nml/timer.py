"""A periodic timer whose ``wait()`` returns at the next period boundary (ARCH-018).

Boundaries are absolute (start + k * period), so the work done in one period never shifts
the next ones; a period overrun skips to the next boundary still ahead and is counted.
"""

from __future__ import annotations

import time


class Timer:
    def __init__(self, period_s: float) -> None:
        if not period_s > 0:
            raise ValueError(f"timer period must be positive, got {period_s}")
        self.period_s = period_s
        self._start = time.monotonic()
        self._ticks = 0
        self.overruns = 0

    def wait(self) -> None:
        """Sleep until the next period boundary."""
        self._ticks += 1
        target = self._start + self._ticks * self.period_s
        now = time.monotonic()
        if now > target:
            missed = int((now - target) / self.period_s) + 1
            self.overruns += missed
            self._ticks += missed
            target = self._start + self._ticks * self.period_s
        time.sleep(max(0.0, target - time.monotonic()))
