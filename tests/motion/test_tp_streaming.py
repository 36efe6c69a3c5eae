"""Moves queued while the planner runs, a few per servo period as motion's command handler
queues them (MOT-017, MOT-053): the lookahead's backward pass then spreads its work over
several periods, and the path must still keep every limit and tolerance, reach its end,
and run at the programmed feed where the queue stays ahead of the machine."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from motion.tp import TermCond, TrajectoryPlanner
from tests.motion.test_tp import (
    AMAX,
    DT,
    LIMIT_A,
    LIMIT_V,
    Run,
    assert_follows_polyline,
    distance_to_polyline,
    pose,
)


def stream(
    tp: TrajectoryPlanner,
    vertices: list[tuple[float, float, float]],
    adds_per_period: int,
    feed: float,
    term: TermCond = TermCond.BLEND,
    tolerance: float = 0.0,
    pause_at: int | None = None,
    accelerations: list[float] | None = None,
) -> Run:
    """Queue a line to each vertex after the first, at most ``adds_per_period`` per period
    while the queue has room, stepping until done; pause ``pause_at`` periods in for 300
    periods when given. ``accelerations`` gives each line's, else AMAX."""
    run = Run(tp)
    accelerations = accelerations or [AMAX] * (len(vertices) - 1)
    pending = list(enumerate(zip(vertices[1:], accelerations, strict=True), start=1))
    pending.reverse()
    periods = 0
    while pending or not tp.is_done:
        for _ in range(adds_per_period):
            if not pending or tp.is_full:
                break
            n, (vertex, acc) = pending.pop()
            tp.add_line(pose(*vertex), feed, 53.34, acc, n, term, tolerance)
        if periods == pause_at:
            tp.pause()
        elif pause_at is not None and periods == pause_at + 300:
            tp.resume()
        run.step()
        periods += 1
        assert periods < 500_000, "planner did not finish"
    return run


def test_dense_circle_streamed_runs_at_feed_without_stopping() -> None:
    # 7200 chords of 9 µm: one braking ramp spans about fifty pieces, more than one
    # period's share of the backward pass, so every pass takes a few periods
    count = 7200
    vertices = [
        (10 * math.cos(2 * math.pi * i / count), 10 * math.sin(2 * math.pi * i / count), 0.0)
        for i in range(count + 1)
    ]
    tp = TrajectoryPlanner(LIMIT_V, LIMIT_A, DT, max_vel=53.34, max_acc=AMAX)
    tp.set_position(pose(*vertices[0]))
    run = stream(tp, vertices, adds_per_period=3, feed=15.0, tolerance=0.001)
    run.assert_within_limits()
    assert distance_to_polyline(run.path[:, :3], np.array(vertices)).max() <= 0.001 + 1e-9
    assert np.allclose(run.path[-1][:3], vertices[-1], atol=1e-9)
    vel = np.array(run.vel)
    assert (vel[100:-100] > 15.0 - 1e-6).all()


def _polyline(start_angle: float, steps: list[tuple[float, ...]]) -> list[tuple]:
    """Vertices from the origin: each step turns by an angle, then goes a length (with a
    Z change)."""
    vertices = [(0.0, 0.0, 0.0)]
    angle = start_angle
    for turn, length, dz, _acc in steps:
        angle += turn
        x, y, z = vertices[-1]
        vertices.append((x + length * math.cos(angle), y + length * math.sin(angle), z + dz))
    return vertices


@settings(max_examples=25, deadline=None)
@given(
    start_angle=st.floats(-math.pi, math.pi),
    steps=st.lists(
        st.tuples(
            st.floats(-1.2, 1.2),  # turn (radians)
            st.floats(0.005, 0.4),  # length
            st.floats(-0.01, 0.01),  # Z change
            # the move's acceleration: a low one lowers the plan of the pieces before it
            st.sampled_from([AMAX, AMAX, AMAX, 20.0]),
        ),
        min_size=20,
        max_size=150,
    ),
    feed=st.floats(1, 50),
    tolerance=st.sampled_from([0.0, 0.001, 0.05]),
    term=st.sampled_from(list(TermCond)),
    adds_per_period=st.integers(1, 4),
    queue_size=st.sampled_from([8, 40, 2000]),
    pause_at=st.one_of(st.none(), st.integers(0, 400)),
)
def test_any_streamed_dense_polyline_stays_within_limits_and_tolerance(
    start_angle, steps, feed, tolerance, term, adds_per_period, queue_size, pause_at
) -> None:
    vertices = _polyline(start_angle, steps)
    tp = TrajectoryPlanner(LIMIT_V, LIMIT_A, DT, 53.34, AMAX, queue_size=queue_size)
    tp.set_position(pose(0.0, 0.0, 0.0))
    accelerations = [step[3] for step in steps]
    run = stream(tp, vertices, adds_per_period, feed, term, tolerance, pause_at, accelerations)
    assert_follows_polyline(run, vertices, term, tolerance)
