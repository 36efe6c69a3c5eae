"""G64 blending of corners where a line meets an arc or two arcs meet (MOT-017, MOT-062):
a tangent arc cuts the corner within the tolerance instead of stopping there."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motion.tp import TermCond
from tests.motion.test_tp import AMAX, Run, distance_to_polyline, planner, pose

FEED = 25.0


def distance_to_arc(points: np.ndarray, centre, radius: float, start: float, sweep: float):
    """Distance of XY points to the arc from angle ``start`` turning ``sweep`` radians."""
    rel = points[:, :2] - np.array(centre)
    angle = np.arctan2(rel[:, 1], rel[:, 0])
    offset = np.mod((angle - start) * np.sign(sweep), 2 * math.pi)
    inside = offset <= abs(sweep)
    on_circle = np.abs(np.linalg.norm(rel, axis=1) - radius)
    ends = [np.array(centre) + radius * np.array([math.cos(a), math.sin(a)])
            for a in (start, start + sweep)]  # fmt: skip
    to_ends = np.min([np.linalg.norm(points[:, :2] - e, axis=1) for e in ends], axis=0)
    return np.where(inside, on_circle, to_ends)


def run_contour(term: TermCond, tolerance: float) -> Run:
    """Line, 90-degree corner into a half circle, corner into a 3/4 circle, corner into
    a line: every junction a real corner."""
    tp = planner()
    tp.add_line(pose(10, 0), FEED, 53.34, AMAX, 1, term, tolerance)
    # counter-clockwise about (15, 0) from (10, 0) down through (15, -5) to (20, 0)
    tp.add_circle(pose(20, 0), (15, 0, 0), (0, 0, 1), 0, FEED, 53.34, AMAX, 2, term, tolerance)
    # arrives going +Y; counter-clockwise about (20, -5): leaves going -X, ends at (25, -5)
    tp.add_circle(pose(25, -5), (20, -5, 0), (0, 0, 1), 0, FEED, 53.34, AMAX, 3, term, tolerance)
    # arrives going +Y; the line goes +X
    tp.add_line(pose(35, -5), FEED, 53.34, AMAX, 4, term, tolerance)
    return Run(tp).until_done()


def contour_distance(points: np.ndarray) -> np.ndarray:
    return np.min(
        [
            distance_to_polyline(points[:, :3], np.array([(0, 0, 0), (10, 0, 0)], float)),
            distance_to_arc(points, (15, 0), 5.0, math.pi, math.pi),
            distance_to_arc(points, (20, -5), 5.0, math.pi / 2, 1.5 * math.pi),
            distance_to_polyline(points[:, :3], np.array([(25, -5, 0), (35, -5, 0)], float)),
        ],
        axis=0,
    )


# (0.04: the one tolerance where the planner blends two corners and stops at the third;
# below 0.035 it stops at all three, from 0.045 it blends all)
@pytest.mark.parametrize("tolerance", [0.04, 0.5])
def test_corners_with_arcs_are_blended_within_the_tolerance(tolerance: float) -> None:
    stop = run_contour(TermCond.STOP, 0.0)
    blend = run_contour(TermCond.BLEND, tolerance)
    blend.assert_within_limits()
    path = blend.path
    assert contour_distance(path).max() <= tolerance + 1e-9
    assert np.allclose(path[-1][:3], (35, -5, 0))
    assert len(blend.pos) < len(stop.pos)
    at_rest = np.array(blend.vel)[1:-1] == 0
    if tolerance >= 0.5:
        assert not at_rest.any()  # no stop at any corner
    else:  # a small tolerance makes a slow arc: only where it beats stopping
        assert at_rest.sum() == 1


def test_exact_stop_still_stops_at_arc_corners() -> None:
    run = run_contour(TermCond.STOP, 0.0)
    run.assert_within_limits()
    assert contour_distance(run.path).max() < 1e-9
    at_corner = np.linalg.norm(run.path[:, :2] - (20.0, 0.0), axis=1) < 1e-12
    assert (np.array(run.vel)[at_corner] == 0).any()
