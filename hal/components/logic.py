"""logic: and, or, xor, nand and nor of up to 16 inputs, chosen per instance by
``personality``: the low byte is the number of inputs ``in-00``...; 0x100 adds ``and``,
0x200 ``or``, 0x400 ``xor`` (true for an odd number of true inputs), 0x800 ``nand``,
0x1000 ``nor`` (``loadrt logic count=1 personality=0x202`` is a 2-input or)."""

from hal.api import RtComponent, funct, pin, sized

AND, OR, XOR, NAND, NOR = 0x100, 0x200, 0x400, 0x800, 0x1000


def _has(flag: int):
    return lambda options: options["personality"] & flag


class Logic(RtComponent):
    has_personality = True
    in_ = pin("bit in", "in-{:02d}", count=sized(16, lambda o: o["personality"] & 0xFF))
    and_ = pin("bit out", when=_has(AND))
    or_ = pin("bit out", when=_has(OR))
    xor = pin("bit out", when=_has(XOR))
    nand = pin("bit out", when=_has(NAND))
    nor = pin("bit out", when=_has(NOR))

    def setup(self, personality: int = 0) -> None:
        self.personality = personality
        self.inputs = personality & 0xFF

    @funct()
    def update(self, period: int) -> None:
        ins = self.in_
        count = sum(1 for i in range(self.inputs) if ins[i])
        is_all, is_any = count == self.inputs, count > 0
        flags = self.personality
        if flags & AND:
            self.and_ = is_all
        if flags & OR:
            self.or_ = is_any
        if flags & XOR:
            self.xor = count & 1
        if flags & NAND:
            self.nand = not is_all
        if flags & NOR:
            self.nor = not is_any


COMPONENT = Logic
