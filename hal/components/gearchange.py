"""gearchange: a spindle speed for one of two gear ranges. The speed's size is clamped to
``min1``..``max1`` in gear 1, or to ``min2``..``max2`` and divided by ``scale2`` (at least 1)
in gear 2 (``sel`` true), where ``reverse`` also flips the direction; the sign is kept."""

from hal.api import RtComponent, funct, param, pin


class GearChange(RtComponent):
    sel = pin("bit in")
    speed_in = pin("float in")
    speed_out = pin("float out")
    dir_in = pin("bit in")
    dir_out = pin("bit out")
    min1 = param("float rw")
    max1 = param("float rw", default=100000.0)
    min2 = param("float rw")
    max2 = param("float rw", default=100000.0)
    scale2 = param("float rw", default=1.0)
    reverse = param("bit rw")

    @funct()
    def update(self, period: int) -> None:
        if self.scale2 < 1:
            self.scale2 = 1.0
        speed = self.speed_in
        sign = -1.0 if speed < 0 else 1.0
        speed = abs(speed)
        is_second = self.sel
        low, high = (self.min2, self.max2) if is_second else (self.min1, self.max1)
        if speed < low:
            speed = low
        elif speed > high:
            speed = high
        if is_second:
            speed /= self.scale2
            self.dir_out = self.dir_in != self.reverse
        else:
            self.dir_out = self.dir_in
        self.speed_out = sign * speed


COMPONENT = GearChange
