"""biquad: a biquad IIR filter, H(z) = (n0 + n1 z^-1 + n2 z^-2) / (1 + d1 z^-1 + d2 z^-2),
in transposed direct form II (states ``s1``, ``s2``).

The coefficients are computed when ``enable`` rises: for ``type`` 1 a low-pass, for 2 a
notch at ``f0`` Hz with quality ``Q`` (``valid`` stays false unless 0.5 <= Q <= 2 and f0 is
at most half the sample rate); for ``type`` 0 the parameters n0..d2 are used as set. While
disabled or not valid, ``out`` is ``in``.
"""

import math

from hal.api import RtComponent, funct, param, pin

LINUXCNC_PI = 3.141592653589  # the value biquad uses
DIRECT, LOW_PASS, NOTCH = 0, 1, 2


class Biquad(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    enable = pin("bit in")
    valid = pin("bit out")
    type_ = pin("u32 in")
    f0 = pin("float in", default=250.0)
    Q = pin("float in", default=0.7071)
    d1 = param("float rw")
    d2 = param("float rw")
    n0 = param("float rw", default=1.0)
    n1 = param("float rw")
    n2 = param("float rw")
    s1 = pin("float out")
    s2 = pin("float out")

    def setup(self) -> None:
        self.was_enabled = False

    def _design(self, period: int) -> None:
        """The coefficients of the filter ``type`` asks for; ``valid`` says if it worked."""
        kind = self.type_
        if kind == DIRECT:
            self.valid = True
            return
        self.valid = False
        rate = 1.0 / (period * 1e-9)
        f0, q = self.f0, self.Q
        if f0 > rate / 2.0 or q > 2.0 or q < 0.5 or kind not in (LOW_PASS, NOTCH):
            return
        w0 = 2.0 * LINUXCNC_PI * f0 / rate
        alpha = math.sin(w0) / (2.0 * q)
        cosine = math.cos(w0)
        if kind == LOW_PASS:
            b0, b1, b2 = (1.0 - cosine) / 2.0, 1.0 - cosine, (1.0 - cosine) / 2.0
        else:
            b0, b1, b2 = 1.0, -2.0 * cosine, 1.0
        a0, a1, a2 = 1.0 + alpha, -2.0 * cosine, 1.0 - alpha
        self.n0, self.n1, self.n2 = b0 / a0, b1 / a0, b2 / a0
        self.d1, self.d2 = a1 / a0, a2 / a0
        self.s1 = self.s2 = 0.0
        self.valid = True

    @funct()
    def update(self, period: int) -> None:
        is_enabled = self.enable
        if is_enabled != self.was_enabled:
            self.was_enabled = is_enabled
            if is_enabled:
                self._design(period)
        value = self.in_
        if not is_enabled or not self.valid:
            self.out = value
            return
        out = value * self.n0 + self.s1
        self.out = out
        self.s1 = value * self.n1 - out * self.d1 + self.s2
        self.s2 = value * self.n2 - out * self.d2


COMPONENT = Biquad
