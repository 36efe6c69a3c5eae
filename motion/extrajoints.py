"""Extra joints (``loadrt motmod num_extrajoints=N``, motion(9)).

The last N of motion's joints take part in homing (free mode, HOME_SEQUENCE, jogs before
homing) but not in kinematics: coordinated and teleop motion never move them. Once homed,
an extra joint follows its ``joint.N.posthome-cmd`` pin (joint coordinates) instead of
motion's planners, as LinuxCNC does; its following error is no longer checked (the motor
feedback is the HAL loop's business then) and it can be unhomed only with motion off.

Unlike LinuxCNC, which passes the pin's value to ``motor-pos-cmd`` as it is, the joint
follows it within its own MAX_VELOCITY and MAX_ACCELERATION and soft limits (a
``FreePlanner`` retargeted every period): a value that jumps (a HAL net set by hand, a
limit3 with other limits, the pin still at 0 when homing ends elsewhere) never steps the
motor. A command that already respects those limits (limit3 with the joint's limits, as in
LinuxCNC's sample configs) is followed to the same positions.
"""

from __future__ import annotations

import math

from motion.free import FreePlanner
from motion.joint import Joint


class ExtraJoints:
    """The extra joints of a motion controller: joints ``first`` .. end of ``joints``."""

    def __init__(self, joints: list[Joint], count: int) -> None:
        if not 0 <= count <= len(joints):
            raise ValueError(f"num_extrajoints must be 0..{len(joints)}, got {count}")
        self.count = count
        self.first = len(joints) - count  # the kinematic joints are 0 .. first - 1
        self.joints = joints[self.first :]
        self.posthome_cmd = [0.0] * count  # joint.N.posthome-cmd, set by the caller
        self._followers: list[FreePlanner | None] = [None] * count  # while homed

    def is_extra(self, index: int) -> bool:
        return index >= self.first

    def is_following(self, index: int) -> bool:
        """A homed extra joint: motion's planners leave it alone."""
        k = index - self.first
        return 0 <= k < self.count and self.joints[k].is_homed

    def step(self, dt: float) -> None:
        """One period (after the planners ran): each homed extra joint moves toward its
        posthome-cmd within its limits; an unhomed one is left to free mode."""
        for k, joint in enumerate(self.joints):
            follower = self._followers[k]
            if not joint.is_homed:
                self._followers[k] = None
                continue
            if follower is None:  # just homed: start where homing left it
                planner = joint.planner
                follower = FreePlanner(
                    planner.max_vel, planner.max_acc, planner.min_limit, planner.max_limit
                )
                follower.reset(joint.pos_cmd)
                self._followers[k] = follower
            target = self.posthome_cmd[k]
            if math.isfinite(target):
                target = min(max(target, follower.min_limit), follower.max_limit)
                if target != follower.target:
                    follower.move_to(target, follower.max_vel)
            joint.pos_cmd = follower.step(dt)
            joint.planner.reset(joint.pos_cmd)  # (free mode finds it at rest there)

    def check_jog(self, index: int) -> str | None:
        if self.is_following(index):
            return (
                f"joint {index} is an extra joint: once homed it follows "
                f"joint.{index}.posthome-cmd, it cannot be jogged"
            )
        return None

    def check_unhome(self, index: int, is_motion_enabled: bool) -> str | None:
        """LinuxCNC: extra joints may be unhomed only while motion is off."""
        if not is_motion_enabled:
            return None
        indices = range(self.first, self.first + self.count) if index == -1 else [index]
        for joint in indices:
            if self.is_following(joint):
                return f"cannot unhome extra joint {joint} with motion enabled"
        return None
