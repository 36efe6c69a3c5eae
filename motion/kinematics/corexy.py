"""CoreXY kinematics: two belts drive X and Y together.

Joint 0 = X + Y, joint 1 = X - Y; further joints map 1:1 to Z A B C U V W in order.
This is the template for a new module: ``create`` plus the four functions.
"""

from __future__ import annotations

from collections.abc import Sequence

from motion.kinematics import KinematicsError, KinematicsType, check_joints, check_pose
from motion.pose import AXIS_LETTERS, EmcPose


class CoreXY:
    def __init__(self, num_joints: int = 3) -> None:
        if not 2 <= num_joints <= len(AXIS_LETTERS):
            raise KinematicsError(f"corexy: num_joints must be 2..9, got {num_joints}")
        self.num_joints = num_joints
        self.axis_mask = (1 << num_joints) - 1

    def forward(self, joints: Sequence[float]) -> EmcPose:
        j = check_joints(joints, self.num_joints)
        world = [0.0] * len(AXIS_LETTERS)
        world[0] = 0.5 * (j[0] + j[1])
        world[1] = 0.5 * (j[0] - j[1])
        world[2 : self.num_joints] = j[2 : self.num_joints]
        return EmcPose(*world)

    def inverse(self, pose: EmcPose) -> list[float]:
        check_pose(pose)
        w = pose.as_tuple()
        return [w[0] + w[1], w[0] - w[1], *w[2 : self.num_joints]]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: EmcPose, joints: Sequence[float]) -> tuple[EmcPose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(num_joints: int | str = 3) -> CoreXY:
    return CoreXY(int(num_joints))
