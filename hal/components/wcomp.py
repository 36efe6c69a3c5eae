"""wcomp: window comparator; ``out`` when min < in < max, ``under``/``over`` at the edges."""

from hal.api import RtComponent, funct, pin


class Wcomp(RtComponent):
    in_ = pin("float in")
    min = pin("float in")
    max = pin("float in")
    out = pin("bit out")
    under = pin("bit out")
    over = pin("bit out")

    @funct()
    def update(self, period: int) -> None:
        value = self.in_
        self.under = value <= self.min
        self.over = value >= self.max
        self.out = self.min < value < self.max


COMPONENT = Wcomp
