"""bin2gray: a u32 number in Gray code (each step changes one bit)."""

from hal.api import RtComponent, funct, pin


class Bin2Gray(RtComponent):
    in_ = pin("u32 in")
    out = pin("u32 out")

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.out = value ^ (value >> 1)


COMPONENT = Bin2Gray
