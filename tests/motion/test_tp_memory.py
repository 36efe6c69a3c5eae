"""The planner frees the moves it is done with, also with the garbage collector off as
in the realtime host (ARCH-017): moves that ran, and a whole queue dropped by an abort,
which it frees over the following servo periods."""

from __future__ import annotations

import gc

from motion.tp import TermCond, TrajectoryPlanner
from motion.tp.geometry import Piece
from motion.tp.planner import Move
from tests.motion.test_tp import AMAX, DT, LIMIT_A, LIMIT_V, pose


def alive() -> int:
    """Moves and pieces anywhere in this process."""
    return sum(isinstance(o, Move | Piece) for o in gc.get_objects())


def test_an_aborted_full_queue_is_freed(collector_off) -> None:
    tp = TrajectoryPlanner(LIMIT_V, LIMIT_A, DT, 53.34, AMAX, queue_size=1500)
    tp.set_position(pose(0.0, 0.0, 0.0))
    for n in range(1, 1501):  # a zigzag of short moves: lines and blend arcs
        tp.add_line(pose(0.02 * n, 0.01 * (n % 2)), 20.0, 53.34, AMAX, n, TermCond.BLEND)
    for _ in range(100):
        tp.step()
    tp.abort()
    for _ in range(10_000):
        tp.step()
        if tp.is_done and alive() == 0:
            break
    assert tp.is_done
    assert alive() == 0
    assert gc.collect() == 0
