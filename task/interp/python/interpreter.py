"""The ``interpreter`` module of user Python code (PY-022, PY-024).

Status codes, LinuxCNC's enumerations, ``InterpreterException`` (raised by ``self.execute()``
and ``self.read()`` when ``throw_exceptions`` is non-zero) and ``this``, the interpreter
running Python code now (``;py,print(this.call_level)``).
"""

from __future__ import annotations

from ..common import (
    CONSTANT_RPM,
    CONSTANT_SURFACE,
    INVERSE_TIME,
    LEFT,
    MODE_ABSOLUTE,
    MODE_INCREMENTAL,
    OLD_Z,
    R_PLANE,
    RIGHT,
    UNITS_PER_MINUTE,
    UNITS_PER_REVOLUTION,
)
from ..errors import (
    INTERP_ENDFILE,
    INTERP_ERROR,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_FILE_NOT_OPEN,
    INTERP_MIN_ERROR,
    INTERP_OK,
)

TOLERANCE_EQUAL = 0.0001
# non-zero: an error of self.execute() or self.read() raises InterpreterException (read when
# the error happens, so ``interpreter.throw_exceptions = 0`` takes effect at once)
throw_exceptions = 1
this = None  # the interpreter (its Python view) whose Python code runs


class InterpreterException(Exception):  # noqa: N818 (LinuxCNC's name)
    """An interpreter error met by ``self.execute()`` or ``self.read()``."""

    def __init__(self, error_message: str, line_number: int, line_text: str) -> None:
        super().__init__(error_message)
        self.error_message = error_message
        self.line_number = line_number
        self.line_text = line_text


def equal(a: float, b: float) -> bool:
    """The interpreter's equality of numbers."""
    return abs(a - b) < TOLERANCE_EQUAL


def is_near_int(value: float) -> bool:
    return abs(int(value + 0.5) - value) < 0.0001


def nearest_int(value: float) -> int:
    return int(value + 0.5)


__all__ = [
    "CONSTANT_RPM",
    "CONSTANT_SURFACE",
    "INTERP_ENDFILE",
    "INTERP_ERROR",
    "INTERP_EXECUTE_FINISH",
    "INTERP_EXIT",
    "INTERP_FILE_NOT_OPEN",
    "INTERP_MIN_ERROR",
    "INTERP_OK",
    "INVERSE_TIME",
    "LEFT",
    "MODE_ABSOLUTE",
    "MODE_INCREMENTAL",
    "OLD_Z",
    "RIGHT",
    "R_PLANE",
    "TOLERANCE_EQUAL",
    "UNITS_PER_MINUTE",
    "UNITS_PER_REVOLUTION",
    "InterpreterException",
    "equal",
    "is_near_int",
    "nearest_int",
    "this",
    "throw_exceptions",
]
