"""estop_latch: a software E-stop latch. It starts faulted (``ok-out`` false, ``fault-out``
true) and becomes OK on a rising edge of ``reset`` while ``ok-in`` is true and ``fault-in``
false; either of those failing faults it again. While OK, ``watchdog`` toggles every period.
"""

from hal.api import RtComponent, funct, pin


class EstopLatch(RtComponent):
    ok_in = pin("bit in", default=1)
    fault_in = pin("bit in")
    reset = pin("bit in")
    ok_out = pin("bit out")
    fault_out = pin("bit out", default=1)
    watchdog = pin("bit out")

    def setup(self) -> None:
        self.old_reset = False

    @funct()
    def update(self, period: int) -> None:
        reset = self.reset
        if self.ok_in and not self.fault_in:
            if reset and not self.old_reset:
                self.ok_out, self.fault_out = True, False
            if self.ok_out:
                self.watchdog = not self.watchdog
        else:
            self.ok_out, self.fault_out = False, True
        self.old_reset = reset


COMPONENT = EstopLatch
