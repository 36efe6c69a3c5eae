"""timedelay: ``out`` follows ``in`` after ``in`` held steady for on-delay / off-delay seconds."""

from hal.api import RtComponent, funct, pin


class Timedelay(RtComponent):
    in_ = pin("bit in")
    out = pin("bit out")
    on_delay = pin("float in", default=0.5)
    off_delay = pin("float in", default=0.5)
    elapsed = pin("float out")

    def setup(self) -> None:
        self.timer = 0.0

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        if value == self.out:
            self.timer = 0.0
            return
        self.timer += period * 1e-9
        self.elapsed = self.timer  # keeps the last count once out has followed
        if self.timer >= (self.on_delay if value else self.off_delay):
            self.out = value
            self.timer = 0.0


COMPONENT = Timedelay
