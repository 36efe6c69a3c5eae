"""limit2: clamp to [min, max] and limit the rate of change to ``maxv`` per second.

While ``load`` is true, ``out`` follows ``in`` (clamped) without the rate limit.
"""

from hal.api import RtComponent, funct, pin


class Limit2(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    load = pin("bit in")
    min = pin("float in", default=-1e20)
    max = pin("float in", default=1e20)
    maxv = pin("float in", default=1e20)

    def setup(self) -> None:
        self.old = 0.0

    @funct()
    def update(self, period: int) -> None:
        target = min(max(self.in_, self.min), self.max)
        if not self.load:
            step = self.maxv * period * 1e-9
            target = min(max(target, self.old - step), self.old + step)
        self.old = target
        self.out = target


COMPONENT = Limit2
