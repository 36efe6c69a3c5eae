"""slow: a test component whose function takes 3 ms (it always overruns a 1 ms thread)."""

import time

from hal.api import RtComponent, funct, pin


class Slow(RtComponent):
    calls = pin("s32 out")

    @funct()
    def update(self, period: int) -> None:
        time.sleep(0.003)
        self.calls = self.calls + 1


COMPONENT = Slow
