"""mux2: select one of two values (``out = in1 if sel else in0``)."""

from hal.api import RtComponent, funct, pin


class Mux2(RtComponent):
    sel = pin("bit in")
    out = pin("float out")
    in0 = pin("float in")
    in1 = pin("float in")

    @funct()
    def update(self, period: int) -> None:
        self.out = self.in1 if self.sel else self.in0


COMPONENT = Mux2
