"""oneshot: an output pulse of ``width`` seconds when the input changes (rising/falling)."""

from hal.api import RtComponent, funct, param, pin


class Oneshot(RtComponent):
    in_ = pin("bit in")
    reset = pin("bit in")
    out = pin("bit out")
    out_not = pin("bit out")
    width = pin("float in")
    time_left = pin("float out")
    retriggerable = param("bit rw", default=1)
    rising = param("bit rw", default=1)
    falling = param("bit rw")

    def setup(self) -> None:
        self.timer = 0.0
        self.old_in = False

    @funct()
    def update(self, period: int) -> None:
        if self.reset:
            self.timer, self.old_in = 0.0, False
            self.out, self.out_not = False, True
            return
        value, old = self.in_, self.old_in
        is_trigger = (value and not old and self.rising) or (old and not value and self.falling)
        self.old_in = value
        if self.timer > 0.0:  # a pulse is running
            if not self.retriggerable:
                is_trigger = False
            self.timer = max(self.timer - period * 1e-9, 0.0)
        if is_trigger:
            self.timer = self.width
        self.time_left = self.timer
        self.out = self.timer > 0.0
        self.out_not = self.timer <= 0.0


COMPONENT = Oneshot
