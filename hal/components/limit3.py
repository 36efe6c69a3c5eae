"""limit3: clamp to [min, max], limit velocity to ``maxv`` and acceleration to ``maxa``.

The output moves towards ``in`` as fast as the limits allow and decelerates in time to stop
on it (a time-optimal profile in whole periods). ``load`` makes it follow ``in`` immediately;
with ``enable`` false the output returns to 0 within the same limits.
"""

import math

from hal.api import RtComponent, funct, pin


class Limit3(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    load = pin("bit in")
    enable = pin("bit in", default=1)
    min = pin("float in", default=-1e20)
    max = pin("float in", default=1e20)
    maxv = pin("float in", default=1e20)
    maxa = pin("float in", default=1e20)
    smooth_steps = pin("u32 in", default=2)

    def setup(self) -> None:
        self.pos = 0.0
        self.vel = 0.0

    @funct()
    def update(self, period: int) -> None:
        dt = period * 1e-9
        # disabled, the output returns to 0 within the limits
        target = min(max(self.in_ if self.enable else 0.0, self.min), self.max)
        if self.load:
            self.pos, self.vel = target, 0.0
            self.out = target
            return
        maxv, maxa = abs(self.maxv), abs(self.maxa)
        error = target - self.pos
        dv = maxa * dt
        # fastest speed from which braking by dv per period still stops on the target
        brake = dv * (math.sqrt(0.25 + 2 * abs(error) / (dv * dt)) - 0.5) if dv else 0.0
        wanted = math.copysign(min(brake, maxv, abs(error) / dt), error)
        vel = min(max(wanted, self.vel - dv), self.vel + dv)
        pos = self.pos + vel * dt
        if abs(target - pos) < 1e-12:
            pos = target
        self.pos = min(max(pos, self.min), self.max)
        self.vel = vel
        self.out = self.pos


COMPONENT = Limit3
