"""mux_generic: multiplexers of any size and type (``loadrt mux_generic config=bf8,ss4``).

Each config string makes one instance ``mux-gen.NN`` (at most 100): a number of inputs (2 to
1024) and one or two type letters, b f s u, for the inputs and the output (the output type
defaults to the input's). Pins: ``in-<type>-NN``, ``out-<type>``, ``sel-int`` (u32) and, for
sizes whose binary form is a 1 followed only by 0s past bit 0 (2, 3, 4, 5, 8, 9...),
``sel-bit-NN``; the selection is the sum of the bit value and ``sel-int`` (clamped to the
last input). ``suppress-no-input`` keeps the output while the selection is 0; a new
selection waits ``debounce-us`` microseconds. Types convert as LinuxCNC's: float to bit is
true beyond +-2e-7, float to s32 clamps to +-(2^31 - 1), to u32 to 0..2^32 - 1, s32 to u32
at 0, u32 to s32 at 2^31 - 1. Parameters ``elapsed`` and ``selected`` show the debounce.
"""

from __future__ import annotations

from typing import Any

from hal.api import make_accessor
from hal.components._cmath import to_s32
from hal.core import (
    HAL_BIT,
    HAL_FLOAT,
    HAL_IN,
    HAL_OUT,
    HAL_RO,
    HAL_S32,
    HAL_U32,
    TYPE_NAMES,
    HalError,
)

MAX_INSTANCES = 100
MAX_SIZE = 1024
EPSILON = 2e-7
S32_MAX, U32_MAX = 0x7FFFFFFF, 0xFFFFFFFF
_TYPES = {"b": HAL_BIT, "f": HAL_FLOAT, "s": HAL_S32, "u": HAL_U32}


def parse_config(text: str) -> tuple[int, int, int]:
    """(size, input type, output type) of a config string such as ``ff8``."""
    size, types = 0, []
    for char in text:
        if char.isdigit():
            size = min(size * 10 + int(char), MAX_SIZE)
        elif char.lower() in _TYPES:
            if len(types) == 2:
                raise HalError("mux_generic: too many type specifiers in fmt string")
            types.append(_TYPES[char.lower()])
        else:
            raise HalError("mux_generic: invalid character in fmt string")
    if size < 1:
        raise HalError("mux_generic: No entry count given")
    if size < 2:
        raise HalError("mux_generic: A one-element mux makes no sense")
    if not types:
        raise HalError("mux_generic: No type specifiers in fmt string")
    return size, types[0], types[-1]


def selection_bits(size: int) -> int:
    """How many sel-bit pins LinuxCNC makes for ``size`` inputs (its rule, quirks kept)."""
    bits, rest = 1, size >> 1
    while not rest & 1:
        rest >>= 1
        bits += 1
    return bits if rest == 1 else 0


def _convert(in_type: int, out_type: int, value: Any) -> Any:
    """An input value as the output type; None where LinuxCNC writes nothing."""
    if in_type == out_type:
        return value
    if in_type == HAL_FLOAT:
        if out_type == HAL_BIT:
            return value > EPSILON or value < -EPSILON
        if out_type == HAL_S32:
            return S32_MAX if value > S32_MAX else -S32_MAX if value < -S32_MAX else to_s32(value)
        return U32_MAX if value > U32_MAX else 0 if value < 0 else int(value)
    if out_type == HAL_FLOAT:
        return float(value)
    if in_type == HAL_BIT:
        return int(value)
    if out_type == HAL_BIT:
        return value != 0
    if in_type == HAL_S32:  # to u32
        return max(value, 0)
    return min(value, S32_MAX)  # u32 to s32


class MuxGeneric:
    """One ``mux-gen.NN`` instance."""

    def __init__(self, host: Any, comp: str, name: str, config: str) -> None:
        self.size, self.in_type, self.out_type = parse_config(config)
        hal = host.hal

        def new_pin(suffix: str, hal_type: int, direction: int) -> Any:
            slot = hal.new_pin(comp, f"{name}.{suffix}", hal_type, direction)
            return make_accessor(hal, hal_type, slot, is_pin=True)

        def new_param(suffix: str) -> Any:
            slot = hal.new_param(comp, f"{name}.{suffix}", HAL_U32, HAL_RO)
            return make_accessor(hal, HAL_U32, slot, is_pin=False)

        self.sel_bits = [
            new_pin(f"sel-bit-{i:02d}", HAL_BIT, HAL_IN) for i in range(selection_bits(self.size))
        ]
        self.sel_int = new_pin("sel-int", HAL_U32, HAL_IN)
        in_word, out_word = TYPE_NAMES[self.in_type], TYPE_NAMES[self.out_type]
        self.inputs = [
            new_pin(f"in-{in_word}-{i:02d}", self.in_type, HAL_IN) for i in range(self.size)
        ]
        self.suppress = new_pin("suppress-no-input", HAL_BIT, HAL_IN)
        self.debounce = new_pin("debounce-us", HAL_U32, HAL_IN)
        self.elapsed = new_param("elapsed")
        self.selected = new_param("selected")
        self.output = new_pin(f"out-{out_word}", self.out_type, HAL_OUT)
        has_fp = HAL_FLOAT in (self.in_type, self.out_type)
        host.add_function(comp, name, self.update, has_fp)

    def update(self, period: int) -> None:
        selection = sum(1 << i for i, pin in enumerate(self.sel_bits) if pin.__get__(None))
        selection += self.sel_int.__get__(None)
        if self.suppress.__get__(None) and selection == 0:
            return
        elapsed = self.elapsed.__get__(None)
        if selection != self.selected.__get__(None) and elapsed < self.debounce.__get__(None):
            self.elapsed.__set__(None, elapsed + period // 1000)
            return
        self.selected.__set__(None, selection)
        self.elapsed.__set__(None, 0)
        chosen = self.inputs[min(selection, self.size - 1)].__get__(None)
        value = _convert(self.in_type, self.out_type, chosen)
        if value is not None:
            self.output.__set__(None, value)


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    unknown = set(args) - {"config"}
    if unknown:
        raise HalError(f"mux_generic: unknown argument '{sorted(unknown)[0]}'")
    configs = [c for c in args.get("config", "").split(",") if c]
    if not configs:
        raise HalError("The mux_generic component requires at least one valid format string")
    if len(configs) > MAX_INSTANCES:
        raise HalError(f"mux_generic: at most {MAX_INSTANCES} config strings")
    for index, config in enumerate(configs):
        MuxGeneric(host, comp, f"mux-gen.{index:02d}", config)  # (its function keeps it)
