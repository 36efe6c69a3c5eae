"""bitslice: the bits of a u32 input on separate pins ``out-00`` ... (``personality`` pins
per instance, ``loadrt bitslice personality=8``); weighted_sum does the opposite."""

from hal.api import RtComponent, funct, pin


class Bitslice(RtComponent):
    has_personality = True
    in_ = pin("u32 in")
    out = pin("bit out", "out-{:02d}", count=lambda options: min(options["personality"], 32))

    def setup(self, personality: int = 0) -> None:
        self.width = min(personality, 32)

    @funct()
    def update(self, period: int) -> None:
        value, out = self.in_, self.out
        for bit in range(self.width):
            out[bit] = (value >> bit) & 1


COMPONENT = Bitslice
