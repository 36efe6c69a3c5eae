"""lowpass: first-order filter, ``out += (in - out) * gain``; ``load`` copies in to out."""

from hal.api import RtComponent, funct, param, pin


class Lowpass(RtComponent):
    in_ = pin("float in")
    out = pin("float out")
    load = pin("bit in")
    gain = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        if self.load:
            self.out = self.in_
        else:
            out = self.out
            self.out = out + (self.in_ - out) * self.gain


COMPONENT = Lowpass
