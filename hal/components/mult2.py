"""mult2: ``out = in0 * in1``."""

from hal.api import RtComponent, funct, pin


class Mult2(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    out = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in0 * self.in1


COMPONENT = Mult2
