"""or2: two-input OR gate (``out = in0 or in1``)."""

from hal.api import RtComponent, funct, pin


class Or2(RtComponent):
    in0 = pin("bit in")
    in1 = pin("bit in")
    out = pin("bit out")

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        self.out = self.in0 or self.in1


COMPONENT = Or2
