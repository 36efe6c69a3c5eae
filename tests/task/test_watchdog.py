"""The interpreter watchdog: task answers while the interpreter is stuck in one call."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from nml.safety import SafetyBoard, SafetyLink
from task.watchdog import InterpreterInterruptedError, InterpreterWatchdog


@pytest.fixture
def link() -> Iterator[SafetyLink]:
    board = SafetyBoard.create()
    made = SafetyLink.open("task", 0.5)  # (a loaded machine may hold a thread back 0.1 s)
    yield made
    made.close()
    board.unlink()


def spin(seconds: float) -> None:
    """Python that keeps running (a user's remap handler that never returns)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass


def test_a_stuck_call_keeps_the_heartbeat_beating(link: SafetyLink) -> None:
    with InterpreterWatchdog(link, limit_s=0):
        spin(1.5)  # longer than the 0.5 s heartbeat timeout
    assert link.board.find_lost() == []


def test_an_estop_request_interrupts_a_stuck_call(link: SafetyLink) -> None:
    watchdog = InterpreterWatchdog(link, limit_s=0)
    with pytest.raises(InterpreterInterruptedError, match="E-stop") as caught, watchdog:
        SafetyBoard.attach().request_estop("from another UI")
        spin(5.0)
    assert caught.value.is_requested
    assert watchdog.depth == 0 and not watchdog.is_armed


def test_a_call_longer_than_the_limit_is_interrupted(link: SafetyLink) -> None:
    with (
        pytest.raises(InterpreterInterruptedError, match="INTERP_TIMEOUT") as caught,
        InterpreterWatchdog(link, limit_s=0.3),
    ):
        spin(5.0)
    assert not caught.value.is_requested


def test_without_a_board_only_the_limit_applies() -> None:
    with InterpreterWatchdog(None, limit_s=0):
        spin(0.25)  # nothing to beat, nothing to interrupt
