"""Interpreter return codes and the error type (INTERP-005, INTERP-031)."""

from __future__ import annotations

INTERP_OK = 0
INTERP_EXIT = 1
INTERP_EXECUTE_FINISH = 2
INTERP_ENDFILE = 3
INTERP_FILE_NOT_OPEN = 4
INTERP_ERROR = 5
INTERP_MIN_ERROR = 3


class InterpError(Exception):
    """An interpreter error; ``str()`` is the message rs274 prints."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message
        # LinuxCNC's function stack of the error, innermost first (filled in only when the
        # interpreter records it: rs274 -s, see stack.py)
        self.stack: list[str] = []

    def __str__(self) -> str:
        return self.message
