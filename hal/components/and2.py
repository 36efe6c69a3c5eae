"""and2: two-input AND gate (``out = in0 and in1``)."""

from hal.api import RtComponent, funct, pin


class And2(RtComponent):
    in0 = pin("bit in")
    in1 = pin("bit in")
    out = pin("bit out")

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        self.out = self.in0 and self.in1


COMPONENT = And2
