"""div2: ``out = in0 / in1``, never dividing by less than ``deadband`` in magnitude.

With the divisor within ``deadband`` of zero (deadband is at least 1e-12), ``in0`` is
divided by ``-deadband`` (divisor just below zero) or ``+deadband`` (zero or just above), as
LinuxCNC 2.9 does, and a warning is printed once per such episode.
"""

import sys

from hal.api import RtComponent, funct, param, pin

SMALLEST_DEADBAND = 1e-12


class Div2(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    out = pin("float out")
    deadband = param("float rw")

    def setup(self) -> None:
        self.has_warned = False

    @funct()
    def update(self, period: int) -> None:
        dividend, divisor = self.in0, self.in1
        deadband = self.deadband
        if deadband < SMALLEST_DEADBAND:
            self.deadband = deadband = SMALLEST_DEADBAND
        if -deadband < divisor < 0:
            self.out = dividend / -deadband
            self._warn("-")
        elif 0 <= divisor < deadband:
            self.out = dividend / deadband
            self._warn("+")
        else:
            self.out = dividend / divisor
            self.has_warned = False

    def _warn(self, sign: str) -> None:
        if not self.has_warned:
            self.has_warned = True
            print(
                f"{self.name}: divisor too close to zero, dividing by {sign}deadband instead",
                file=sys.stderr,
            )


COMPONENT = Div2
