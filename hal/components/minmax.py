"""minmax: the smallest and largest value ``in`` has had since ``reset`` (while ``reset``
is true both follow ``in``)."""

from hal.api import RtComponent, funct, pin


class MinMax(RtComponent):
    in_ = pin("float in")
    reset = pin("bit in")
    max_ = pin("float out")
    min_ = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        if self.reset:
            self.max_ = self.min_ = value
            return
        if value > self.max_:
            self.max_ = value
        if value < self.min_:
            self.min_ = value


COMPONENT = MinMax
