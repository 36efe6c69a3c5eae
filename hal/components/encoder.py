"""encoder: software quadrature counter (``loadrt encoder num_chan=N`` or count=/names=).

``encoder.update-counters`` (no floating point, base thread) samples phase-A/B/Z each period
and counts every quadrature edge (``x4-mode``) or one count per cycle; in ``counter-mode``
phase-A is the count input and phase-B the direction. ``encoder.capture-position`` (servo
thread) publishes counts, position = counts / position-scale, velocity (units/s) and
velocity-rpm. A rising phase-Z while ``index-enable`` is set zeroes the count and clears
``index-enable``; ``reset`` zeroes it too. ``latch-input`` edges store counts-latched.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, module_funct, pin

# quadrature state (A, B) -> order on the cycle 00 -> 10 -> 11 -> 01
_ORDER = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}


class Encoder(RtComponent):
    counter_mode = pin("bit io")
    counts = pin("s32 out")
    counts_latched = pin("s32 out")
    index_enable = pin("bit io")
    latch_falling = pin("bit in", default=1)
    latch_input = pin("bit in")
    latch_rising = pin("bit in", default=1)
    min_speed_estimate = pin("float in", default=1.0)
    missing_teeth = pin("s32 in")
    phase_A = pin("bit in")
    phase_B = pin("bit in")
    phase_Z = pin("bit in")
    position = pin("float out")
    position_interpolated = pin("float out")
    position_latched = pin("float out")
    position_scale = pin("float io", default=1.0)
    rawcounts = pin("s32 out")
    reset = pin("bit in")
    velocity = pin("float out")
    velocity_rpm = pin("float out")
    x4_mode = pin("bit io", default=1)

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if "num_chan" in args:
            args = dict(args)
            args["count"] = args.pop("num_chan")
        return super().instances(module, args)

    def setup(self) -> None:
        self.raw = 0
        self.index_offset = 0
        self.state = 0
        self.old_z = False
        self.old_a = False
        self.old_latch = False
        self.old_counts = 0
        self.elapsed = 0.0
        self.has_index_request = False

    def count_edges(self) -> None:
        a, b, z = self.phase_A, self.phase_B, self.phase_Z
        if self.counter_mode:
            if a and not self.old_a:
                self.raw += -1 if b else 1
        else:
            state = _ORDER[(1 if a else 0, 1 if b else 0)]
            step = (state - self.state) % 4
            # x4 counts every edge; x1 only the edge that closes (or reopens) a cycle
            is_x4 = self.x4_mode
            if step == 1 and (is_x4 or state == 0):
                self.raw += 1
            elif step == 3 and (is_x4 or state == 3):
                self.raw -= 1
            self.state = state
        self.old_a = a
        if z and not self.old_z and self.index_enable:
            self.index_offset = self.raw
            self.index_enable = False
        self.old_z = z
        latch = self.latch_input
        if latch != self.old_latch and (self.latch_rising if latch else self.latch_falling):
            self.counts_latched = self._counts()
        self.old_latch = latch

    def _counts(self) -> int:
        return self.raw - self.index_offset

    def capture(self, period: int) -> None:
        if self.reset:
            self.index_offset = self.raw
        counts = self._counts()
        scale = self.position_scale or 1.0
        self.rawcounts = self.raw
        self.counts = counts
        self.position = counts / scale
        self.position_interpolated = counts / scale
        self.position_latched = self.counts_latched / scale
        self.elapsed += period * 1e-9
        delta = counts - self.old_counts
        if delta:
            self.velocity = delta / scale / self.elapsed
            self.elapsed = 0.0
        elif self.elapsed > 1.0 / max(self.min_speed_estimate, 1e-9) / abs(scale):
            self.velocity = 0.0
        self.velocity_rpm = self.velocity * 60.0
        self.old_counts = counts

    @module_funct("update-counters", fp=False)
    @classmethod
    def update_counters(cls, instances: list[Encoder], period: int) -> None:
        for inst in instances:
            inst.count_edges()

    @module_funct("capture-position")
    @classmethod
    def capture_position(cls, instances: list[Encoder], period: int) -> None:
        for inst in instances:
            inst.capture(period)


COMPONENT = Encoder
