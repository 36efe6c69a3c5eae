"""mux8: select one of eight values: ``out`` follows ``in<N>`` with N = sel2 sel1 sel0 in
binary."""

from hal.api import RtComponent, funct, pin


class Mux8(RtComponent):
    sel0 = pin("bit in")
    sel1 = pin("bit in")
    sel2 = pin("bit in")
    out = pin("float out")
    in_ = pin("float in", "in{}", count=8)

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in_[(4 if self.sel2 else 0) + (2 if self.sel1 else 0) + self.sel0]


COMPONENT = Mux8
