"""comp: comparator with hysteresis; ``out`` true when in1 > in0, ``equal`` within ±hyst/2."""

from hal.api import RtComponent, funct, param, pin


class Comp(RtComponent):
    in0 = pin("float in")
    in1 = pin("float in")
    out = pin("bit out")
    equal = pin("bit out")
    hyst = param("float rw")

    @funct()
    def update(self, period: int) -> None:
        half = 0.5 * self.hyst
        diff = self.in1 - self.in0
        if diff < -half:
            self.out, self.equal = False, False
        elif diff > half:
            self.out, self.equal = True, False
        else:  # inside the hysteresis band: out keeps its state
            self.equal = True


COMPONENT = Comp
