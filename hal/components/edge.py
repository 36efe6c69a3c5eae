"""edge: a pulse on ``out`` (and a low pulse on ``out-invert``) at the chosen input edges.

``both`` selects both edges; otherwise ``in-edge`` true means falling, false rising.
The pulse lasts ``out-width-ns`` (at least one period).
"""

from hal.api import RtComponent, funct, param, pin


class Edge(RtComponent):
    in_ = pin("bit in")
    out = pin("bit out")
    out_invert = pin("bit out")
    both = param("bit rw")
    in_edge = param("bit rw", default=1)
    out_width_ns = param("s32 rw")
    time_left_ns = param("s32 ro")
    last_in = param("bit ro")

    def setup(self) -> None:
        self.is_first = True

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        value = self.in_
        left = self.time_left_ns
        if left > 0:
            left -= period
            self.time_left_ns = left
        if self.is_first:  # the first call only learns the input
            self.is_first = False
        else:
            last = self.last_in
            is_rise, is_fall = value and not last, last and not value
            is_edge = (is_rise or is_fall) if self.both else (is_fall if self.in_edge else is_rise)
            if is_edge:
                self.time_left_ns = self.out_width_ns
                self.out = True
            elif left > 0:
                self.out = True
            else:
                self.time_left_ns = 0
                self.out = False
        self.last_in = value
        self.out_invert = not self.out


COMPONENT = Edge
