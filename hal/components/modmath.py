"""modmath: modulo direction finders (``loadrt modmath mod_dir=N``), e.g. for a tool
carousel: with positions ``min-num`` to ``max-num`` (default 0 to 15), ``up`` or ``down``
tells which way from ``actual`` to ``desired`` is shorter (round the end when ``wrap``,
the default), ``on-target`` that they are equal. Functions ``mod-dir.N``."""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, funct, pin
from hal.components._cmath import c_div, c_mod
from hal.core import HalError


class ModDir(RtComponent):
    up = pin("bit out")
    down = pin("bit out")
    on_target = pin("bit out", default=1)
    actual = pin("s32 in")
    desired = pin("s32 in")
    min_num = pin("s32 io")
    max_num = pin("s32 io", default=15)
    wrap = pin("bit io", default=1)

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"mod_dir"}:
            raise HalError(f"{module}: unknown argument '{sorted(set(args) - {'mod_dir'})[0]}'")
        try:
            count = int(args.get("mod_dir", "0"), 0)
        except ValueError:
            raise HalError(f"{module}: mod_dir must be a number") from None
        return [(f"mod-dir.{i}", {}) for i in range(max(count, 0))]

    @funct()
    def update(self, period: int) -> None:
        low, high = self.min_num, self.max_num
        span = high - low + 1
        actual, desired = self.actual, self.desired
        if not low <= actual <= high:
            actual = low + c_mod(actual - low, span)
        if not low <= desired <= high:
            desired = low + c_mod(desired - low, span)
        to_go = desired - actual
        if self.wrap:
            half = c_div(span, 2)
            if to_go > half:
                to_go -= span
            if to_go < -half:
                to_go += span
        self.up = to_go > 0
        self.down = to_go < 0
        self.on_target = to_go == 0


COMPONENT = ModDir
