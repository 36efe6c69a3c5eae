"""Task sends motion one command per move: the line of EMC_TRAJ_SET_MOTION_ID travels in the
move that follows it (its ``id``), as LinuxCNC's task fills emcmotCommand.id."""

from __future__ import annotations

from types import SimpleNamespace

from nml import emc
from task.controller import LineQueue, Task


def stamp(*queued: emc.NMLmsg) -> bool:
    task = SimpleNamespace(queue=LineQueue(queued))
    return Task._stamp_next_move(task, queued[0].id)


def test_the_move_after_a_motion_id_carries_it() -> None:
    for move in (
        emc.EMC_TRAJ_LINEAR_MOVE(),
        emc.EMC_TRAJ_CIRCULAR_MOVE(),
        emc.EMC_TRAJ_PROBE(),
        emc.EMC_TRAJ_RIGID_TAP(),
    ):
        assert stamp(emc.EMC_TRAJ_SET_MOTION_ID(id=9), move)
        assert move.id == 9


def test_a_motion_id_without_a_move_after_it_is_sent_as_it_is() -> None:
    assert not stamp(emc.EMC_TRAJ_SET_MOTION_ID(id=9))
    assert not stamp(emc.EMC_TRAJ_SET_MOTION_ID(id=9), emc.EMC_TRAJ_SET_TERM_COND())
    line_zero = emc.EMC_TRAJ_LINEAR_MOVE()
    assert not stamp(emc.EMC_TRAJ_SET_MOTION_ID(id=0), line_zero)  # 0 means "the last id"
