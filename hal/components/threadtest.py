"""threadtest: a counter for testing threads: ``increment`` adds one to ``count``, ``reset``
sets it to 0 (add them to two threads to see how they interleave)."""

from hal.api import RtComponent, funct, pin


class ThreadTest(RtComponent):
    count = pin("u32 out")

    @funct("increment")
    def increment(self, period: int) -> None:
        self.count = self.count + 1

    @funct("reset")
    def reset(self, period: int) -> None:
        self.count = 0


COMPONENT = ThreadTest
