"""blend: mix two values, out = in0 * (1 - k) + in1 * k, with a counter."""

from hal.api import RtComponent, funct, param, pin


class Blend(RtComponent):
    in0 = pin("float in")  # pin blend.N.in0
    in1 = pin("float in")
    k = pin("float in", default=0.5)
    out = pin("float out")
    is_mixing = pin("bit out", "mixing")  # explicit HAL name
    gains = pin("float in", "gain-{}", count=3)  # blend.N.gain-0 .. gain-2
    runs = param("u32 ro")  # parameters: "TYPE ro" or "TYPE rw"

    def setup(self) -> None:
        self.last = 0.0  # private state: plain attributes

    @funct()  # the function is called blend.N
    def update(self, period: int) -> None:  # period of the thread, in ns
        k = self.k
        self.out = self.in0 * (1 - k) + self.in1 * k
        self.is_mixing = 0 < k < 1
        self.runs = self.runs + 1


COMPONENT = Blend
