"""Task stays answering while it is inside the interpreter, whatever the interpreter does.

Task gives the interpreter a slice of each cycle, but one call can still run long: a large
program being read, a pathological expression, and with REMAP a user's Python handler that
loops forever. While task is inside the interpreter, ``InterpreterWatchdog`` keeps a timer
(SIGALRM every WATCH_S) whose handler, between two bytecodes of whatever runs:

- beats task's heartbeat, so motion does not take a busy task for a dead one;
- interrupts the interpreter (``InterpreterInterruptedError``, an InterpError, so task stops the
  run like any interpreter error) when an E-stop or abort is requested on the safety board,
  which task then acts on, or when one call has run longer than ``limit_s``
  ([TASK]INTERP_TIMEOUT).

The handler touches nothing else of task's: it beats, reads the board, and raises.
"""

from __future__ import annotations

import signal
import time
from types import FrameType, TracebackType

from nml.safety import SafetyLink
from task.interp.errors import InterpError

WATCH_S = 0.1


class InterpreterInterruptedError(InterpError):
    """The interpreter was stopped in the middle of a call: ``is_requested`` for an E-stop
    or abort (which task then reports as such), else it ran too long."""

    def __init__(self, message: str, *, is_requested: bool = False) -> None:
        super().__init__(message)
        self.is_requested = is_requested


class InterpreterWatchdog:
    def __init__(self, safety: SafetyLink | None, limit_s: float) -> None:
        self.safety = safety
        self.limit_s = limit_s  # 0: no limit
        self.entered_at = 0.0
        self.depth = 0
        self.is_armed = False
        self._previous: object = None

    def __enter__(self) -> InterpreterWatchdog:
        self.depth += 1
        if self.depth == 1:
            self.entered_at = time.monotonic()
            self._previous = signal.signal(signal.SIGALRM, self._on_alarm)
            self.is_armed = True
            signal.setitimer(signal.ITIMER_REAL, WATCH_S, WATCH_S)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        try:
            if self.depth == 1:
                self.is_armed = False  # first: an alarm still on its way raises nothing
                signal.setitimer(signal.ITIMER_REAL, 0, 0)
                signal.signal(signal.SIGALRM, self._previous)  # type: ignore[arg-type]
        finally:
            self.depth -= 1

    def _on_alarm(self, _signum: int, _frame: FrameType | None) -> None:
        if not self.is_armed:
            return
        safety = self.safety
        if safety is not None:
            safety.heartbeat.beat()
            watcher, board = safety.watcher, safety.board
            if board.estop_stamp() != watcher.estop_seen:
                raise InterpreterInterruptedError("interpreter stopped: E-stop", is_requested=True)
            if board.abort_stamp() != watcher.abort_seen:
                raise InterpreterInterruptedError("interpreter stopped: abort", is_requested=True)
        spent = time.monotonic() - self.entered_at
        if self.limit_s and spent > self.limit_s:
            raise InterpreterInterruptedError(
                f"the interpreter ran {spent:.1f} s in one step without returning; stopped "
                f"([TASK]INTERP_TIMEOUT = {self.limit_s:g})"
            )
