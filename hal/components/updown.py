"""updown: count rising edges of ``countup`` and ``countdown``; a true ``reset`` sets 0.
``wrap`` jumps past ``max`` to ``min`` (and below ``min`` to ``max``); else ``clamp`` holds
the count within them."""

from hal.api import RtComponent, funct, param, pin


class UpDown(RtComponent):
    countup = pin("bit in")
    countdown = pin("bit in")
    reset = pin("bit in")
    count = pin("s32 out")
    clamp = param("bit rw")
    wrap = param("bit rw")
    max_ = param("s32 rw", default=0x7FFFFFFF)
    min_ = param("s32 rw")

    def setup(self) -> None:
        self.old_up = self.old_down = None  # the first call takes the inputs as they are

    @funct()
    def update(self, period: int) -> None:
        up, down = self.countup, self.countdown
        if self.old_up is None:
            self.old_up, self.old_down = up, down
        count = self.count
        if up and not self.old_up:
            count += 1
        if down and not self.old_down:
            count -= 1
        if self.reset:
            count = 0
        low, high = self.min_, self.max_
        if self.wrap:
            if count > high:
                count = low
            elif count < low:
                count = high
        elif self.clamp:
            if count > high:
                count = high
            elif count < low:
                count = low
        self.count = count
        self.old_up, self.old_down = up, down


COMPONENT = UpDown
