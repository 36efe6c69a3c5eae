"""scorbot-kins: the Scorbot ER-3 arm (joints in degrees). Joint 0 turns the arm about Z and
picks the vertical plane the rest moves in; the shoulder (joint 1) sits 16 mm out and
140 mm up from the origin (the centre of joint 0 at the bottom of the base plate); the
upper arm and the forearm (joint 2's angle is from the horizontal, as joint 1's) are both
221 mm long. The controlled point is the wrist; its pitch and roll (joints 3, 4) pass
through to A and B (a differential in HAL drives the motors). The elbow is always up.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from motion.kinematics import (
    TO_DEG,
    TO_RAD,
    HalContext,
    KinematicsError,
    KinematicsType,
    check_joints,
    check_pose,
    realtime_module,
)
from nml.pose import Pose

SHOULDER_OUT, SHOULDER_UP = 16.0, 140.0  # link 0: origin to the shoulder
UPPER_ARM = FOREARM = 221.0  # links 1 and 2


class Scorbot:
    num_joints = 5
    joint_axes = [0, 1, 2, 3, 4]
    axis_mask = 0b11111  # X Y Z A B

    def forward(self, joints: Sequence[float]) -> Pose:
        j = check_joints(joints, self.num_joints)
        reach = (
            SHOULDER_OUT + UPPER_ARM * math.cos(TO_RAD * j[1]) + FOREARM * math.cos(TO_RAD * j[2])
        )
        height = (
            SHOULDER_UP + UPPER_ARM * math.sin(TO_RAD * j[1]) + FOREARM * math.sin(TO_RAD * j[2])
        )
        turn = TO_RAD * j[0]
        return Pose(reach * math.cos(turn), reach * math.sin(turn), height, j[3], j[4])

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        # the wrist relative to the shoulder, in the arm's plane
        r = math.hypot(pose.x, pose.y) - SHOULDER_OUT
        z = pose.z - SHOULDER_UP
        distance = math.hypot(r, z)
        if distance == 0.0 or distance > UPPER_ARM + FOREARM:
            raise KinematicsError(
                f"scorbot-kins: X{pose.x:g} Y{pose.y:g} Z{pose.z:g} is out of the arm's reach"
            )
        to_wrist = math.atan2(z, r)
        # the arms make an isosceles triangle over the shoulder-wrist line
        shoulder = to_wrist + math.acos(distance / 2 / UPPER_ARM)
        forearm = -math.asin(min(max((UPPER_ARM * math.sin(shoulder) - z) / FOREARM, -1.0), 1.0))
        return [
            TO_DEG * math.atan2(pose.y, pose.x),
            TO_DEG * shoulder,
            TO_DEG * forearm,
            pose.a,
            pose.b,
        ]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> Scorbot:
    return Scorbot()


rtapi_app_main: Any = realtime_module(create)
