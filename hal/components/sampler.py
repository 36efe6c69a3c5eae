"""sampler: copy pins into a shared-memory FIFO every period, for ``cnc hal sample``.

``loadrt sampler depth=D[,D2...] cfg=STRING[,STRING2...]`` makes one channel per cfg
string, with one input pin ``sampler.N.pin.M`` per letter (f float, b bit, s s32, u u32,
l s64, k u64). Each call of ``sampler.N`` stores one row when ``enable`` is true; a full
FIFO (``depth`` - 1 rows) drops the row and counts an overrun. ``sample-num`` is only
declared, as in LinuxCNC 2.9: rows are numbered by the FIFO.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, funct, pin
from hal.core import HAL_IN, HalError
from hal.fifo import Fifo, parse_cfg


class Sampler(RtComponent):
    curr_depth = pin("s32 out")
    full = pin("bit out")
    enable = pin("bit in", default=1)
    overruns = pin("s32 io")
    sample_num = pin("s32 io")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"depth", "cfg"} or "cfg" not in args:
            raise HalError(f"{module}: usage: loadrt {module} depth=N[,N...] cfg=STRING[,...]")
        cfgs = args["cfg"].split(",")
        depths = [int(d) for d in args.get("depth", "").split(",") if d] or [1024]
        depths += [depths[-1]] * (len(cfgs) - len(depths))
        return [
            (f"{module}.{i}", {"cfg": cfg, "depth": depth})
            for i, (cfg, depth) in enumerate(zip(cfgs, depths, strict=False))
        ]

    def setup(self, cfg: str = "f", depth: int = 1024) -> None:
        self.types = parse_cfg(cfg)
        self.slots = [
            self.hal.new_pin(self.comp, f"{self.name}.pin.{m}", hal_type, HAL_IN)
            for m, hal_type in enumerate(self.types)
        ]
        self.fifo = Fifo.create(self.name, depth, self.types)

    def teardown(self) -> None:
        self.fifo.close()
        self.fifo.unlink()

    @funct()
    def update(self, period: int) -> None:
        fifo = self.fifo
        if not self.enable:
            self.curr_depth = fifo.count()
            self.full = not fifo.is_writable()
            return
        q, ptr = self.hal.q, self.hal.ptr
        if fifo.put([q[ptr[slot]] for slot in self.slots]):
            self.full = False
            self.curr_depth = fifo.count()
        else:  # full: the row is lost
            self.overruns = self.overruns + 1
            self.full = True
            self.curr_depth = fifo.depth


COMPONENT = Sampler
