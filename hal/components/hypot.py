"""hypot: three-input hypotenuse, ``out = sqrt(in0² + in1² + in2²)``."""

import math

from hal.api import RtComponent, funct, pin


class Hypot(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    in2 = pin("float in")
    out = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        self.out = math.sqrt(self.in0**2 + self.in1**2 + self.in2**2)


COMPONENT = Hypot
