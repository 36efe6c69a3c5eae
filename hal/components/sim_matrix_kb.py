"""sim_matrix_kb: simulated 8x8 key matrix for panelui: the bit inputs
``button.cCC.rRR`` become key codes on ``out``: at the first input (rows first) that
changed, row * 8 + column plus 0xC0 when pressed or 0x80 when released; with no change,
0x40 while any key is down, 0 when all are up."""

from hal.api import RtComponent, funct, pin

KEY_DOWN, KEY_UP, NO_CHANGE = 0xC0, 0x80, 0x40


class SimMatrixKb(RtComponent):
    out = pin("u32 out")
    c00 = pin("bit in", "button.c00.r{:02d}", count=8)
    c01 = pin("bit in", "button.c01.r{:02d}", count=8)
    c02 = pin("bit in", "button.c02.r{:02d}", count=8)
    c03 = pin("bit in", "button.c03.r{:02d}", count=8)
    c04 = pin("bit in", "button.c04.r{:02d}", count=8)
    c05 = pin("bit in", "button.c05.r{:02d}", count=8)
    c06 = pin("bit in", "button.c06.r{:02d}", count=8)
    c07 = pin("bit in", "button.c07.r{:02d}", count=8)

    def setup(self) -> None:
        self.last = [False] * 64

    @funct()
    def update(self, period: int) -> None:
        is_any_down = False
        columns = (self.c00, self.c01, self.c02, self.c03, self.c04, self.c05, self.c06, self.c07)
        for row in range(8):
            for col in range(8):
                is_down = columns[col][row]
                is_any_down = is_any_down or is_down
                code = row * 8 + col
                if is_down != self.last[code]:
                    self.last[code] = is_down
                    self.out = code | (KEY_DOWN if is_down else KEY_UP)
                    return
        self.out = NO_CHANGE if is_any_down else 0


COMPONENT = SimMatrixKb
