"""not: inverter (``out = not in``)."""  # noqa: N999 - LinuxCNC's component name

from hal.api import RtComponent, funct, pin


class Not(RtComponent):
    in_ = pin("bit in")
    out = pin("bit out")

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        self.out = not self.in_


COMPONENT = Not
