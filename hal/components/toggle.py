"""toggle: each (debounced) press on ``in`` flips ``out``; ``debounce`` is in periods."""

from hal.api import RtComponent, funct, param, pin


class Toggle(RtComponent):
    in_ = pin("bit in")
    out = pin("bit io")
    debounce = param("u32 rw", default=2)

    def setup(self) -> None:
        self.count = 0
        self.is_pressed = False

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        limit = self.debounce
        if not 1 <= limit <= 10000:  # keep a sane delay, as LinuxCNC does
            self.debounce = limit = 2
        if self.in_:
            self.count = min(self.count + 1, limit)
            if self.count >= limit and not self.is_pressed:
                self.is_pressed = True
                self.out = not self.out
        else:
            self.count = max(self.count - 1, 0)
            if self.count == 0:
                self.is_pressed = False


COMPONENT = Toggle
