"""broken: a test component whose function raises; the host must say so once, keep calling it
and not die."""

from hal.api import RtComponent, funct, pin


class Broken(RtComponent):
    calls = pin("s32 out")

    @funct()
    def update(self, period: int) -> None:
        self.calls = self.calls + 1
        raise RuntimeError("broken on purpose")


COMPONENT = Broken
