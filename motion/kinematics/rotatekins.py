"""rotatekins: X and Y turned by the C axis: the machine's X/Y joints are the world's X/Y
rotated by C degrees (a rotary table under an XY stage); the other joints are 1:1."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from motion.kinematics import HalContext, NineJointKins, check_pose, realtime_module
from nml.pose import Pose


class RotateKins(NineJointKins):
    def forward(self, joints: Sequence[float]) -> Pose:
        j = self.joints_of(joints)
        c = -j[5] * math.pi / 180
        return Pose(
            j[0] * math.cos(c) - j[1] * math.sin(c),
            j[0] * math.sin(c) + j[1] * math.cos(c),
            *j[2:9],
        )

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        c = pose.c * math.pi / 180
        return [
            pose.x * math.cos(c) - pose.y * math.sin(c),
            pose.x * math.sin(c) + pose.y * math.cos(c),
            *pose.as_tuple()[2:],
        ]


def create(hal: HalContext | None = None) -> RotateKins:
    return RotateKins()


rtapi_app_main: Any = realtime_module(create)
