"""The program time estimate: interpreter, task's canon and the trajectory planner at the
machine's limits (cnc/ui/estimate.py). The test mill (tests/task/machine/mill.ini) moves
every axis at up to 50 mm/s and 1000 mm/s^2, so a straight move from rest to rest of
length L at 50 mm/s takes L/50 + 0.05 s (0.05 s to reach the speed, 0.05 s to stop, each
covering half the distance a full-speed period would)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cnc.ui.estimate import estimate, reached_times, time_at
from tests.task.test_machine import MACHINE

SHARED_PROGRAMS = Path("/work/shared/reference/programs")
BENCH_INI = Path(__file__).parents[2] / "scripts" / "bench" / "axis_mm.ini"


@pytest.fixture
def machine(tmp_path: Path) -> Path:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    return folder


def run(machine: Path, text: str, **options):  # type: ignore[no-untyped-def]
    """The estimate of ``text``; the planner's own time unless a ``clock`` is given
    (task's reading and motion's intake are timed by the test's clock, not this
    machine's)."""
    program = machine / "part.ngc"
    program.write_text(text)
    options.setdefault("clock", None)
    return estimate(str(program), str(machine / "mill.ini"), **options)


def test_short_moves_run_at_the_rate_they_reach_the_planner(machine: Path) -> None:
    """200 moves of 0.01 mm at 3000 mm/min take the planner about 0.1 s. Read at 5 ms a
    line (200 lines a second), task feeds them for 1 s, and the moves cannot run ahead
    of it. Read at 0.2 ms a line, motion's one move a 1 ms period limits them: 0.2 s
    and more (the planner looks ahead over a short queue). Long moves are not slowed."""
    moves = "".join(f"G1 X{0.01 * n:.2f}\n" for n in range(1, 201))
    text = "G21 G90 G64 F3000\n" + moves + "M2\n"
    planner = run(machine, text).total_s
    assert planner < 0.15
    fed = run(machine, text, clock=Clock(0.005)).total_s
    assert fed == pytest.approx(200 * 0.005, abs=0.02)
    taken = run(machine, text, clock=Clock(0.0002)).total_s
    assert 200 * 0.001 <= taken < 0.5
    long = "G21 G90\nG1 X100 F3000\nM2\n"
    assert run(machine, long, clock=Clock(0.005)).total_s == pytest.approx(
        run(machine, long).total_s, abs=0.012
    )


class Clock:
    """A clock the estimate times task's reading with: each line takes ``seconds`` (it
    is read before and after each)."""

    def __init__(self, seconds: float) -> None:
        self.seconds, self.calls = seconds, 0

    def __call__(self) -> float:
        self.calls += 1
        return (self.calls // 2) * self.seconds


def test_a_straight_feed_accelerates_cruises_and_brakes(machine: Path) -> None:
    found = run(machine, "G21 G90\nG1 X100 F3000\nM2\n")
    assert found.total_s == pytest.approx(100 / 50 + 0.05, abs=0.002)
    assert found.error is None and found.end_line == 3
    assert found.time_at(2) == pytest.approx(0.0, abs=0.002)


def test_exact_stops_dwells_and_a_slow_feed_add_up(machine: Path) -> None:
    """G61.1 stops at the corner: two moves from rest to rest; the dwell adds its time;
    the M0 stop counts nothing but is reported; a 600 mm/min feed never reaches 50 mm/s."""
    text = "G21 G90 G61.1\nG0 X50\nG1 Y50 F3000\nG4 P1.5\nM0\nG1 X40 F600\nM2\n"
    found = run(machine, text)
    slow = 10 / 10 + 10 / 1000  # 10 mm at 10 mm/s: 0.01 s each to reach it and to stop
    assert found.total_s == pytest.approx(2 * (50 / 50 + 0.05) + 1.5 + slow, abs=0.003)
    assert (found.stops, found.dwell_s) == (1, 1.5)
    assert found.time_at(3) == pytest.approx(1.05, abs=0.002)  # line 3 starts after line 2
    assert found.time_at(6) == pytest.approx(2 * 1.05 + 1.5, abs=0.005)  # after the dwell
    assert found.time_at(99) == found.time_at(6)  # past the end: the last line's start


def test_a_full_circle_is_slowed_by_its_radius(machine: Path) -> None:
    """A 10 mm radius at 3000 mm/min would need 250 mm/s^2 centripetal acceleration: well
    within 1000, so the circle runs at the feed; 62.83 mm at 50 mm/s, from rest to rest."""
    found = run(machine, "G21 G90\nG0 X10\nG2 X10 Y0 I-10 J0 F3000\nM2\n")
    circle = found.total_s - found.time_at(3)
    assert circle == pytest.approx(2 * np.pi * 10 / 50 + 0.05, abs=0.01)


def test_the_estimate_starts_where_the_machine_is(machine: Path) -> None:
    found = run(machine, "G21 G90\nG1 X100 F3000\nM2\n", start=[50.0, 0.0, 0.0])
    assert found.total_s == pytest.approx(50 / 50 + 0.05, abs=0.002)


def test_an_interpreter_error_ends_the_estimate_with_its_line(machine: Path) -> None:
    found = run(machine, "G21 G90\nG1 X10 F3000\nG999\nG1 X90\nM2\n")
    assert found.error == {"line": 3, "message": "G-code out of range"}
    assert found.total_s == pytest.approx(10 / 50 + 0.05, abs=0.002)  # what came before


def test_reached_times_fill_lines_without_motion() -> None:
    starts = np.array([np.nan, np.nan, 0.0, np.nan, 2.5, np.nan])
    reached = reached_times(starts)
    assert [time_at(reached, line) for line in range(8)] == [0, 0, 0, 0, 2.5, 2.5, 2.5, 2.5]


@pytest.mark.skipif(not SHARED_PROGRAMS.is_dir(), reason="no shared benchmark programs")
def test_the_estimate_is_the_planners_own_time_on_a_benchmark_program() -> None:
    """circle_g64 on LinuxCNC's sim limits (scripts/bench/axis_mm.ini): the planner alone
    (scripts/bench/tp_bench.py, from X0 Y0 Z10) takes 14.233 s; the estimate, through the
    interpreter and task's canon, must find the same."""
    found = estimate(
        str(SHARED_PROGRAMS / "circle_g64.ngc"), str(BENCH_INI), start=[0.0, 0.0, 10.0],
        clock=None,
    )  # fmt: skip
    assert found.total_s == pytest.approx(14.233, abs=0.002)
