"""streamer: play rows from a shared-memory FIFO into pins, one row per period.

``loadrt streamer depth=D[,D2...] cfg=STRING[,...]`` makes one channel per cfg string with
an output pin ``streamer.N.pin.M`` per letter (f, b, s, u, l, k). ``cnc hal stream`` fills
the FIFO. Each call of ``streamer.N`` takes one row while ``enable`` is true (only at the
``clock`` edges chosen by ``clock-mode`` when it is not 0); with nothing
to take, ``empty`` is set and, when ``enable`` is true, ``underruns`` counts.
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
        self.fifo = Fifo.create(self.name, depth, len(self.types))
        self.old_clock = False

    def _is_clocked(self) -> bool:
        """clock-mode 0: every period; 1: falling, 2: rising, 3: any edge of ``clock``."""
        clock, mode = self.clock, self.clock_mode
        was, self.old_clock = self.old_clock, clock
        if mode == 0:
            return True
        if clock == was:
            return False
        return mode == 3 or (mode == 2) == clock

    def teardown(self) -> None:
        self.fifo.close()
        self.fifo.unlink()

    @funct()
    def update(self, period: int) -> None:
        if not self.enable or not self._is_clocked():
            return
        row = self.fifo.get()
        if row is None:
            self.empty = True
            self.underruns = self.underruns + 1
            self.curr_depth = 0
            return
        q, ptr = self.hal.q, self.hal.ptr
        for slot, word in zip(self.slots, row[1:].tolist(), strict=True):
            q[ptr[slot]] = word
        self.empty = False
        self.curr_depth = self.fifo.count()


COMPONENT = Streamer
