"""ddt: derivative, ``out = (in - previous in) / period`` (per second)."""

from hal.api import RtComponent, funct, pin


class Ddt(RtComponent):
    in_ = pin("float in")
    out = pin("float out")

    def setup(self) -> None:
        self.old = 0.0

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.out = (value - self.old) * 1e9 / period
        self.old = value


COMPONENT = Ddt
