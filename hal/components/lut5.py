"""lut5: any logic function of five inputs by look-up table: the inputs ``in-0`` (bit 0) to
``in-4`` (bit 4) make a number N, and ``out`` is bit N of ``function`` (0x80000000 is a
5-input and, 0xe a 2-input or, 0x6 a 2-input xor)."""

from hal.api import RtComponent, funct, param, pin


class Lut5(RtComponent):
    in_ = pin("bit in", "in-{}", count=5)
    out = pin("bit out")
    function = param("u32 rw")

    @funct()
    def update(self, period: int) -> None:
        ins = self.in_
        row = ins[0] + 2 * ins[1] + 4 * ins[2] + 8 * ins[3] + 16 * ins[4]
        self.out = (self.function >> row) & 1


COMPONENT = Lut5
