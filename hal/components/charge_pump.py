"""charge_pump: a square wave for the charge-pump input of controller boards (one instance,
``charge-pump``): ``out`` toggles every call while ``enable`` is true, ``out-2`` and
``out-4`` at a half and a quarter of its frequency; all low when disabled."""

from hal.api import RtComponent, funct, pin


class ChargePump(RtComponent):
    is_singleton = True
    out = pin("bit out")
    out_2 = pin("bit out")
    out_4 = pin("bit out")
    enable = pin("bit in", default=1)

    def setup(self) -> None:
        self.calls = 0

    @funct()
    def update(self, period: int) -> None:
        if self.enable:
            self.calls += 1
            calls = self.calls
            self.out, self.out_2, self.out_4 = calls & 1, calls & 2, calls & 4
        else:
            self.out = self.out_2 = self.out_4 = False


COMPONENT = ChargePump
