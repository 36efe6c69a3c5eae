"""flipflop: D flip-flop; ``out`` takes ``data`` on a rising ``clk``; ``set``/``reset`` win."""

from hal.api import RtComponent, funct, pin


class Flipflop(RtComponent):
    data = pin("bit in")
    clk = pin("bit in")
    set = pin("bit in")
    reset = pin("bit in")
    out = pin("bit io")
    out_not = pin("bit io")

    def setup(self) -> None:
        self.old_clk = False

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        clk = self.clk
        out = self.out
        if self.reset:
            out = False
        elif self.set:
            out = True
        elif clk and not self.old_clk:
            out = self.data
        self.old_clk = clk
        self.out = out
        self.out_not = not out


COMPONENT = Flipflop
