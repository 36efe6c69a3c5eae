"""lincurve: a one-dimensional lookup table. ``personality`` (2 to 16) points (``x-val-NN``,
``y-val-NN``), x ascending; ``out`` (and the I/O pin ``out-io``, for PID gains) follows
the straight line between the two points around ``in``, or the end point's y beyond the
table (no extrapolation)."""

from typing import Any

from hal.api import RtComponent, funct, param, pin

MAX_POINTS = 16


class LinCurve(RtComponent):
    has_personality = True
    x_val = param("float rw", "x-val-{:02d}", count="personality")
    y_val = param("float rw", "y-val-{:02d}", count="personality")
    in_ = pin("float in")
    out = pin("float out")
    out_io = pin("float io")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        wanted = super().instances(module, args)
        for _name, options in wanted:  # 2 to 16 points, whatever personality says
            options["personality"] = min(max(options["personality"], 2), MAX_POINTS)
        return wanted

    def setup(self, personality: int = 2) -> None:
        self.last = personality - 1
        self.segment = 0  # where the last search ended: inputs move little per period

    @funct()
    def update(self, period: int) -> None:
        x, xs, ys, last = self.in_, self.x_val, self.y_val, self.last
        if x >= xs[last]:
            value = ys[last]
        elif x <= xs[0]:
            value = ys[0]
        else:
            i = self.segment
            while x > xs[i + 1]:
                i += 1
            while x < xs[i]:
                i -= 1
            self.segment = i
            x0, y0 = xs[i], ys[i]
            value = y0 + (x - x0) / (xs[i + 1] - x0) * (ys[i + 1] - y0)
        self.out = value
        self.out_io = value


COMPONENT = LinCurve
