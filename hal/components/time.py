"""time: a cycle timer in hours, minutes and seconds. A rising edge of ``start`` or ``pause``
(whichever makes the timer run) restarts it from 0; it counts while ``start`` is true and
``pause`` false, and holds while ``pause`` is true."""

from hal.api import RtComponent, funct, pin


class Time(RtComponent):
    start = pin("bit in")
    pause = pin("bit in")
    seconds = pin("u32 out")
    minutes = pin("u32 out")
    hours = pin("u32 out")

    def setup(self) -> None:
        self.total_ns = 0.0
        self.was_running = False

    @funct()
    def update(self, period: int) -> None:
        start, pause = self.start, self.pause
        is_running = start or pause
        if is_running and not self.was_running:
            self.total_ns = 0.0
        if start and not pause:
            self.total_ns += period
            total = int(self.total_ns * 1e-9) & 0xFFFFFFFF
            self.seconds = total % 60
            self.minutes = (total // 60) % 60
            self.hours = total // 3600
        self.was_running = is_running


COMPONENT = Time
