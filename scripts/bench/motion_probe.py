"""motion_probe: per-period timing of a servo thread, for ``motion_bench.py``.

    loadrt motion_probe                      # (CNC_HAL_COMPONENTS=scripts/bench)
    addf motion-probe.0.start servo-thread   # first on the thread
    addf motion-command-handler servo-thread
    addf motion-controller servo-thread
    addf motion-probe.0.end servo-thread     # right after the functions measured

Pins, written every period and meant to be recorded with ``cnc hal sample``:

- ``lateness``: ns between the period's deadline and the start of ``start``. The host's
  deadlines are multiples of the period on CLOCK_MONOTONIC and advance by one period, or
  jump to the next multiple after an overrun (hal/rtapi_app.py); the probe follows the
  host's ``<thread>.overruns`` counter to know which.
- ``cpu-ns`` / ``wall-ns``: this thread's CPU time and the wall time from the end of
  ``start`` to ``end``, i.e. spent in the functions between them (motion's command handler
  and controller: queueing moves, the planner, joints, publishing status).
"""

from __future__ import annotations

import time

from hal.api import RtComponent, funct, pin


class MotionProbe(RtComponent):
    prefix = "motion-probe"
    options = {"thread": str}
    lateness = pin("s32 out")
    cpu_ns = pin("s32 out")
    wall_ns = pin("s32 out")

    def setup(self, thread: str = "servo-thread") -> None:
        self.thread = thread
        self.deadline = 0  # of the current period; 0 before the first
        self.seen_overruns = 0
        self.cpu_mark = 0
        self.wall_mark = 0
        self.overruns_slot = -1  # of the host's <thread>.overruns, found on the first call

    @funct("start", has_fp=False)
    def start(self, period: int) -> None:
        now = time.monotonic_ns()
        hal = self.hal
        if self.overruns_slot < 0:
            self.overruns_slot = hal.meta["params"][f"{self.thread}.overruns"]["slot"]
        overruns = hal.q[self.overruns_slot]
        if self.deadline == 0 or overruns != self.seen_overruns:
            self.deadline = now - now % period  # the host moved to the next multiple
        else:
            self.deadline += period
        self.seen_overruns = overruns
        self.lateness = now - self.deadline
        self.cpu_mark = time.thread_time_ns()
        self.wall_mark = time.monotonic_ns()

    @funct("end", has_fp=False)
    def end(self, period: int) -> None:
        self.cpu_ns = time.thread_time_ns() - self.cpu_mark
        self.wall_ns = time.monotonic_ns() - self.wall_mark


COMPONENT = MotionProbe
