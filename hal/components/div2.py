"""div2: ``out = in0 / in1``; 0 when ``|in1|`` <= ``deadband`` (so a zero divisor is safe)."""

from hal.api import RtComponent, funct, param, pin


class Div2(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    out = pin("float out")
    deadband = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        divisor = self.in1
        if abs(divisor) <= self.deadband or divisor == 0.0:
            self.out = 0.0
        else:
            self.out = self.in0 / divisor


COMPONENT = Div2
