"""ilowpass: a low-pass filter for integers, made to smooth MPG jog counts: each period the
internal value moves ``gain`` of the way to ``in``, and ``out`` is that value times
``scale``, rounded (divide the jog scale by ``scale``)."""

import math

from hal.api import RtComponent, funct, param, pin
from hal.components._cmath import to_s64, wrap_s32


class ILowpass(RtComponent):
    in_ = pin("s32 in")
    out = pin("s32 out")
    scale = param("float rw", default=1024.0)
    gain = param("float rw", default=0.5)

    def setup(self) -> None:
        self.value = 0.0

    @funct()
    def update(self, period: int) -> None:
        self.value += (self.in_ - self.value) * self.gain
        self.out = wrap_s32(to_s64(math.floor(self.value * self.scale + 0.5)))


COMPONENT = ILowpass
