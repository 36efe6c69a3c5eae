"""debounce: filter noisy inputs; ``loadrt debounce cfg=N[,M...]`` makes groups of N pins.

Each period a counter per pin goes up while ``in`` is true and down while false; ``out``
becomes true on the period after it reached the group's ``delay``, false on the period
after it reached zero.
"""

from typing import Any

from hal.api import RtComponent, funct, param, pin
from hal.core import HalError


class Debounce(RtComponent):
    in_ = pin("bit in", "{}.in", count="size")
    out = pin("bit out", "{}.out", count="size")
    delay = param("s32 rw", default=5)

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"cfg"}:
            raise HalError("debounce: only cfg=N[,N...] is accepted")
        try:
            sizes = [int(n) for n in args.get("cfg", "1").split(",") if n]
        except ValueError:
            raise HalError("debounce: cfg must be numbers") from None
        return [(f"debounce.{g}", {"size": size}) for g, size in enumerate(sizes)]

    def setup(self, size: int = 1) -> None:
        self.counts = [0] * size

    @funct(has_fp=False)
    def update(self, period: int) -> None:
        if self.delay < 0:
            self.delay = 1
        delay = self.delay
        ins, outs, counts = self.in_, self.out, self.counts
        for i in range(len(counts)):
            # the output changes on the call after the counter reached its end
            if ins[i]:
                if counts[i] < delay:
                    counts[i] += 1
                else:
                    outs[i] = True
            elif counts[i] > 0:
                counts[i] -= 1
            else:
                outs[i] = False


COMPONENT = Debounce
