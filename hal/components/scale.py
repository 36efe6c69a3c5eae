"""scale: ``out = in * gain + offset``."""

from hal.api import RtComponent, funct, pin


class Scale(RtComponent):
    in_ = pin("float in")
    gain = pin("float in")
    offset = pin("float in")
    out = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in_ * self.gain + self.offset


COMPONENT = Scale
