"""abs: absolute value and sign of a float."""

from hal.api import RtComponent, funct, pin


class Abs(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    sign = pin("bit out")
    is_positive = pin("bit out")
    is_negative = pin("bit out")

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.out = abs(value)
        self.sign = value < 0
        self.is_positive = value > 0
        self.is_negative = value < 0


COMPONENT = Abs
