"""timedelta: measures the real time between calls (thread jitter), in nanoseconds.

``out`` is the last interval, ``err`` the accumulated |interval - average| ... like
LinuxCNC's: ``min``/``max`` intervals, ``jitter`` the largest deviation from the first
interval, ``avg-err`` the average deviation; ``reset`` clears the statistics.
"""

import time

from hal.api import RtComponent, funct, pin


class Timedelta(RtComponent):
    out = pin("s32 out")
    err = pin("s32 out")
    min = pin("s32 out")
    max = pin("s32 out")
    jitter = pin("s32 out")
    avg_err = pin("float out")
    current_error = pin("s32 out")
    current_jitter = pin("s32 out")
    reset = pin("bit in")

    def setup(self) -> None:
        self.last = 0
        self.count = 0
        self.total_err = 0

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        now = time.monotonic_ns()
        if self.reset or self.last == 0:
            self.last, self.count, self.total_err = now, 0, 0
            self.min, self.max, self.jitter, self.err = 0, 0, 0, 0
            return
        interval = now - self.last
        self.last = now
        error = interval - period
        self.out = interval
        self.current_error = error
        self.current_jitter = abs(error)
        self.count += 1
        self.total_err += abs(error)
        if self.count == 1 or interval < self.min:
            self.min = interval
        if interval > self.max:
            self.max = interval
        self.jitter = max(self.jitter, abs(error))
        self.err = self.total_err
        self.avg_err = self.total_err / self.count


COMPONENT = Timedelta
