"""The controller as the text UIs see it: API objects, operator messages, INI values.

``Controller(source)`` holds one ``cnc.stat``, ``cnc.command`` and ``cnc.error_channel`` for
an INI or NML file (None: the running machine), made on first use. After a failure that
may mean the controller stopped or restarted, ``reset()`` drops them so that the next use
makes new ones, which find the new buffers (old objects keep seeing the old ones).
"""

from __future__ import annotations

import collections
import contextlib
import time
from dataclasses import dataclass
from typing import Any

import cnc
from cnc.ui.formatting import MESSAGE_KINDS, message_line

MESSAGE_HISTORY = 20  # operator messages kept for display


@dataclass(frozen=True)
class Message:
    """One operator message from the error channel."""

    time: float  # time.time() when it was read
    kind: int  # cnc.OPERATOR_ERROR, OPERATOR_TEXT, OPERATOR_DISPLAY, NML_ERROR ...
    text: str

    @property
    def is_error(self) -> bool:
        return MESSAGE_KINDS.get(self.kind) == "error"

    def __str__(self) -> str:
        return message_line(self.kind, self.text)

    def stamped(self) -> str:
        """The message with the time it arrived: "10:18:05 error: ..."."""
        return f"{time.strftime('%H:%M:%S', time.localtime(self.time))} {self}"


class Controller:
    """The API objects of one controller; ``cnc.error`` at creation for a bad INI/NML file."""

    def __init__(self, source: str | None = None) -> None:
        self.source = source
        self.history: collections.deque[Message] = collections.deque(maxlen=MESSAGE_HISTORY)
        self._objects: dict[str, Any] = {}
        # Made now: a bad file is reported at start, and messages are kept from now on.
        self.stat  # noqa: B018
        self.errors  # noqa: B018

    def _get(self, name: str, make: Any) -> Any:
        found = self._objects.get(name)
        if found is None:
            found = self._objects[name] = make(self.source)
        return found

    @property
    def stat(self) -> cnc.stat:
        return self._get("stat", cnc.stat)

    @property
    def command(self) -> cnc.command:
        return self._get("command", cnc.command)

    @property
    def errors(self) -> cnc.error_channel:
        return self._get("errors", cnc.error_channel)

    def poll(self) -> cnc.stat:
        """The polled status; ``cnc.error`` if the controller is not running."""
        status = self.stat
        status.poll()
        return status

    def read_messages(self) -> list[Message]:
        """The operator messages that arrived since the last call (also kept in history)."""
        messages = []
        while (found := self.errors.poll()) is not None:
            kind, text = found
            messages.append(Message(time.time(), kind, text))
        self.history.extend(messages)
        return messages

    def reset(self) -> None:
        """Drop the API objects; the next use makes new ones."""
        for found in self._objects.values():
            with contextlib.suppress(Exception):  # closing a dead link must not hide the cause
                found.close()
        self._objects.clear()

    def close(self) -> None:
        self.reset()

    def ini_file(self) -> str | None:
        """The INI file: the one named at start, else the running task's (stat.ini_filename)."""
        if self.source is not None and self.source.lower().endswith(".ini"):
            return self.source
        try:
            return self.poll().ini_filename or None
        except cnc.error:
            return None

    def ini_value(self, section: str, key: str) -> str | None:
        """``[section]key`` of the controller's INI file, or None if unknown."""
        path = self.ini_file()
        if path is None:
            return None
        try:
            return cnc.ini(path).find(section, key)
        except cnc.error:
            return None

    def ini_number(self, section: str, key: str) -> float | None:
        """``[section]key`` as a number ('.' decimal point, CFG-002), or None if absent or
        not a number."""
        value = self.ini_value(section, key)
        try:
            return None if value is None else float(value)
        except ValueError:
            return None


def running_ini() -> str | None:
    """The INI file of the running machine (stat.ini_filename), or None."""
    probe = Controller()
    try:
        return probe.ini_file()
    finally:
        probe.close()
