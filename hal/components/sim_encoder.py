"""sim_encoder: simulated quadrature encoder (``loadrt sim_encoder num_chan=N``).

``sim-encoder.update-speed`` (servo thread) turns ``speed`` / ``scale`` revolutions per
second into 4 * ``ppr`` quadrature steps per revolution, at most one step per call of
``sim-encoder.make-pulses`` (base thread). That function adds the rate to a 32-bit phase
accumulator and steps the outputs each time it wraps half-way: the cycle is A, AB, B, none
(A alone at rest), ``rawcounts`` counts the steps, and phase-Z is high at the start of each
revolution.
"""

from __future__ import annotations

from hal.api import RtComponent, module_funct, pin

# quadrature step -> (phase-A, phase-B)
_PHASES = ((True, False), (True, True), (False, True), (False, False))
HALF_TURN = 1 << 31  # the accumulator steps the outputs each time it crosses 0 or 2**31
DEFAULT_BASE_NS = 50_000  # until make-pulses has run and told us its period


def _wrap32(value: int) -> int:
    return (value + HALF_TURN) % (1 << 32) - HALF_TURN


class SimEncoder(RtComponent):
    count_option = "num_chan"
    max_count = 8
    phase_A = pin("bit out")
    phase_B = pin("bit out")
    phase_Z = pin("bit out")
    ppr = pin("u32 io", default=100)
    rawcounts = pin("s32 in")
    scale = pin("float io", default=1.0)
    speed = pin("float in")

    def setup(self) -> None:
        self.accum = 0
        self.addval = 0
        self.step = 0  # place in the quadrature cycle, 0..3
        self.cycle = 0  # quadrature cycle within the revolution, 0..ppr-1
        self.base_ns = DEFAULT_BASE_NS

    def pulses(self, period: int) -> None:
        self.base_ns = period
        before = self.accum
        self.accum = _wrap32(before + self.addval)
        if (before < 0) != (self.accum < 0):
            ppr = max(self.ppr, 1)
            if self.addval < 0:
                self.rawcounts = self.rawcounts - 1
                self.step -= 1
                if self.step < 0:
                    self.step = 3
                    self.cycle = (self.cycle - 1) % ppr
            else:
                self.rawcounts = self.rawcounts + 1
                self.step += 1
                if self.step > 3:
                    self.step = 0
                    self.cycle = (self.cycle + 1) % ppr
        self.phase_A, self.phase_B = _PHASES[self.step]
        self.phase_Z = self.step == 0 and self.cycle == 0

    def update(self) -> None:
        base_s = self.base_ns * 1e-9
        max_rate = 1.0 / base_s  # one quadrature step per make-pulses call
        scale = self.scale
        if -1e-20 < scale < 1e-20:
            self.scale = scale = 1.0
        rate = self.speed / scale * self.ppr * 4.0
        rate = min(max(rate, -max_rate), max_rate)
        self.addval = int(rate * HALF_TURN * base_s)

    @module_funct("make-pulses", has_fp=False)
    @classmethod
    def make_pulses(cls, instances: list[SimEncoder], period: int) -> None:
        for inst in instances:
            inst.pulses(period)

    @module_funct("update-speed")
    @classmethod
    def update_speed(cls, instances: list[SimEncoder], period: int) -> None:
        for inst in instances:
            inst.update()


COMPONENT = SimEncoder
