"""near: ``out`` when in1 and in2 are within a factor ``scale`` or ``difference`` of each other."""

from hal.api import RtComponent, funct, param, pin


class Near(RtComponent):
    in1 = pin("float in")
    in2 = pin("float in")
    out = pin("bit out")
    scale = param("float rw", default=1.0)
    difference = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        a, b, scale = self.in1, self.in2, self.scale
        if a < 0:  # compare magnitudes on the positive side
            a, b = -a, -b
        is_within_scale = scale > 1 and a / scale <= b <= a * scale
        self.out = is_within_scale or abs(a - b) <= self.difference


COMPONENT = Near
