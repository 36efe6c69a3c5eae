"""Free-mode planner and jogs (MOT-045..052, MOT-074)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion.free import FreePlanner, JogLimitError

DT = 0.001


def run(planner: FreePlanner, max_periods: int = 200_000) -> np.ndarray:
    """Step until the planner is idle; returns the positions, the start included."""
    positions = [planner.pos]
    for _ in range(max_periods):
        if not planner.is_active:
            break
        positions.append(planner.step(DT))
    assert not planner.is_active, "planner did not finish"
    return np.array(positions)


def peaks(positions: np.ndarray) -> tuple[float, float]:
    vel = np.abs(np.diff(positions)) / DT
    acc = np.abs(np.diff(positions, 2)) / DT**2
    return float(vel.max(initial=0)), float(acc.max(initial=0))


@settings(max_examples=40, deadline=None)
@given(
    start=st.floats(-50, 50),
    target=st.floats(-50, 50),
    vmax=st.floats(1, 100),
    amax=st.floats(10, 2000),
    vel=st.floats(0.5, 200),
)
def test_trapezoid_reaches_target_within_limits(start, target, vmax, amax, vel) -> None:
    planner = FreePlanner(vmax, amax, pos=start)
    planner.move_to(target, vel)
    path = run(planner)
    assert path[-1] == target
    v_peak, a_peak = peaks(path)
    assert v_peak <= min(vmax, vel) * (1 + 1e-9) + 1e-9
    assert a_peak <= amax * (1 + 1e-6)


@settings(max_examples=30, deadline=None)
@given(first=st.floats(-20, 20), second=st.floats(-20, 20), at=st.integers(1, 400))
def test_retarget_while_moving_stays_within_limits(first, second, at) -> None:
    planner = FreePlanner(30, 500)
    planner.move_to(first, 30)
    positions = [planner.pos]
    for _ in range(at):
        positions.append(planner.step(DT))
    planner.move_to(second, 30)
    path = np.concatenate([positions, run(planner)[1:]])
    assert path[-1] == second
    v_peak, a_peak = peaks(path)
    assert v_peak <= 30 + 1e-9 and a_peak <= 500 * (1 + 1e-6)


def test_jog_incr_is_cumulative() -> None:  # MOT-048
    planner = FreePlanner(30, 500, -100, 100)
    planner.jog_incr(2.54, 10)
    for _ in range(50):
        planner.step(DT)
    assert planner.is_active  # the first increment is still running
    planner.jog_incr(2.54, 10)
    run(planner)
    assert planner.pos == pytest.approx(5.08)


def test_jog_abs_replaces_the_target() -> None:  # MOT-051
    planner = FreePlanner(30, 500, -100, 100)
    planner.jog_abs(10, 20)
    for _ in range(100):
        planner.step(DT)
    planner.jog_abs(-3, 20)
    run(planner)
    assert planner.pos == -3


def test_jog_cont_stops_at_the_soft_limit_without_overshoot() -> None:  # MOT-045/074
    planner = FreePlanner(30, 500, -5, 12)
    planner.jog_cont(25)
    path = run(planner)
    assert path.max() <= 12 and path[-1] == 12
    planner.jog_cont(-25)
    path = run(planner)
    assert path.min() >= -5 and path[-1] == -5


def test_jog_incr_is_clipped_at_the_soft_limit() -> None:
    planner = FreePlanner(30, 500, -5, 5)
    planner.jog_incr(4, 10)
    planner.jog_incr(4, 10)
    path = run(planner)
    assert path.max() <= 5 and planner.pos == 5


def test_jog_further_past_a_limit_is_refused_but_back_is_allowed() -> None:  # MOT-046
    planner = FreePlanner(30, 500, -5, 5, pos=5)
    with pytest.raises(JogLimitError, match="positive soft limit"):
        planner.jog_cont(10)
    with pytest.raises(JogLimitError):
        planner.jog_incr(1, 10)
    planner.jog_incr(-1, 10)
    run(planner)
    assert planner.pos == 4


def test_override_limits_lets_a_jog_pass_the_limit() -> None:  # MOT-042
    planner = FreePlanner(30, 500, -5, 5, pos=5)
    planner.jog_incr(1, 10, is_override_limits=True)
    run(planner)
    assert planner.pos == 6


def test_jog_cont_stop_decelerates_at_the_limit() -> None:  # MOT-052
    planner = FreePlanner(30, 500, -100, 100)
    planner.jog_cont(30)
    positions = [planner.pos]
    for _ in range(200):
        positions.append(planner.step(DT))
    assert planner.vel == pytest.approx(30)
    planner.stop()
    path = np.concatenate([positions, run(planner)[1:]])
    _, a_peak = peaks(path)
    assert a_peak <= 500 * (1 + 1e-6)
    # stopping distance at 500 mm/s^2 from 30 mm/s is 0.9 mm
    assert path[-1] - positions[-1] == pytest.approx(0.9, abs=0.05)
    assert planner.vel == 0


def test_bad_arguments_are_rejected_clearly() -> None:
    with pytest.raises(ValueError, match="max velocity must be positive"):
        FreePlanner(0, 10)
    with pytest.raises(ValueError, match="max acceleration must be a finite"):
        FreePlanner(1, math.nan)
    with pytest.raises(ValueError, match="soft limits"):
        FreePlanner(1, 1, 5, -5)
    planner = FreePlanner(1, 1)
    with pytest.raises(ValueError, match="target must be a finite"):
        planner.move_to(math.nan, 1)
    with pytest.raises(ValueError, match="jog velocity must not be zero"):
        planner.jog_cont(0)


def test_scale_slows_the_move_but_never_exceeds_max_velocity() -> None:  # MOT-040
    planner = FreePlanner(20, 500)
    planner.scale = 3.0
    planner.move_to(10, 20)
    v_peak, _ = peaks(run(planner))
    assert v_peak <= 20 + 1e-9
    planner.scale = 0.5
    planner.move_to(0, 20)
    v_peak, _ = peaks(run(planner))
    assert v_peak <= 10 + 1e-9
