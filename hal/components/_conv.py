"""The conv_<from>_<to> family: type conversion, with ``out-of-range`` and ``clamp`` where the
value may not fit (out-of-range values are clamped when ``clamp`` is true, else wrapped)."""

from __future__ import annotations

from hal.api import RtComponent, funct, param, pin

_RANGES = {"bit": (0, 1), "s32": (-(1 << 31), (1 << 31) - 1), "u32": (0, (1 << 32) - 1)}


def make(source: str, target: str) -> type[RtComponent]:
    """The component class converting ``source`` values to ``target``."""
    low, high = _RANGES.get(target, (None, None))
    src_low, src_high = _RANGES.get(source, (float("-inf"), float("inf")))
    can_overflow = low is not None and (src_low < low or src_high > high)
    has_fp = "float" in (source, target)
    attrs: dict[str, object] = {
        "in_": pin(f"{source} in"),
        "out": pin(f"{target} out"),
    }
    if can_overflow:
        attrs["out_of_range"] = pin("bit out")
        attrs["clamp"] = param("bit rw")

        def update(self: RtComponent, period: int) -> None:
            value = self.in_
            if value < low or value > high:
                self.out_of_range = True
                if self.clamp:
                    self.out = low if value < low else high
                else:
                    self.out = int(value) if target != "bit" else value != 0
            else:
                self.out_of_range = False
                self.out = int(value)

    else:
        convert = float if target == "float" else int

        def update(self: RtComponent, period: int) -> None:
            self.out = convert(self.in_)

    attrs["update"] = funct(has_fp=has_fp)(update)
    return type(f"Conv_{source}_{target}", (RtComponent,), attrs)
