"""One way to receive commands, for every process that takes them (task, motion,
iocontrol, the web server, halui).

A receiver marks each handler with ``@handler(KEY, ...)`` (a message class, or a name for a
UI's own requests) and builds its table once with ``Handlers(owner, ...)``. A receiver
with a second kind of handler names its table: task's ``@handler(MSG, table=QUEUE)``
steps carry a program's queued messages out, beside its commands' handlers. A handler
carries its command out and returns (``RUNNING`` when the command goes on after the call:
an MDI line), or raises ``Refused(reason)``. ``carry_out`` runs one handler and turns the
result into an ``Answer``: ``Refused`` is the refusal, any other exception becomes an
"internal error" refusal (logged with its traceback; a bug in one command never stops the
process). ``echo`` writes an answer into a status message as RCS does (NML-041): the
command's type and serial number, EXEC, DONE or ERROR.

Where a command goes and what it needs is declared on its message class (``receiver=``,
``waits_for_motion=``, ``requires=``: ``nml/message.py``, the catalogue in ``nml/emc.py``);
``unmet`` checks a declaration's ``Requires`` against task's state and mode.

E-stop and abort do not depend on any of this: they reach motion, iocontrol and task first
through the safety board (``nml/safety.py``), which nothing here can block.
"""

from __future__ import annotations

import enum
import logging
import types
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from nml.message import RCS_STATUS, NMLmsg, Requires

log = logging.getLogger("nml.commands")

Key = type | str  # a message class, or the name of a UI request


class Refused(Exception):  # noqa: N818  (a refusal is an answer, not an error)
    """A command that is not carried out, and why (``str()``). ``is_quiet``: the reason
    is not said to the operator (said already, or nothing new: motion after a refused move,
    a UI whose controller reported the refusal on the error channel)."""

    def __init__(self, reason: str, is_quiet: bool = False) -> None:
        super().__init__(reason)
        self.reason = reason
        self.is_quiet = is_quiet


class InternalError(Refused):
    """The refusal of a command whose handler raised an exception nothing expected."""


# What a handler returns for a command that goes on after the call (answered DONE later)
RUNNING = "running"

COMMANDS = "commands"  # the table of a receiver's commands (the default)
QUEUE = "queue"  # task's: the steps of a program's queued messages


def handler(*keys: Key, table: str = COMMANDS) -> Callable[[Callable], Callable]:
    """Mark a function or method as the handler of ``keys`` (message classes or names)
    in its receiver's ``table``."""

    def mark(function: Callable) -> Callable:
        marks = ((table, key) for key in keys)
        function.handles = (*getattr(function, "handles", ()), *marks)  # type: ignore[attr-defined]
        return function

    return mark


class Handlers(dict):
    """The handler of each key (``dict``) in ``table``, collected from the ``@handler``
    marks of its owners: objects (their methods, bound) or modules (their functions). A
    key handled twice is refused."""

    def __init__(self, *owners: object, table: str = COMMANDS) -> None:
        super().__init__()
        for owner in owners:
            for key, function in _marked(owner, table):
                if key in self:
                    raise TypeError(f"{_name(key)} has two handlers")
                self[key] = function


def handled_by(cls: type, table: str = COMMANDS) -> list[Key]:
    """The keys the ``@handler`` methods of a class handle (tests, documentation)."""
    return [
        key
        for name in dir(cls)
        for kind, key in getattr(getattr(cls, name), "handles", ())
        if kind == table
    ]


def _marked(owner: object, table: str) -> Iterator[tuple[Key, Callable[..., Any]]]:
    if isinstance(owner, types.ModuleType):
        for function in vars(owner).values():
            for kind, key in getattr(function, "handles", ()):
                if kind == table:
                    yield key, function
        return
    cls = type(owner)
    for name in dir(cls):
        for kind, key in getattr(getattr(cls, name, None), "handles", ()):
            if kind == table:
                yield key, getattr(owner, name)


def _name(key: Key) -> str:
    return key.__name__ if isinstance(key, type) else key


@dataclass(frozen=True)
class Answer:
    """How a command ended: ``status`` (RCS_STATUS: EXEC while it goes on, DONE, ERROR) and
    the refusal when it was refused."""

    status: RCS_STATUS
    refusal: Refused | None = None

    @property
    def reason(self) -> str | None:
        """What to tell the operator (None: nothing, the command is not refused or quietly)."""
        if self.refusal is None or self.refusal.is_quiet:
            return None
        return self.refusal.reason


DONE = Answer(RCS_STATUS.DONE)
GOES_ON = Answer(RCS_STATUS.EXEC)


def carry_out(
    receiver: str,
    function: Callable[[Any], Any],
    cmd: NMLmsg,
    expected: tuple[type[Exception], ...] = (),
) -> Answer:
    """Run one handler; its answer. ``expected``: exceptions whose text is the refusal (an
    interpreter error). The one place any other exception in a command becomes a refusal
    (``<receiver>: internal error in <NAME>: <type>: <text>``, logged with its traceback)."""
    try:
        result = function(cmd)
    except Refused as refusal:
        return Answer(RCS_STATUS.ERROR, refusal)
    except expected as exc:
        return Answer(RCS_STATUS.ERROR, Refused(str(exc)))
    except Exception as exc:
        return Answer(RCS_STATUS.ERROR, internal_error(receiver, f"in {cmd.NAME}", exc))
    return GOES_ON if result is RUNNING else DONE


def internal_error(receiver: str, where: str, exc: BaseException) -> InternalError:
    """The refusal of an exception nothing expected (a bug, or a value nothing refused)."""
    log.error("%s: internal error %s", receiver, where, exc_info=exc)
    return InternalError(f"{receiver}: internal error {where}: {type(exc).__name__}: {exc}")


def echo(stat: Any, cmd: NMLmsg, status: RCS_STATUS) -> None:
    """The RCS answer in a status message: which command, and how it is doing (NML-041)."""
    stat.command_type = cmd.TYPE
    stat.echo_serial_number = cmd.serial_number
    stat.status = status


def unmet(requires: Requires | None, state: enum.IntEnum, mode: enum.IntEnum) -> str | None:
    """Why a command declared ``requires`` cannot run in task's ``state`` and ``mode``."""
    if requires is None:
        return None
    if requires.state is not None and state != requires.state:
        wanted = type(state)(requires.state)
        return f"machine must be {_words(wanted)}, it is {_words(state)}"
    if requires.mode is not None and mode != requires.mode:
        return f"must be in {type(mode)(requires.mode).name} mode, not {mode.name}"
    return None


def _words(value: enum.IntEnum) -> str:
    return value.name.replace("_", " ").lower()
