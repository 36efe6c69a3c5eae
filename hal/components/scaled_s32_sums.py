"""scaled_s32_sums: the sum of four s32 inputs, each times its scale, as a float
(``out-f``) and truncated to s32 (``out-s``)."""

from hal.api import RtComponent, funct, pin
from hal.components._cmath import to_s32


class ScaledS32Sums(RtComponent):
    in_ = pin("s32 in", "in{}", count=4)
    scale = pin("float in", "scale{}", count=4, default=1.0)
    out_s = pin("s32 out")
    out_f = pin("float out")

    @funct()
    def update(self, period: int) -> None:
        ins, scales = self.in_, self.scale
        total = ins[0] * scales[0] + ins[1] * scales[1] + ins[2] * scales[2] + ins[3] * scales[3]
        self.out_f = total
        self.out_s = to_s32(total)


COMPONENT = ScaledS32Sums
