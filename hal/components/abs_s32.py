"""abs_s32: the absolute value and sign of an s32 input (``out`` of -2^31 wraps to -2^31,
as in C)."""

from hal.api import RtComponent, funct, pin


class AbsS32(RtComponent):
    in_ = pin("s32 in")
    out = pin("s32 out")
    sign = pin("bit out")  # true for a negative input
    is_positive = pin("bit out")
    is_negative = pin("bit out")

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.sign = value < 0
        self.out = -value if value < 0 else value
        self.is_positive = value > 0
        self.is_negative = value < 0


COMPONENT = AbsS32
