"""dbounce: debounce with a ``delay`` pin per instance (count=/names=, unlike debounce's
groups): a counter climbs while ``in`` is true and falls while it is false; ``out`` becomes
true when the input stays true once the counter is at ``delay``, false once it is at 0."""

from hal.api import RtComponent, funct, pin


class Dbounce(RtComponent):
    in_ = pin("bit in")
    out = pin("bit out")
    delay = pin("u32 in", default=5)

    def setup(self) -> None:
        self.state = 0

    @funct()
    def update(self, period: int) -> None:
        if self.in_:
            if self.state < self.delay:
                self.state += 1
            else:
                self.out = True
        elif self.state > 0:
            self.state -= 1
        else:
            self.out = False


COMPONENT = Dbounce
