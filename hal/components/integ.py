"""integ: integrator, ``out += gain * in * dt`` limited to [min, max]; ``reset`` zeroes it."""

from hal.api import RtComponent, funct, pin


class Integ(RtComponent):
    in_ = pin("float in")
    gain = pin("float in", default=1.0)
    out = pin("float out")
    reset = pin("bit in")
    max = pin("float in", default=1e20)
    min = pin("float in", default=-1e20)

    @funct()
    def update(self, period: int) -> None:
        if self.reset:
            self.out = 0.0
            return
        value = self.out + self.in_ * self.gain * period * 1e-9
        self.out = min(max(value, self.min), self.max)


COMPONENT = Integ
