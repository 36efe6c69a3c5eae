"""limit1: clamp ``in`` to [min, max]."""

from hal.api import RtComponent, funct, pin


class Limit1(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    min = pin("float in", default=-1e20)
    max = pin("float in", default=1e20)

    @funct()
    def update(self, period: int) -> None:
        self.out = min(max(self.in_, self.min), self.max)


COMPONENT = Limit1
