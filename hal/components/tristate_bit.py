"""tristate_bit: drive the I/O pin ``out`` with ``in`` only while ``enable`` is true (a
tristate buffer); otherwise something else may drive the signal."""

from hal.api import RtComponent, funct, pin


class TristateBit(RtComponent):
    in_ = pin("bit in")
    out = pin("bit io")
    enable = pin("bit in")

    @funct()
    def update(self, period: int) -> None:
        if self.enable:
            self.out = self.in_


COMPONENT = TristateBit
