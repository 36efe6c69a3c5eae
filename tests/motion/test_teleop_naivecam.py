"""Teleop velocity planning (MOT-016/021) and the G64 Q naive-CAM merger."""

import itertools

import numpy as np
import pytest

from motion.teleop import TeleopPlanner
from motion.tp.naivecam import NaiveCamMerger

DT = 0.001
VEL = [30.0, 20.0, 10.0, 90.0, 90.0, 90.0, 30.0, 30.0, 30.0]
ACC = [500.0, 300.0, 200.0, 900.0, 900.0, 900.0, 500.0, 500.0, 500.0]


def run(planner: TeleopPlanner, periods: int) -> np.ndarray:
    return np.array([planner.step(DT).copy() for _ in range(periods)])


def test_teleop_follows_the_vector_within_axis_limits() -> None:
    planner = TeleopPlanner(VEL, ACC)
    planner.set_velocity([40.0, 40.0, 0, 0, 0, 0, 0, 0, 0])  # X alone would exceed 30
    path = run(planner, 500)
    vel = np.diff(path, axis=0) / DT
    acc = np.diff(path, 2, axis=0) / DT**2
    assert (np.abs(vel).max(axis=0) <= np.array(VEL) + 1e-9).all()
    assert (np.abs(acc).max(axis=0) <= np.array(ACC) * (1 + 1e-9)).all()
    # the direction is kept: the whole vector is scaled to Y's 20 mm/s
    assert planner.vel[:2] == pytest.approx([20.0, 20.0])


def test_teleop_abort_is_a_coordinated_stop() -> None:  # MOT-021
    planner = TeleopPlanner(VEL, ACC)
    planner.set_velocity([10.0, 5.0, 0, 0, 0, 0, 0, 0, 0])
    run(planner, 300)
    start = planner.pos.copy()
    planner.abort()
    path = run(planner, 300)
    assert not planner.is_moving
    moved = path - start
    # stopped along the same direction (2:1), within the tightest acceleration
    assert np.allclose(moved[:, 0], 2 * moved[:, 1], atol=1e-9)
    acc = np.abs(np.diff(path, 2, axis=0)) / DT**2
    assert (acc.max(axis=0) <= np.array(ACC) * (1 + 1e-9)).all()


def test_teleop_stops_at_the_axis_limit() -> None:
    planner = TeleopPlanner(VEL, ACC, axis_min=[-5] * 9, axis_max=[5] * 9)
    planner.set_velocity([30.0, 0, 0, 0, 0, 0, 0, 0, 0])
    path = run(planner, 1500)
    assert path[:, 0].max() <= 5.0
    assert planner.pos[0] == pytest.approx(5.0, abs=0.01)


def test_teleop_rejects_bad_vectors() -> None:
    with pytest.raises(ValueError, match="positive"):
        TeleopPlanner([0] * 9, ACC)
    planner = TeleopPlanner(VEL, ACC)
    with pytest.raises(ValueError, match="9 numbers"):
        planner.set_velocity([1, 2])


def line(merger, start, end, q=0.01, **args):
    args = {"vel": 10.0, "ini_maxvel": 50.0, "acc": 500.0, "motion_id": 0, **args}
    return merger.push(start, [*end, 0, 0, 0, 0, 0, 0], q, **args)


def test_naive_cam_merges_nearly_collinear_lines() -> None:
    merger = NaiveCamMerger()
    points = [(0, 0, 0), (1, 0.002, 0), (2, -0.003, 0), (3, 0, 0), (3, 1, 0)]
    out = []
    for n, (a, b) in enumerate(itertools.pairwise(points), start=1):
        out += line(merger, [*a, 0, 0, 0, 0, 0, 0], b, motion_id=n)
    out += merger.flush()
    assert [o["end"][:2] for o in out] == [[3, 0], [3, 1]]
    assert [o["motion_id"] for o in out] == [3, 4]


def test_naive_cam_keeps_corners_and_different_feeds() -> None:
    merger = NaiveCamMerger()
    out = line(merger, [0] * 9, (1, 0, 0))
    out += line(merger, [1] + [0] * 8, (2, 0.05, 0))  # beyond Q: a real corner
    out += line(merger, [2, 0.05] + [0] * 7, (3, 0.1, 0), vel=20.0)  # another feed
    out += merger.flush()
    assert len(out) == 3


def test_naive_cam_off_when_q_is_zero() -> None:
    merger = NaiveCamMerger()
    out = line(merger, [0] * 9, (1, 0, 0), q=0.0)
    assert len(out) == 1 and merger.flush() == []
