"""The planner's per-move geometry keeps numpy's arithmetic where it avoids numpy's calls
(cross products, norms, blend arcs, cached line ends): same values, bit for bit."""

from __future__ import annotations

import math

import numpy as np

from motion.tp.geometry import LinePiece, blend_arc, circle_piece, cross3, norm
from nml.axes import NUM_AXES

RNG = np.random.default_rng(20261121)


def test_cross3_and_norm_are_numpys() -> None:
    for _ in range(200):
        a, b = RNG.normal(size=3) * 10.0, RNG.normal(size=3)
        assert np.array_equal(cross3(a, b), np.cross(a, b))
        v = RNG.normal(size=NUM_AXES) * RNG.uniform(1e-3, 1e3)
        assert norm(v) == float(np.linalg.norm(v))
        assert norm(a) == float(np.linalg.norm(a))


def test_line_end_follows_trims() -> None:
    start, end = RNG.normal(size=NUM_AXES), RNG.normal(size=NUM_AXES)
    line = LinePiece(None, start, end)
    assert np.array_equal(line.end, line.start + line.direction * line.length)
    line.trim_start(0.1 * line.length)
    assert np.array_equal(line.end, line.start + line.direction * line.length)
    line.trim_end(0.2 * line.length)
    assert np.array_equal(line.end, line.start + line.direction * line.length)


def _reference_blend(
    corner: np.ndarray, u1: np.ndarray, u2: np.ndarray, radius: float, turn: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The blend arc's centre and axes as first written (numpy throughout)."""
    d = radius * math.tan(0.5 * turn)
    inward = u2 - math.cos(turn) * u1
    inward /= math.hypot(*inward.tolist())
    centre = (corner - u1 * d) + inward * radius
    return centre, -inward, u1


def test_blend_arc_is_the_reference_arc() -> None:
    for _ in range(200):
        corner = RNG.normal(size=NUM_AXES) * 50.0
        u1, u2 = np.zeros(NUM_AXES), np.zeros(NUM_AXES)
        u1[:3], u2[:3] = RNG.normal(size=3), RNG.normal(size=3)
        u1 /= np.linalg.norm(u1)
        u2 /= np.linalg.norm(u2)
        turn = math.acos(max(-1.0, min(1.0, float(u1 @ u2))))
        radius = RNG.uniform(1e-3, 10.0)
        arc = blend_arc(None, corner, u1, u2, radius, turn)
        centre, e1, e2 = _reference_blend(corner, u1, u2, radius, turn)
        assert np.array_equal(arc.centre, centre)
        assert np.array_equal(arc.e1, e1)
        assert np.array_equal(arc.e2, e2)


def test_arc_points_with_and_without_h() -> None:
    start = np.zeros(NUM_AXES)
    start[:3] = (10.0, 0.0, 0.0)
    for is_helix in (False, True):
        end = start.copy()
        end[:3] = (0.0, 10.0, 5.0 if is_helix else 0.0)
        arc = circle_piece(None, start, end, np.zeros(3), np.array([0.0, 0.0, 1.0]), 0)
        assert arc.has_h is is_helix
        for s in np.linspace(0.0, arc.length, 7):
            phi = s * arc.k
            r = arc.r0 + arc.dr * phi
            expected = (
                arc.centre
                + (r * math.cos(phi)) * arc.e1
                + (r * math.sin(phi)) * arc.e2
                + arc.h * phi
            )
            assert np.array_equal(arc.point(s), expected)
        assert np.allclose(arc.point(arc.length), end)
