"""mux4: select one of four values by ``sel0`` (bit 0) and ``sel1`` (bit 1)."""

from hal.api import RtComponent, funct, pin


class Mux4(RtComponent):
    sel0 = pin("bit in")
    sel1 = pin("bit in")
    out = pin("float out")
    in_ = pin("float in", "in{}", count=4)

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in_[(2 if self.sel1 else 0) + (1 if self.sel0 else 0)]


COMPONENT = Mux4
