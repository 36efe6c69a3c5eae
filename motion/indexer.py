"""Locking indexers: rotary joints held by a lock that must open before they move.

A joint with ``[JOINT_N]LOCKING_INDEXER = 1`` has two pins (``loadrt motmod
unlock_joints_mask=`` bit N): ``joint.N.unlock`` (out) asks the lock to open and
``joint.N.is-unlocked`` (in) says it is open. As LinuxCNC:

- homing asks for the unlock and waits for it before the joint moves, then locks it
  again (``motion.homing``);
- an axis with ``[AXIS_L]LOCKING_INDEXER_JOINT = N`` moves only alone, by G0 (the
  interpreter's rule). Such a coordinated move is an *indexing move*: it starts from rest
  and waits there until ``is-unlocked``; when it has ended, motion drops ``unlock`` and
  the next move waits until ``is-unlocked`` is false (the lock is back);
- the joint and its axis cannot be jogged (nor wheel-jogged);
- with motion off every unlock request is dropped.

``LockingIndexers.hold(tp)`` runs once per coordinated period before the planner's step;
its result holds the start of the next move (``tp.is_start_held``).
"""

from __future__ import annotations

from motion.joint import Joint
from nml.axes import AXIS_LETTERS


class LockingIndexers:
    def __init__(self, joints: list[Joint], unlock_joints_mask: int = 0) -> None:
        self.joints = joints
        # the joints with unlock pins (motmod unlock_joints_mask)
        self.has_pins = [bool(unlock_joints_mask >> j & 1) for j in range(len(joints))]
        self.axis_joint: dict[int, int] = {}  # axis index -> its locking joint
        self._active: tuple[object, int] | None = None  # (indexing move, joint)
        self._relocking: int | None = None  # joint whose lock we wait for

    def set_axis_joint(self, axis: int, joint: int) -> str | None:
        """[AXIS_L]LOCKING_INDEXER_JOINT (-1: none)."""
        if joint < 0:
            self.axis_joint.pop(axis, None)
            return None
        if joint >= len(self.joints):
            return f"locking indexer joint {joint} does not exist"
        self.axis_joint[axis] = joint
        return None

    def indexing_joint(self, start: list[float], end: list[float], requested: int) -> int:
        """The joint a coordinated move from ``start`` to ``end`` must unlock (-1: none):
        the one task named (EMC_TRAJ_LINEAR_MOVE.indexer_jnum), else that of the locking
        axis the move turns."""
        if requested >= 0:
            return requested
        for axis, joint in self.axis_joint.items():
            if end[axis] != start[axis]:
                return joint
        return -1

    def check_move(self, joint: int) -> str | None:
        if not 0 <= joint < len(self.joints):
            return f"locking indexer joint {joint} does not exist"
        if not self.has_pins[joint]:
            return (
                f"joint {joint} is a locking indexer but has no unlock pins: "
                f"loadrt motmod unlock_joints_mask=0x{1 << joint:X}"
            )
        return None

    def check_jog(
        self, joint: int | None, axis: int | None, is_locking_joint: bool = False
    ) -> str | None:
        """LinuxCNC: a locking indexer ([JOINT_N]LOCKING_INDEXER, ``is_locking_joint``) and
        its axis are moved by G0 or homing only."""
        if joint is not None and is_locking_joint:
            return f"cannot jog locking indexer joint {joint}"
        if axis is not None and axis in self.axis_joint:
            letter = AXIS_LETTERS[axis]
            return f"cannot jog locking indexer axis {letter} (joint {self.axis_joint[axis]})"
        return None

    def hold(self, move: object | None) -> bool:
        """One coordinated period, ``move`` the planner's current move: ask for the unlock
        of an indexing move and hold its start until the lock is open; once it has ended,
        drop the request and hold the next move until the lock is closed again."""
        joints = self.joints
        if self._active is not None and self._active[0] is not move:
            joint = self._active[1]
            joints[joint].is_unlock_requested = False
            self._relocking, self._active = joint, None
        if self._relocking is not None:
            if joints[self._relocking].is_unlocked:
                return True
            self._relocking = None
        joint = getattr(move, "indexer_joint", -1) if move is not None else -1
        if joint < 0:
            return False
        self._active = (move, joint)
        joints[joint].is_unlock_requested = True
        return not joints[joint].is_unlocked

    def release_all(self) -> None:
        """Motion off or abort: every unlock request dropped (homing asks again)."""
        for joint in self.joints:
            joint.is_unlock_requested = False
        self._active = None
