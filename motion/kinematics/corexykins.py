"""corexykins: CoreXY kinematics, two belts drive X and Y together.

Joint 0 = X + Y, joint 1 = X - Y; joints 2... map 1:1 to Z A B C U V W in order (as
LinuxCNC's, all nine; a motion of fewer joints sees the first ones, ``fit_joints``). This
is the template for a new module: ``create`` plus the four functions, and
``rtapi_app_main`` at the end.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from motion.kinematics import (
    HalContext,
    KinematicsType,
    check_joints,
    check_pose,
    realtime_module,
)
from nml.pose import AXIS_NAMES, Pose


class CoreXY:
    num_joints = 9
    joint_axes = list(range(9))  # (joints 0 and 1 together drive X and Y)
    axis_mask = 0x1FF

    def forward(self, joints: Sequence[float]) -> Pose:
        j = check_joints(joints, self.num_joints)
        world = [0.0] * len(AXIS_NAMES)
        world[0] = 0.5 * (j[0] + j[1])
        world[1] = 0.5 * (j[0] - j[1])
        world[2:9] = j[2:9]
        return Pose(*world)

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        w = pose.as_tuple()
        return [w[0] + w[1], w[0] - w[1], *w[2:9]]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> CoreXY:
    return CoreXY()


rtapi_app_main: Any = realtime_module(create)
