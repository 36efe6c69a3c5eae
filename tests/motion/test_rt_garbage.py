"""Motion leaves no reference cycles behind (ARCH-017); an aborted queue: test_tp_memory.py.

The realtime host runs with the garbage collector disabled, so that no collection pause
lands in a servo period: any cycle a period makes is never freed. Leaked memory then grows
the heap from the servo thread, and with memory locked every new page is faulted in there,
which overran 1 ms periods about once a second during a dense program.
"""

from __future__ import annotations

import gc

import pytest

from motion.controller import COORD, FREE
from motion.tp import TermCond
from nml import emc
from tests.motion.test_controller import enabled_homed, move, run
from tests.motion.test_tp import Run, planner, pose


def garbage() -> int:
    """How many unreachable objects (cycles) collected now."""
    return gc.collect()


@pytest.mark.parametrize("term", [TermCond.BLEND, TermCond.EXACT, TermCond.STOP])
def test_planner_moves_that_ran_leave_no_cycles(collector_off, term) -> None:
    tp = planner()
    for i in range(200):
        tp.add_line(pose(0.1 * (i + 1), 0.1 * (i % 2)), 20.0, 30.0, 500.0, i, term, 0.05, False)
        tp.step()
    # a half circle from where the lines end (X20 Y0.1), counter-clockwise about Z
    centre, normal = [20.0, 5.1, 0.0], [0.0, 0.0, 1.0]
    tp.add_circle(pose(20.0, 10.1), centre, normal, 0, 20.0, 30.0, 500.0, 300, term)
    Run(tp).until_done()
    assert garbage() == 0


def test_controller_periods_leave_no_cycles(collector_off) -> None:
    """A program's worth of moves, status every period, then jogs in free mode."""
    motion = enabled_homed(COORD)
    stat = emc.EMC_MOTION_STAT()
    for i in range(100):
        assert motion.handle(move(0.2 * (i + 1), 0.2 * (i % 2))) is None
        run(motion, 2)
        motion.fill_status(stat)
    for _ in range(5_000):
        run(motion, 1)
        motion.fill_status(stat)
        if motion.tp.is_done and motion.is_in_position:
            break
    assert motion.tp.is_done
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=FREE)) is None
    jog = emc.EMC_JOG_INCR(joint_or_axis=0, incr=1.0, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(jog) is None
    run(motion, 500)
    motion.fill_status(stat)
    assert garbage() == 0
