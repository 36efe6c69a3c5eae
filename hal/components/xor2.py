"""xor2: two-input exclusive OR (``out`` is true when exactly one input is true)."""

from hal.api import RtComponent, funct, pin


class Xor2(RtComponent):
    in0 = pin("bit in")
    in1 = pin("bit in")
    out = pin("bit out")

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        self.out = self.in0 != self.in1


COMPONENT = Xor2
