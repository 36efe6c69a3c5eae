"""The periodic Timer (ARCH-018): boundaries are absolute, overruns are counted.

A fake clock makes the schedule exact, whatever the load on the machine running the tests.
"""

import pytest

from nml import timer as timer_module
from nml.timer import Timer


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0
        self.wakeups: list[float] = []

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds
        self.wakeups.append(round(self.now - 100.0, 9))


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> FakeClock:
    fake = FakeClock()
    monkeypatch.setattr(timer_module, "time", fake)
    return fake


def test_wait_returns_on_absolute_boundaries_whatever_the_work_took(clock: FakeClock) -> None:
    periodic = Timer(0.02)
    for work in (0.0, 0.015, 0.005, 0.019, 0.0):
        clock.now += work
        periodic.wait()
    assert clock.wakeups == [0.02, 0.04, 0.06, 0.08, 0.1]
    assert periodic.overruns == 0


def test_an_overrun_skips_to_the_next_boundary_ahead_and_is_counted(clock: FakeClock) -> None:
    periodic = Timer(0.02)
    clock.now += 0.05  # misses the boundaries at 20 and 40 ms
    periodic.wait()
    assert periodic.overruns == 2
    assert clock.wakeups == [0.06]
    periodic.wait()
    assert clock.wakeups == [0.06, 0.08]


def test_period_must_be_positive() -> None:
    with pytest.raises(ValueError, match="timer period must be positive"):
        Timer(0)
