"""C's conversions of a double to an integer, as LinuxCNC's components (compiled for x86)
make them: truncation toward zero, and the 'integer indefinite' value (the most negative
number) for NaN, infinities and values that do not fit."""

from __future__ import annotations

import math
import struct

S32_MIN, S32_MAX = -(1 << 31), (1 << 31) - 1
S64_MIN, S64_MAX = -(1 << 63), (1 << 63) - 1


def to_s32(value: float) -> int:
    """``(int)value``."""
    if not math.isfinite(value) or not S32_MIN - 1 < value < S32_MAX + 1:
        return S32_MIN
    return int(value)


def to_s64(value: float) -> int:
    """``(long long)value``."""
    if not math.isfinite(value) or not S64_MIN - 1 < value < S64_MAX + 1:
        return S64_MIN
    return int(value)


def wrap_s32(value: int) -> int:
    """An integer wrapped to 32 bits, signed (C's conversion to int32_t)."""
    return ((value + (1 << 31)) & 0xFFFFFFFF) - (1 << 31)


def c_div(a: int, b: int) -> int:
    """C's integer division: the quotient truncated toward zero."""
    quotient = abs(a) // abs(b)
    return quotient if (a < 0) == (b < 0) else -quotient


def c_mod(a: int, b: int) -> int:
    """C's ``a % b``: the remainder has the sign of ``a``."""
    return a - b * c_div(a, b)


_FLOAT = struct.Struct("f")


def to_f32(value: float) -> float:
    """A double stored in a C ``float`` (single precision), as some components keep state."""
    try:
        return _FLOAT.unpack(_FLOAT.pack(value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)
