"""``cnc.error_channel``: messages for the operator, as LinuxCNC's ``linuxcnc.error_channel``.

``poll()`` returns ``(kind, text)`` for the next message, or None: ``kind`` is the message
type number (OPERATOR_ERROR, OPERATOR_TEXT, OPERATOR_DISPLAY). The ``emcError`` buffer is a
broadcast queue: every error_channel object, in any process, gets its own copy of every
message sent after it was created, and of those still queued for other channels when it was
created (LinuxCNC's plain queue hands each message to one reader only).

A channel holds the messages it has not read yet; one that is never polled makes the queue
fill up; writers then drop the oldest messages (they never wait for a reader), and each
channel that had not read them is told how many it missed. Close a channel you stop
polling (``close()``, or drop it).
"""

from __future__ import annotations

import os

from cnc.api.connection import Link
from cnc.api.errors import error
from nml import emc
from nml.channels import EMC_ERROR
from nml.errors import NmlError, NmlFormatError

# Message class -> the field holding its text.
_TEXT_FIELDS = {
    emc.EMC_OPERATOR_ERROR: "error",
    emc.EMC_OPERATOR_TEXT: "text",
    emc.EMC_OPERATOR_DISPLAY: "display",
}


class error_channel:  # LinuxCNC's name: linuxcnc.error_channel
    """The operator messages of the controller; ``poll()`` returns the next one or None.

    ``error_channel(path)`` names an NML or INI file; without it the running machine is
    found. If the controller is not running yet, the channel attaches at the first poll.
    """

    __slots__ = ("__weakref__", "_link")

    def __init__(self, source: str | os.PathLike[str] | None = None) -> None:
        self._link = Link(source)
        self._link.close_with(self)
        self._link.try_attach(EMC_ERROR)  # from now on, every message is kept for us

    def poll(self) -> tuple[int, str] | None:
        """The next message as ``(kind, text)``, or None; ``cnc.error`` if not running.
        Messages dropped before this channel read them (the buffer was full) are told
        first, as one OPERATOR_ERROR saying how many."""
        try:
            buffer = self._link.buffer(EMC_ERROR)
            missed = buffer.take_missed()
            if missed:
                return emc.EMC_OPERATOR_ERROR.TYPE, (
                    f"{missed} operator message(s) were dropped before this display read "
                    "them: the error channel was full"
                )
            message = buffer.read()
        except NmlFormatError as exc:  # found corrupt and repaired: said once, as a message
            return emc.EMC_OPERATOR_ERROR.TYPE, f"error channel: {exc}"
        except NmlError as exc:
            raise error(str(exc)) from None
        if message is None:
            return None
        field = _TEXT_FIELDS.get(type(message))
        if field is None:
            return message.TYPE, f"unrecognized error {message.TYPE}"
        return message.TYPE, getattr(message, field)

    def close(self) -> None:
        """Detach now (otherwise when the object is collected): stop holding messages."""
        self._link.close()
