"""The periodic Timer (ARCH-018): boundaries are absolute, overruns are counted."""

import time

import pytest

from nml.timer import Timer


def test_wait_returns_on_absolute_boundaries_whatever_the_work_took() -> None:
    timer = Timer(0.02)
    start = time.monotonic()
    for work in (0.0, 0.015, 0.005, 0.019, 0.0):
        time.sleep(work)
        timer.wait()
    elapsed = time.monotonic() - start
    assert elapsed >= 0.1  # five whole periods, the work did not shorten them
    assert elapsed < 0.1 + 0.02  # nor did the work push later boundaries back
    assert timer.overruns == 0


def test_an_overrun_skips_to_the_next_boundary_ahead_and_is_counted() -> None:
    timer = Timer(0.02)
    start = time.monotonic()
    time.sleep(0.05)  # misses the boundaries at 20 and 40 ms
    timer.wait()
    assert timer.overruns == 2
    assert time.monotonic() - start >= 0.06


def test_period_must_be_positive() -> None:
    with pytest.raises(ValueError, match="timer period must be positive"):
        Timer(0)
