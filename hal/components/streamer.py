"""streamer: play rows from a shared-memory FIFO into pins, one row per period.

``loadrt streamer depth=D[,D2...] cfg=STRING[,...]`` makes one channel per cfg string with
an output pin ``streamer.N.pin.M`` per letter (f, b, s, u, l, k). ``cnc hal stream`` fills
the FIFO. Each call of ``streamer.N`` shows the rows waiting (``curr-depth``, ``empty``),
then takes one row while ``enable`` is true (only at the ``clock`` edges chosen by
``clock-mode`` when it is not 0); with nothing to take, ``underruns`` counts.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, funct, pin
from hal.components.sampler import Sampler
from hal.core import HAL_OUT
from hal.fifo import Fifo, parse_cfg


class Streamer(RtComponent):
    curr_depth = pin("s32 out")
    empty = pin("bit out", default=1)
    enable = pin("bit in", default=1)
    underruns = pin("s32 io")
    clock = pin("bit in")
    clock_mode = pin("s32 in")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        return Sampler.instances(module, args)  # the same arguments as sampler

    def setup(self, cfg: str = "f", depth: int = 1024) -> None:
        self.types = parse_cfg(cfg)
        self.slots = [
            self.hal.new_pin(self.comp, f"{self.name}.pin.{m}", hal_type, HAL_OUT)
            for m, hal_type in enumerate(self.types)
        ]
        self.fifo = Fifo.create(self.name, depth, self.types)
        self.clock_edge = 0  # the last two clock states, newest in bit 0

    def _is_clocked(self) -> bool:
        """clock-mode 0: every period; 1: falling, 2: rising, 3: any edge of ``clock``."""
        edge = self.clock_edge = ((self.clock_edge << 1) | self.clock) & 3
        if not self.enable:
            return False
        mode = self.clock_mode
        if mode == 1:
            return edge == 2
        if mode == 2:
            return edge == 1
        if mode == 3:
            return edge in (1, 2)
        return True

    def teardown(self) -> None:
        self.fifo.close()
        self.fifo.unlink()

    @funct()
    def update(self, period: int) -> None:
        is_clocked = self._is_clocked()  # (the clock edges are followed every period)
        fifo = self.fifo
        depth = fifo.count()
        self.curr_depth = depth
        self.empty = depth == 0
        if not is_clocked:
            return  # the outputs keep their values
        if depth == 0:
            self.underruns = self.underruns + 1
            return
        row = fifo.get()
        assert row is not None  # (one reader: nothing took the row since count())
        q, ptr = self.hal.q, self.hal.ptr
        for slot, word in zip(self.slots, row[1:], strict=True):
            q[ptr[slot]] = word


COMPONENT = Streamer
