"""select8: 8-way selector; ``outM`` is true when enabled and ``sel`` == M."""

from hal.api import RtComponent, funct, pin


class Select8(RtComponent):
    sel = pin("s32 in")
    out = pin("bit out", "out{}", count=8)
    enable = pin("bit in", default=1)

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        sel = self.sel if self.enable else -1
        out = self.out
        for i in range(8):
            out[i] = i == sel


COMPONENT = Select8
