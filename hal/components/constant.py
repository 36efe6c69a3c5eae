"""constant: an output pin holding the value of the parameter ``value``."""

from hal.api import RtComponent, funct, param, pin


class Constant(RtComponent):
    out = pin("float out")
    value = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        self.out = self.value


COMPONENT = Constant
