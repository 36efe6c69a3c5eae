"""orient: the position command of a spindle orientation (M19) PID loop.

On a rising edge of ``enable`` it takes the spindle ``position`` (revolutions) and sets
``command`` to the nearest position at ``angle`` degrees past the index: the nearest either
way for ``mode`` 0, ahead (clockwise) for 1, behind for 2. While enabled, ``poserr`` is the
error in degrees, and ``is-oriented`` becomes true once the error has stayed within
``tolerance`` degrees for more than 100 periods (connect it to spindle.N.is-oriented).
"""

import math

from hal.api import RtComponent, funct, pin

SETTLE_PERIODS = 100


class Orient(RtComponent):
    enable = pin("bit in")
    mode = pin("s32 in")
    position = pin("float in")
    angle = pin("float in")
    command = pin("float out")
    poserr = pin("float out")
    is_oriented = pin("bit out")
    tolerance = pin("float in", default=0.5)

    def setup(self) -> None:
        self.was_enabled = False
        self.settled = 0  # periods within tolerance since the orientation started

    @funct()
    def update(self, period: int) -> None:
        self.is_oriented = False
        is_enabled = self.enable
        if is_enabled:
            position = self.position
            if not self.was_enabled:  # a new orientation: aim from where the spindle is
                self.settled = 0
                target = self.angle / 360.0
                mode = self.mode
                if mode == 0:
                    self.command = math.floor(position + 0.5 - target) + target
                elif mode == 1:
                    self.command = math.ceil(position - target) + target
                elif mode == 2:
                    self.command = math.floor(position - target) + target
            error = (position - self.command) * 360.0
            self.poserr = error
            if abs(error) < self.tolerance and self.settled <= SETTLE_PERIODS:
                self.settled += 1
            self.is_oriented = self.settled > SETTLE_PERIODS
        self.was_enabled = is_enabled


COMPONENT = Orient
