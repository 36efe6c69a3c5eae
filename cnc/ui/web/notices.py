"""Operator messages as the page shows them: one notice per event, however many lines the
controller wrote about it.

One refused move reaches the error channel as several messages within a few milliseconds
("Linear move on line 0 would exceed X's positive limit", the same for joint 0, "motion
refused a command"). ``Notices`` gathers the errors that arrive within ``WINDOW_S`` of the
first into one notice: its first line is the text, the others its details; a line that only
says that something failed is dropped when a line says why. Texts and displays
((MSG, ...), user messages) are passed on one by one, as they are.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

WINDOW_S = 0.25  # errors this close together are one event
# Lines that add nothing when another line of the same event gives the reason.
GENERIC = ("motion refused a command",)
# An MDI line has no program line: "on line 0" says nothing.
_NO_LINE = re.compile(r" on line 0\b")


def clean(text: str) -> str:
    return _NO_LINE.sub("", text).strip()


@dataclass
class _Pending:
    since: float
    lines: list[str] = field(default_factory=list)


class Notices:
    """Collects messages (kind, text) and hands out notices for the pages."""

    def __init__(self) -> None:
        self._pending: _Pending | None = None

    def add(self, kind: str, text: str, now: float) -> list[dict[str, Any]]:
        """A message read from the error channel; the notices ready now."""
        ready = self.due(now)
        if kind != "error":
            return [*ready, {"type": "notice", "kind": kind, "text": text}]
        if self._pending is None:
            self._pending = _Pending(now)
        line = clean(text)
        if line not in self._pending.lines:
            self._pending.lines.append(line)
        return ready

    def due(self, now: float) -> list[dict[str, Any]]:
        """The gathered errors, once their window has passed."""
        pending = self._pending
        if pending is None or now - pending.since < WINDOW_S:
            return []
        self._pending = None
        lines = [line for line in pending.lines if line not in GENERIC] or pending.lines
        notice: dict[str, Any] = {"type": "notice", "kind": "error", "text": lines[0]}
        if len(lines) > 1:
            notice["details"] = lines[1:]
        return [notice]
