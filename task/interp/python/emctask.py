"""The ``emctask`` module of user Python code: there only in task (PY-024, PY-025).

``emcstat`` is task's status (EMC_STAT: ``emcstat.io.tool.toolInSpindle``,
``emcstat.io.aux.estop``, ``emcstat.motion.traj.position`` ...), as it stood at the last
synchronisation; ``operator_error``/``operator_text``/``operator_display`` send a message to
every user interface; ``ini_filename()`` is the machine's INI file. A preview interpreter
(a UI's, ``gcode``) has no such module: ``import emctask`` fails there, which code that
only makes sense on the machine can test.
"""

from __future__ import annotations

from collections.abc import Callable

emcstat = None  # task's EMC_STAT
_ini_filename = ""


def _no_operator(kind: str, text: str) -> None:
    """Before task binds the module: messages go nowhere."""


_operator: Callable[[str, str], object] = _no_operator


def bind(stat, ini_filename: str, operator: Callable[[str, str], object]) -> None:
    """Task gives its status, its INI file and its operator messages (kind "error",
    "text" or "display", text)."""
    global emcstat, _ini_filename, _operator
    emcstat = stat
    _ini_filename = ini_filename
    _operator = operator


def ini_filename() -> str:
    return _ini_filename


def operator_error(text: str, id: int = 0) -> None:
    _operator("error", str(text))


def operator_text(text: str, id: int = 0) -> None:
    _operator("text", str(text))


def operator_display(text: str, id: int = 0) -> None:
    _operator("display", str(text))
