"""Coordinated-mode trajectory planner (MOT-017, MOT-022, MOT-037..041, MOT-053..057).

Every test simulates at the 1 ms servo period and checks the sampled path: the per-axis
velocity and acceleration are finite differences of the commanded positions, as a
position loop would see them.
"""

import itertools
import math
import sys
import types

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion.modules import ModuleInterfaceError
from motion.tp import ProbeType, TermCond, TrajectoryPlanner, load_planner

DT = 0.001
VMAX = 30.48
AMAX = 508.0
LIMIT_V = np.array([VMAX] * 3 + [60.0] * 3 + [VMAX] * 3)
LIMIT_A = np.array([AMAX] * 3 + [800.0] * 3 + [AMAX] * 3)


def planner(start=(0.0, 0.0, 0.0)) -> TrajectoryPlanner:
    tp = TrajectoryPlanner(LIMIT_V, LIMIT_A, DT, max_vel=53.34, max_acc=AMAX)
    tp.set_position(list(start) + [0.0] * (9 - len(start)))
    return tp


def pose(*xyz: float, **others: float) -> list[float]:
    values = list(xyz) + [0.0] * (9 - len(xyz))
    for letter, value in others.items():
        values["xyzabcuvw".index(letter)] = value
    return values


class Run:
    """Samples of a simulation: positions (N x 9), path speeds and motion ids."""

    def __init__(self, tp: TrajectoryPlanner) -> None:
        self.tp = tp
        self.pos = [tp.pos.copy()]
        self.vel = [tp.vel]
        self.ids = [tp.motion_id]

    def step(self, periods: int = 1) -> None:
        for _ in range(periods):
            self.pos.append(self.tp.step().copy())
            self.vel.append(self.tp.vel)
            self.ids.append(self.tp.motion_id)

    def until_done(self, max_periods: int = 200_000) -> "Run":
        for _ in range(max_periods):
            if self.tp.is_done:
                return self
            self.step()
        raise AssertionError("planner did not finish")

    @property
    def path(self) -> np.ndarray:
        return np.array(self.pos)

    def assert_within_limits(self) -> None:
        path = self.path
        vel = np.abs(np.diff(path, axis=0)) / DT
        acc = np.abs(np.diff(path, 2, axis=0)) / DT**2
        assert (vel.max(axis=0, initial=0) <= LIMIT_V * (1 + 1e-9)).all(), vel.max(axis=0)
        assert (acc.max(axis=0, initial=0) <= LIMIT_A * (1 + 1e-6)).all(), acc.max(axis=0)


def distance_to_polyline(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    best = np.full(len(points), np.inf)
    for a, b in itertools.pairwise(vertices):
        ab = b - a
        den = float(ab @ ab)
        t = np.clip((points - a) @ ab / den, 0, 1) if den > 0 else np.zeros(len(points))
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * ab), axis=1))
    return best


def assert_follows_polyline(run, vertices, term, tolerance) -> None:
    """Within limits, ending at the last vertex, never farther from the polyline than G64
    allows (P, else a quarter of the longest segment); on it exactly unless blending."""
    run.assert_within_limits()
    assert np.allclose(run.path[-1][:3], vertices[-1], atol=1e-9)
    deviation = distance_to_polyline(run.path[:, :3], np.array(vertices))
    lengths = np.linalg.norm(np.diff(np.array(vertices), axis=0), axis=1)
    bound = tolerance if tolerance > 0 else 0.25 * lengths.max()
    assert deviation.max() <= (bound if term == TermCond.BLEND else 0.0) + 1e-9


def add_polyline(tp, vertices, feed=25.0, term=TermCond.BLEND, tolerance=0.0) -> None:
    for n, vertex in enumerate(vertices[1:], start=1):
        tp.add_line(pose(*vertex), feed, 53.34, AMAX, motion_id=n, term=term, tolerance=tolerance)


# ---------------------------------------------------------------------- termination modes
def test_exact_stop_comes_to_rest_at_every_vertex() -> None:  # G61
    square = [(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0), (0, 0, 0)]
    tp = planner()
    add_polyline(tp, square, term=TermCond.STOP)
    run = Run(tp).until_done()
    run.assert_within_limits()
    path, vel = run.path, np.array(run.vel)
    for vertex in square[1:]:
        at_vertex = np.linalg.norm(path[:, :3] - vertex, axis=1) < 1e-12
        assert (vel[at_vertex] == 0).any(), f"never at rest on {vertex}"
    assert distance_to_polyline(path[:, :3], np.array(square, float)).max() < 1e-9


def test_exact_path_follows_the_corners() -> None:  # G61.1
    zigzag = [(0, 0, 0), (5, 0, 0), (5, 5, 0), (10, 5, 0)]
    tp = planner()
    add_polyline(tp, zigzag, term=TermCond.EXACT)
    run = Run(tp).until_done()
    run.assert_within_limits()
    assert distance_to_polyline(run.path[:, :3], np.array(zigzag, float)).max() < 1e-9
    assert np.allclose(run.path[-1][:3], zigzag[-1])


@pytest.mark.parametrize(
    ("vertices", "is_faster"),
    [
        ([(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0), (0, 0, 0)], True),  # 90 degrees
        ([(0, 0, 0), (10, 0, 0), (2, 6, 0), (6, -4, 0), (0, 0, 0)], False),  # sharp
    ],
)
def test_blending_cuts_corners_within_the_tolerance(vertices, is_faster) -> None:  # G64 P
    periods = {}
    for term, tolerance in ((TermCond.STOP, 0.0), (TermCond.BLEND, 0.05), (TermCond.BLEND, 0.5)):
        tp = planner()
        add_polyline(tp, vertices, term=term, tolerance=tolerance)
        run = Run(tp).until_done()
        run.assert_within_limits()
        deviation = distance_to_polyline(run.path[:, :3], np.array(vertices, float))
        assert deviation.max() <= tolerance + 1e-9
        periods[tolerance] = len(run.pos)
    # where an arc within the tolerance would be slower than stopping, the planner stops
    assert periods[0.5] <= periods[0.05] <= periods[0.0]
    if is_faster:
        assert periods[0.5] < periods[0.0] - 50


def test_polyline_circle_of_3600_segments_runs_at_feed_within_limits() -> None:
    vertices = [
        (40 * math.cos(2 * math.pi * i / 3600), 40 * math.sin(2 * math.pi * i / 3600), 0)
        for i in range(3601)
    ]
    tp = planner(vertices[0])
    run = Run(tp)
    pending = iter(enumerate(vertices[1:], start=1))
    is_feeding = True
    while is_feeding or not tp.is_done:
        while is_feeding and tp.free_slots > 0:
            item = next(pending, None)
            if item is None:
                is_feeding = False
                break
            n, vertex = item
            tp.add_line(pose(*vertex), 25.0, 53.34, AMAX, motion_id=n, tolerance=0.001)
        run.step()
    run.assert_within_limits()
    path = run.path[:, :3]
    assert distance_to_polyline(path, np.array(vertices)).max() <= 0.001 + 1e-9
    # programmed feed on the whole circle except the start and stop ramps
    vel = np.array(run.vel)
    assert (vel[100:-100] > 25.0 - 1e-6).all()
    circumference = 2 * math.pi * 40
    assert len(run.pos) * DT < circumference / 25.0 + 0.2


@settings(max_examples=25, deadline=None)
@given(
    points=st.lists(
        st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-2, 2)), min_size=2, max_size=7
    ),
    feed=st.floats(1, 50),
    tolerance=st.sampled_from([0.0, 0.001, 0.05, 1.0]),
    term=st.sampled_from(list(TermCond)),
)
def test_any_polyline_stays_within_limits_and_tolerance(points, feed, tolerance, term) -> None:
    vertices = [(0.0, 0.0, 0.0), *points]
    tp = planner()
    add_polyline(tp, vertices, feed=feed, term=term, tolerance=tolerance)
    run = Run(tp).until_done()
    assert_follows_polyline(run, vertices, term, tolerance)


# ---------------------------------------------------------------------- arcs
def test_full_circle_keeps_its_radius() -> None:
    tp = planner((10, 0, 0))
    tp.add_circle(pose(10, 0, 0), (0, 0, 0), (0, 0, 1), 0, 25.0, 53.34, AMAX, motion_id=1)
    run = Run(tp).until_done()
    run.assert_within_limits()
    radius = np.hypot(run.path[:, 0], run.path[:, 1])
    assert np.abs(radius - 10).max() < 1e-9
    angles = np.unwrap(np.arctan2(run.path[:, 1], run.path[:, 0]))
    assert angles[-1] == pytest.approx(2 * math.pi)  # counter-clockwise about +Z
    assert (np.diff(angles) >= -1e-12).all()


def test_helix_in_the_xz_plane_with_turns_and_a_rotary_axis() -> None:
    # counter-clockwise about -Y (from +X towards +Z); two extra turns; Y rises 6, A 90
    tp = planner((5, 0, 0))
    tp.add_circle(pose(-5, 6, 0, a=90), (0, 0, 0), (0, -1, 0), 2, 20.0, 53.34, AMAX, 7)
    run = Run(tp).until_done()
    run.assert_within_limits()
    path = run.path
    assert np.abs(np.hypot(path[:, 0], path[:, 2]) - 5).max() < 1e-9
    angle = np.unwrap(np.arctan2(path[:, 2], path[:, 0]))  # measured about -Y
    assert angle[-1] == pytest.approx(2.5 * 2 * math.pi)
    # the helix axis and the rotary axis move in proportion to the angle
    assert np.allclose(path[:, 1], 6 * angle / angle[-1], atol=1e-9)
    assert np.allclose(path[:, 3], 90 * angle / angle[-1], atol=1e-9)
    assert np.allclose(path[-1], pose(-5, 6, 0, a=90))


def test_tangent_arcs_and_lines_run_without_stopping() -> None:
    tp = planner((0, 0, 0))
    tp.add_line(pose(10, 0, 0), 20.0, 53.34, AMAX, 1)
    tp.add_circle(pose(10, 10, 0), (10, 5, 0), (0, 0, 1), 0, 20.0, 53.34, AMAX, 2)
    tp.add_line(pose(0, 10, 0), 20.0, 53.34, AMAX, 3)
    run = Run(tp).until_done()
    run.assert_within_limits()
    vel, ids = np.array(run.vel), np.array(run.ids)
    between = (ids >= 2) & (np.arange(len(ids)) < len(ids) - 50)
    assert vel[np.argmax(ids == 2) : np.argmax(ids == 3) + 5].min() > 1.0
    assert between.any()


def test_invalid_arcs_are_rejected() -> None:
    tp = planner((0, 0, 0))
    with pytest.raises(ValueError, match="zero radius"):
        tp.add_circle(pose(1, 0, 0), (0, 0, 0), (0, 0, 1), 0, 10, 50, AMAX)
    with pytest.raises(ValueError, match="normal vector is zero"):
        tp.add_circle(pose(1, 0, 0), (0, 1, 0), (0, 0, 0), 0, 10, 50, AMAX)
    with pytest.raises(ValueError, match="turns"):
        tp.add_circle(pose(1, 0, 0), (0, 1, 0), (0, 0, 1), -1, 10, 50, AMAX)


# ---------------------------------------------------------------------- axes together
def test_xyz_abc_uvw_arrive_together() -> None:
    tp = planner()
    target = pose(3, 4, 0, a=30, b=-10, c=5, u=1, v=2, w=-1)
    tp.add_line(target, 10.0, 53.34, AMAX, 1)
    run = Run(tp).until_done()
    run.assert_within_limits()
    path = run.path
    fraction = np.hypot(path[:, 0], path[:, 1]) / 5.0  # the XYZ length drives the feed
    assert np.allclose(path, fraction[:, None] * np.array(target), atol=1e-9)
    assert max(run.vel) == pytest.approx(10.0)


def test_rotary_only_move_uses_the_rotary_length() -> None:
    tp = planner()
    tp.add_line(pose(a=45), 30.0, 53.34, AMAX, 1)
    run = Run(tp).until_done()
    run.assert_within_limits()
    assert run.path[-1][3] == pytest.approx(45)
    assert max(run.vel) == pytest.approx(30.0)


# ---------------------------------------------------------------------- status
def test_motion_id_and_distance_to_go() -> None:
    tp = planner()
    tp.add_line(pose(10, 0, 0), 20.0, 53.34, AMAX, 11, TermCond.STOP)
    tp.add_line(pose(10, 5, 0), 20.0, 53.34, AMAX, 12, TermCond.STOP)
    run = Run(tp)
    run.step(10)
    assert tp.motion_id == 11
    assert tp.distance_to_go == pytest.approx(10 - tp.pos[0])
    assert tp.queue_depth == 2
    run.until_done()
    assert tp.motion_id == 12 and tp.distance_to_go == 0 and tp.queue_depth == 0
    assert 11 in run.ids and run.ids.index(12) > run.ids.index(11)


def test_feed_change_between_moves_is_reached_before_the_junction() -> None:
    tp = planner()
    tp.add_line(pose(20, 0, 0), 53.34, 53.34, AMAX, 1, is_rapid=True)
    tp.add_line(pose(30, 0, 0), 5.0, 53.34, AMAX, 2)
    run = Run(tp).until_done()
    run.assert_within_limits()
    vel, ids = np.array(run.vel), np.array(run.ids)
    assert max(vel) == pytest.approx(VMAX)
    assert vel[ids == 2].max() <= 5.0 + 1e-9


# ---------------------------------------------------------------------- overrides
def test_feed_override_applies_with_bounded_acceleration() -> None:  # MOT-040
    tp = planner()
    tp.add_line(pose(60, 0, 0), 20.0, 53.34, AMAX, 1)
    run = Run(tp)
    run.step(500)
    assert tp.vel == pytest.approx(20.0)
    tp.set_feed_scale(0.5)
    run.step(300)
    assert tp.vel == pytest.approx(10.0)
    tp.set_feed_scale(2.0)  # 40 mm/s asked, X is limited to 30.48
    run.step(300)
    assert tp.vel == pytest.approx(VMAX)
    tp.set_feed_scale(0.0)  # feed override 0 holds the motion
    run.step(300)
    assert tp.vel == 0 and not tp.is_done
    tp.set_feed_scale(1.0)
    run.until_done()
    run.assert_within_limits()
    assert run.path[-1][0] == pytest.approx(60)


def test_rapid_scale_only_affects_rapids() -> None:
    tp = planner()
    tp.set_rapid_scale(0.25)
    tp.add_line(pose(10, 0, 0), 53.34, 53.34, AMAX, 1, TermCond.STOP, is_rapid=True)
    tp.add_line(pose(20, 0, 0), 20.0, 53.34, AMAX, 2)
    run = Run(tp).until_done()
    vel, ids = np.array(run.vel), np.array(run.ids)
    assert vel[ids == 1].max() == pytest.approx(53.34 * 0.25)  # the scaled request
    assert vel[ids == 2].max() == pytest.approx(20.0)


def test_bad_scale_is_rejected() -> None:
    tp = planner()
    with pytest.raises(ValueError, match="scale"):
        tp.set_feed_scale(-1)
    with pytest.raises(ValueError, match="scale"):
        tp.set_rapid_scale(math.nan)


# ---------------------------------------------------------------------- pause, step, abort
def test_pause_decelerates_on_the_path_and_resume_continues_exactly() -> None:
    corner = [(0, 0, 0), (10, 0, 0), (10, 10, 0)]
    reference = planner()
    add_polyline(reference, corner, tolerance=0.1)
    ref_path = Run(reference).until_done().path

    tp = planner()
    add_polyline(tp, corner, tolerance=0.1)
    run = Run(tp)
    run.step(400)
    tp.pause()
    run.step(200)
    assert tp.is_paused and tp.vel == 0
    held = tp.pos.copy()
    run.step(100)
    assert np.array_equal(tp.pos, held)  # holds still
    tp.resume()
    run.until_done()
    run.assert_within_limits()
    path = run.path[:, :3]
    # every sample lies on the path of the uninterrupted run
    assert distance_to_polyline(path, ref_path[:, :3]).max() < 1e-3
    assert np.allclose(path[-1], corner[-1])


def test_a_pause_at_rest_holds_at_once_and_later_moves_wait_for_resume() -> None:
    """Task's M0/M1 pause motion with nothing queued: stat.paused reads true at once (as
    LinuxCNC's), and the moves after the stop wait for the resume."""
    tp = planner()
    tp.pause()
    assert tp.is_paused
    add_polyline(tp, [(0, 0, 0), (5, 0, 0)], tolerance=0.01)
    run = Run(tp)
    run.step(200)
    assert tp.vel == 0 and np.allclose(tp.pos[:3], 0) and tp.is_paused
    tp.resume()
    run.until_done()
    assert np.allclose(tp.pos[:3], (5, 0, 0)) and not tp.is_paused


def test_step_runs_to_the_end_of_the_current_move_then_pauses() -> None:  # MOT-039
    tp = planner()
    add_polyline(tp, [(0, 0, 0), (5, 0, 0), (5, 5, 0), (0, 5, 0)], tolerance=0.01)
    tp.pause()
    run = Run(tp)
    run.step(10)
    assert tp.vel == 0 and np.allclose(tp.pos[:3], 0)
    tp.step_once()
    run.step(2000)
    assert tp.is_paused and tp.vel == 0
    assert np.allclose(tp.pos[:3], (5, 0, 0), atol=1e-9)
    run.assert_within_limits()
    tp.resume()
    run.until_done()
    assert np.allclose(tp.pos[:3], (0, 5, 0))


def test_abort_decelerates_along_the_path_then_empties_the_queue() -> None:  # MOT-022
    tp = planner()
    add_polyline(tp, [(0, 0, 0), (20, 0, 0), (20, 20, 0)], tolerance=0.1)
    run = Run(tp)
    run.step(500)
    speed = tp.vel
    tp.abort()
    run.until_done()
    run.assert_within_limits()
    assert tp.queue_depth == 0 and tp.is_done
    path = run.path
    assert np.allclose(path[:, 1:], 0)  # stayed on the first line
    travelled = path[-1][0] - path[500][0]
    assert travelled == pytest.approx(speed**2 / (2 * AMAX), rel=0.05)


def test_abort_is_idempotent_and_cheap_when_idle() -> None:  # MOT-023
    tp = planner((1, 2, 3))
    for _ in range(5000):
        tp.abort()
    assert tp.is_done and np.allclose(tp.pos[:3], (1, 2, 3)) and tp.error is None
    tp.add_line(pose(2, 2, 3), 10.0, 53.34, AMAX, 1)
    Run(tp).until_done()
    assert np.allclose(tp.pos[:3], (2, 2, 3))


# ---------------------------------------------------------------------- probe
def test_probe_stops_on_the_edge_and_records_the_trip_position() -> None:  # MOT-056
    tp = planner()
    tp.add_probe(pose(20, 0, 0), 10.0, 53.34, AMAX, 5)
    tp.add_line(pose(20, 5, 0), 10.0, 53.34, AMAX, 6)
    run = Run(tp)
    while not tp.is_done:
        tp.probe_input = tp.pos[0] >= 7.0
        run.step()
    assert tp.probe_tripped
    assert 7.0 <= tp.probe_pos[0] < 7.0 + 10.0 * DT * 2
    assert tp.pos[0] - tp.probe_pos[0] <= 10.0**2 / (2 * AMAX) + 10.0 * DT * 2
    assert np.allclose(run.path[:, 1], 0)  # the following move was dropped
    run.assert_within_limits()
    tp.clear_probe_flag()
    assert not tp.probe_tripped


def test_probe_move_without_contact_reports_an_error() -> None:
    tp = planner()
    tp.add_probe(pose(2, 0, 0), 10.0, 53.34, AMAX, 5)
    Run(tp).until_done()
    assert not tp.probe_tripped
    assert "without the probe tripping" in tp.take_error()
    assert tp.take_error() is None


def test_probe_without_contact_is_fine_for_g38_3() -> None:
    tp = planner()
    tp.add_probe(pose(2, 0, 0), 10.0, 53.34, AMAX, 5, is_error_without_trip=False)
    Run(tp).until_done()
    assert not tp.probe_tripped and tp.take_error() is None
    assert tp.pos[0] == pytest.approx(2)


def test_probe_already_tripped_is_an_error() -> None:
    tp = planner()
    tp.probe_input = True
    tp.add_probe(pose(2, 0, 0), 10.0, 53.34, AMAX, 5)
    Run(tp).until_done()
    assert "already in the trip state" in tp.take_error()
    assert tp.pos[0] == 0


def test_probe_away_trips_on_loss_of_contact() -> None:
    tp = planner()
    tp.probe_input = True
    tp.add_probe(pose(-5, 0, 0), 10.0, 53.34, AMAX, 5, probe=ProbeType.AWAY)
    run = Run(tp)
    while not tp.is_done:
        tp.probe_input = tp.pos[0] > -1.0
        run.step()
    assert tp.probe_tripped and tp.probe_pos[0] <= -1.0


# ---------------------------------------------------------------------- input checks
def test_bad_moves_are_rejected_with_clear_errors() -> None:
    tp = planner()
    with pytest.raises(ValueError, match="not finite"):
        tp.add_line(pose(math.nan, 0, 0), 10, 50, AMAX)
    with pytest.raises(ValueError, match="velocity must be positive"):
        tp.add_line(pose(1, 0, 0), 0, 50, AMAX)
    with pytest.raises(ValueError, match="9 values"):
        tp.add_line([1, 2, 3], 10, 50, AMAX)
    with pytest.raises(ValueError, match="tolerance"):
        tp.add_line(pose(1, 0, 0), 10, 50, AMAX, tolerance=-1)
    with pytest.raises(ValueError, match="limits"):
        TrajectoryPlanner([1] * 9, [0] * 9)
    small = TrajectoryPlanner(LIMIT_V, LIMIT_A, DT, queue_size=2)
    small.add_line(pose(1, 0, 0), 10, 50, AMAX)
    small.add_line(pose(2, 0, 0), 10, 50, AMAX)
    assert small.is_full
    with pytest.raises(OverflowError, match="full"):
        small.add_line(pose(3, 0, 0), 10, 50, AMAX)


# ---------------------------------------------------------------------- module loading
def test_load_planner_default_and_incomplete_replacement() -> None:  # ARCH-008
    assert load_planner() is TrajectoryPlanner
    module = types.ModuleType("half_tp")

    class Half:
        def step(self):
            return None

        def add_line(self):
            return None

    module.Planner = Half
    sys.modules["half_tp"] = module
    try:
        with pytest.raises(ModuleInterfaceError) as info:
            load_planner("half_tp")
        message = str(info.value)
        assert "add_circle" in message and "abort" in message and "pause" in message
        assert "add_line," not in message
    finally:
        del sys.modules["half_tp"]


@settings(max_examples=20, deadline=None)
@given(
    steps=st.lists(
        st.tuples(
            st.booleans(),  # arc or line
            st.tuples(st.floats(-4, 4), st.floats(-4, 4), st.floats(-1, 1)),  # end
            st.tuples(st.floats(-3, 3), st.floats(-3, 3)),  # arc centre offset in its plane
            st.sampled_from([(0, 0, 1), (0, 0, -1), (0, 1, 0), (1, 0, 0)]),
            st.integers(0, 1),  # extra turns
        ),
        min_size=1,
        max_size=5,
    ),
    feed=st.floats(2, 40),
    term=st.sampled_from(list(TermCond)),
)
def test_any_mix_of_arcs_and_lines_stays_within_limits(steps, feed, term) -> None:
    tp = planner()
    here = np.zeros(3)
    for n, (is_arc, end, offset, normal, turns) in enumerate(steps, start=1):
        end = np.array(end)
        if is_arc:
            axes = [i for i in range(3) if normal[i] == 0]
            centre = here.copy()
            centre[axes[0]] += offset[0]
            centre[axes[1]] += offset[1]
            try:
                tp.add_circle(pose(*end), centre, normal, turns, feed, 53.34, AMAX, n, term)
            except ValueError:
                continue  # start or end on the centre: rejected, as it must be
        else:
            tp.add_line(pose(*end), feed, 53.34, AMAX, n, term)
        here = end
    run = Run(tp).until_done()
    run.assert_within_limits()
    assert np.allclose(run.path[-1][:3], here, atol=1e-9)
