"""Constants and small helpers shared by the interpreter's modules."""

from __future__ import annotations

import math

TYPE_CHECKING = False  # typing.TYPE_CHECKING, without typing's import time (see canon.py)
if TYPE_CHECKING:
    from .block import Block

MM_PER_INCH = 25.4
INCH_PER_MM = 1.0 / 25.4
CENTER_ARC_RADIUS_TOLERANCE_INCH = 2 * 0.001 * math.sqrt(2)
CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * math.sqrt(2)
RADIUS_TOLERANCE_INCH = 0.00005
RADIUS_TOLERANCE_MM = RADIUS_TOLERANCE_INCH * MM_PER_INCH
SPIRAL_RELATIVE_TOLERANCE = 0.001
TINY = 1e-12
MAX_EMS = 4

UNITS_PER_MINUTE, INVERSE_TIME, UNITS_PER_REVOLUTION = 0, 1, 2
MODE_ABSOLUTE, MODE_INCREMENTAL = 0, 1
R_PLANE, OLD_Z = 0, 1
RIGHT, LEFT = 1, 2
CONSTANT_RPM, CONSTANT_SURFACE = 0, 1
NUM_SPINDLES_MAX = 8


def rotate(x: float, y: float, theta: float) -> tuple[float, float]:
    t = theta * (math.pi / 180.0)
    c, s = math.cos(t), math.sin(t)
    return x * c - y * s, x * s + y * c


def round_to_int(x: float) -> int:
    """nearbyint(): ties to even, like Python's round()."""
    return round(x)


def is_near_int(value: float) -> tuple[bool, int]:
    result = int(value + 0.5)
    return abs(result - value) < 0.0001, result


def axis_words(block: Block) -> list[float | None]:
    return [
        block.x_number if block.x_flag else None,
        block.y_number if block.y_flag else None,
        block.z_number if block.z_flag else None,
        block.a_number if block.a_flag else None,
        block.b_number if block.b_flag else None,
        block.c_number if block.c_flag else None,
        block.u_number if block.u_flag else None,
        block.v_number if block.v_flag else None,
        block.w_number if block.w_flag else None,
    ]


def wrapped_msg(value: float, axis: str) -> str:
    return f"Invalid absolute position {value:5.2f} for wrapped rotary axis {axis}"


def c_format(fmt: str, value: float) -> str:
    if fmt == "%lf":
        return f"{value:f}"
    return fmt % value
