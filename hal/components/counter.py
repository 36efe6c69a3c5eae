"""counter: counts rising edges of ``phase-A`` (a pulse counter, the simple cousin of
encoder; ``loadrt counter num_chan=N``, 1 to 8, no names).

``counter.update-counters`` (fast thread) counts and, once ``index-enable`` has been seen
true by the capture, takes a rising ``phase-Z`` as the new zero and clears
``index-enable``. ``counter.capture-position`` (servo thread) gives ``counts`` from that
zero, ``position`` = counts / ``position-scale`` and ``velocity`` in position units per
second; ``reset`` zeroes everything.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, module_funct, pin
from hal.components._cmath import wrap_s32
from hal.core import HalError

MAX_CHANNELS = 8


class Counter(RtComponent):
    phase_A = pin("bit in", "phase-A")
    phase_Z = pin("bit in", "phase-Z")
    index_enable = pin("bit io")
    reset = pin("bit in")
    rawcounts = pin("s32 out")
    counts = pin("s32 out")
    position = pin("float out")
    velocity = pin("float out")
    position_scale = pin("float io", default=1.0)

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"num_chan"}:
            raise HalError(f"{module}: unknown argument '{sorted(set(args) - {'num_chan'})[0]}'")
        try:
            count = int(args.get("num_chan", "1"), 0)
        except ValueError:
            raise HalError(f"{module}: num_chan must be a number") from None
        if not 0 < count <= MAX_CHANNELS:
            raise HalError(f"COUNTER: ERROR: invalid num_chan: {count}")
        return [(f"counter.{i}", {}) for i in range(count)]

    def setup(self) -> None:
        self.old_a = self.old_z = False
        self.is_index_armed = False
        self.last_count = self.last_index_count = 0
        self.old_scale = self.scale = 1.0

    @module_funct("update-counters", has_fp=False)
    @classmethod
    def update_counters(cls, instances: list[Counter], period: int) -> None:
        for cntr in instances:
            a = cntr.phase_A
            if a and not cntr.old_a:
                cntr.rawcounts = cntr.rawcounts + 1
            cntr.old_a = a
            z = cntr.phase_Z
            if cntr.is_index_armed and z and not cntr.old_z:
                cntr.last_index_count = cntr.rawcounts
                cntr.index_enable = False
            cntr.old_z = z

    @module_funct("capture-position")
    @classmethod
    def capture_position(cls, instances: list[Counter], period: int) -> None:
        for cntr in instances:
            if cntr.reset:
                cntr.rawcounts = 0
                cntr.last_index_count = cntr.last_count = 0
            raw = cntr.rawcounts
            counts = wrap_s32(raw - cntr.last_index_count)
            cntr.counts = counts
            moved = wrap_s32(raw - cntr.last_count)
            cntr.last_count = raw
            scale = cntr.position_scale
            if scale != cntr.old_scale:
                cntr.old_scale = scale
                if -1e-20 < scale < 1e-20:
                    scale = cntr.position_scale = 1.0
                cntr.scale = 1.0 / scale
            cntr.position = counts * cntr.scale
            cntr.velocity = moved * cntr.scale * 1e9 / period
            cntr.is_index_armed = cntr.index_enable


COMPONENT = Counter
