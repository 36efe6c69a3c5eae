"""abs: absolute value and sign of a float."""

from hal.api import RtComponent, funct, pin

DEAD_ZONE = 1e-6


class Abs(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    sign = pin("bit out")
    is_positive = pin("bit out")  # in > 1e-6
    is_negative = pin("bit out")  # in < -1e-6

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.out = abs(value)
        self.sign = value < 0
        # a dead zone of 1e-6 around 0, as LinuxCNC's
        self.is_positive = value > DEAD_ZONE
        self.is_negative = value < -DEAD_ZONE


COMPONENT = Abs
