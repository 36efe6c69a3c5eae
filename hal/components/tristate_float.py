"""tristate_float: drive the I/O pin ``out`` with ``in`` only while ``enable`` is true."""

from hal.api import RtComponent, funct, pin


class TristateFloat(RtComponent):
    in_ = pin("float in")
    out = pin("float io")
    enable = pin("bit in")

    @funct()
    def update(self, period: int) -> None:
        if self.enable:
            self.out = self.in_


COMPONENT = TristateFloat
