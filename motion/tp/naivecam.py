"""G64 Q, the naive-CAM detector: consecutive straight feed moves whose end points all lie
within Q of one straight line are sent to the planner as that one line.

The merger holds back the last line until the next move shows whether it continues the
run, so whoever feeds it must call ``flush()`` before anything that is not a mergeable
line (another kind of move, a program end, a wait) and whenever the planner's queue
would otherwise run dry.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np


@dataclass(slots=True)
class PendingLine:
    """A line waiting for its successor: ``add_line`` keyword arguments plus the points
    it absorbed."""

    start: np.ndarray
    end: np.ndarray
    q: float
    args: dict
    points: list[np.ndarray] = field(default_factory=list)


class NaiveCamMerger:
    def __init__(self) -> None:
        self._pending: PendingLine | None = None

    def push(
        self, start: Sequence[float], end: Sequence[float], q: float, **line_args: object
    ) -> list[dict]:
        """Offer a line from ``start`` to ``end`` with naive-CAM tolerance ``q`` (0: no
        merging) and the other ``add_line`` arguments; returns the lines (``add_line``
        keyword dicts, ``end`` included) now ready for the planner, in order."""
        start_v = np.asarray(start, dtype=float)
        end_v = np.asarray(end, dtype=float)
        ready: list[dict] = []
        pending = self._pending
        if pending is not None and self._is_continuation(pending, start_v, end_v, q, line_args):
            pending.points.append(pending.end)
            pending.end = end_v
            pending.args = dict(line_args)  # the last merged move's id is the one shown
            return ready
        ready.extend(self.flush())
        if q > 0 and not line_args.get("is_rapid", False):
            self._pending = PendingLine(start_v, end_v, q, dict(line_args))
        else:
            ready.append({"end": list(end_v), **line_args})
        return ready

    def flush(self) -> list[dict]:
        """The held-back line, if any."""
        pending, self._pending = self._pending, None
        if pending is None:
            return []
        return [{"end": list(pending.end), **pending.args}]

    @staticmethod
    def _is_continuation(
        pending: PendingLine, start: np.ndarray, end: np.ndarray, q: float, args: dict
    ) -> bool:
        if q <= 0 or q != pending.q or not np.allclose(start, pending.end):
            return False
        same = ("vel", "ini_maxvel", "acc", "term", "tolerance", "is_rapid")
        if any(args.get(k) != pending.args.get(k) for k in same):
            return False
        chord = end - pending.start
        length = float(np.linalg.norm(chord))
        if length == 0:
            return False
        unit = chord / length
        for point in [*pending.points, pending.end]:
            rel = point - pending.start
            along = float(rel @ unit)
            if not 0 <= along <= length:
                return False  # going back: not one straight run
            if float(np.linalg.norm(rel - along * unit)) > q:
                return False
        return True
