"""xhc_hb04_util: helpers for the XHC-HB04 pendant. A press of ``start-or-pause`` sets
``run`` when idle, ``pause`` when running and ``resume`` when paused (for halui.program.*;
releasing it clears them). Four low-pass filters: ``outN`` follows ``inN`` by ``coefN``
(0 to 1) per period, times ``scaleN``, rounded; ``divide-by-k-out`` = in / ``k``."""

import math

from hal.api import RtComponent, funct, pin
from hal.components._cmath import to_s32


class XhcHb04Util(RtComponent):
    start_or_pause = pin("bit in")
    is_paused = pin("bit in")
    is_idle = pin("bit in")
    is_running = pin("bit in")
    pause = pin("bit out")
    resume = pin("bit out")
    run = pin("bit out")
    in_ = pin("s32 in", "in{}", count=4)
    out = pin("s32 out", "out{}", count=4)
    scale = pin("float in", "scale{}", count=4, default=1.0)
    coef = pin("float in", "coef{}", count=4, default=1.0)
    divide_by_k_in = pin("float in")
    divide_by_k_out = pin("float out")
    k = pin("float in", default=1.0)

    def setup(self) -> None:
        self.values = [0.0] * 4
        self.old_start_or_pause = False

    @funct()
    def update(self, period: int) -> None:
        k = self.k
        self.divide_by_k_out = 1e99 if k == 0 else self.divide_by_k_in / k
        ins, outs, scales, coefs, values = self.in_, self.out, self.scale, self.coef, self.values
        for i in range(4):
            values[i] += (ins[i] - values[i]) * min(abs(coefs[i]), 1.0)
            rounded = values[i] * scales[i] - 0.5
            outs[i] = to_s32(math.ceil(rounded) if math.isfinite(rounded) else rounded)
        pressed = self.start_or_pause
        if pressed == self.old_start_or_pause:
            return
        self.old_start_or_pause = pressed
        if not pressed:
            self.pause = self.run = self.resume = False
            return
        if self.is_paused:
            self.pause, self.run, self.resume = False, False, True
        if self.is_running:
            self.pause, self.run, self.resume = True, False, False
        if self.is_idle:
            self.pause, self.run, self.resume = False, True, False


COMPONENT = XhcHb04Util
