"""sum2: ``out = in0 * gain0 + in1 * gain1 + offset``."""

from hal.api import RtComponent, funct, param, pin


class Sum2(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    out = pin("float out")
    gain0 = param("float rw", default=1.0)
    gain1 = param("float rw", default=1.0)
    offset = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in0 * self.gain0 + self.in1 * self.gain1 + self.offset


COMPONENT = Sum2
