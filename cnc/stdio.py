"""A closed pipe on stderr or stdout never kills a process of the machine.

``cnc run mill.ini 2>&1 | head -2``: once ``head`` exits, every write to the pipe fails with
EPIPE, in the launcher and in every process it started (they inherit it). A message that
cannot be shown must not stop a controller: ``protect_output()``, called first thing by
each process, makes the first failed write point the stream (and its file descriptor) at
/dev/null, so later writes, and Python's flush at exit, succeed.

``keep_lines_whole()`` (called by protect_output, by ``cnc`` for every subcommand and when
a program makes a HAL component) keeps each line whole where processes share a stream: with
PYTHONUNBUFFERED set, ``print`` writes its text and its newline in two calls, and another
process's line can land between them ("xhc-hb04: waiting for XHC-HB04 deviceFALSE").
Line buffering writes each printed line in one call, as promptly.
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Any, TextIO


class _QuietOnBrokenPipe:
    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except (OSError, ValueError):
            self._silence()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except (OSError, ValueError):
            self._silence()

    def _silence(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            fd = self._stream.fileno()
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, fd)  # (the exit-time flush of the original stream goes here too)
            os.close(null)
        self._stream = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def keep_lines_whole() -> None:
    """Line-buffer stdout and stderr where PYTHONUNBUFFERED (or -u) made them write through."""
    for stream in (sys.stdout, sys.stderr):
        if getattr(stream, "write_through", False):
            with contextlib.suppress(AttributeError, ValueError, OSError):
                stream.reconfigure(line_buffering=True, write_through=False)


def protect_output() -> None:
    keep_lines_whole()
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is not None and not isinstance(stream, _QuietOnBrokenPipe):
            setattr(sys, name, _QuietOnBrokenPipe(stream))
