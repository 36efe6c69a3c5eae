"""tripodkins: a tripod, three struts (joints 0-2, lengths) from base points A = (0, 0, 0),
B = (``tripodkins.Bx``, 0, 0) and C = (``Cx``, ``Cy``, 0) (all 1 by default) to the tool
point D = (X, Y, Z). Forward kinematics has two solutions, above and below the base plane:
it takes the side the last inverse kinematics was on (LinuxCNC's fflags), above at first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    KinematicsType,
    SingularityError,
    check_joints,
    check_pose,
    make_pins,
    realtime_module,
)
from nml.pose import Pose


class TripodPins(RtComponent):
    Bx = pin("float io", "Bx", default=1.0)
    Cx = pin("float io", "Cx", default=1.0)
    Cy = pin("float io", "Cy", default=1.0)


class TripodKins:
    num_joints = 3
    joint_axes = [0, 1, 2]
    axis_mask = 0b111

    def __init__(self, pins: Any) -> None:
        self.pins = pins
        self.is_below = False  # which side the last inverse kinematics was on

    def forward(self, joints: Sequence[float]) -> Pose:
        ad, bd, cd = check_joints(joints, 3)[:3]
        bx, cx, cy = self.pins.Bx, self.pins.Cx, self.pins.Cy
        p = ad * ad
        q = bd * bd - bx * bx
        r = cd * cd - cx * cx - cy * cy
        s, t, u = -2.0 * bx, -2.0 * cx, -2.0 * cy
        if s == 0.0 or u == 0.0:
            raise SingularityError("tripodkins: the base points coincide or are in a line")
        x = (q - p) / s
        y = (r - q - (t - s) * x) / u
        z2 = p - x * x - y * y
        if z2 < 0.0:
            raise SingularityError("tripodkins: the struts cannot meet")
        z = math.sqrt(z2)
        return Pose(x, y, -z if self.is_below else z)

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        bx, cx, cy = self.pins.Bx, self.pins.Cx, self.pins.Cy
        x, y, z = pose.x, pose.y, pose.z
        self.is_below = z < 0.0
        return [
            math.sqrt(x * x + y * y + z * z),
            math.sqrt((x - bx) ** 2 + y * y + z * z),
            math.sqrt((x - cx) ** 2 + (y - cy) ** 2 + z * z),
        ]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, 3)[:3]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> TripodKins:
    return TripodKins(make_pins(TripodPins, hal, "tripodkins"))


rtapi_app_main: Any = realtime_module(create)
