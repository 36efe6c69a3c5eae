"""rosekins: the rose engine, a lathe-like machine whose joints are radius (0), Z (1) and
the work's rotation in degrees (2); X and Y are cartesian. The rotation counts whole turns
as the path crosses the -X axis (``rosekins.revolutions``, ``theta_degrees`` and
``bigtheta_degrees`` show it), so it keeps turning the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    TO_DEG,
    TO_RAD,
    HalContext,
    NineJointKins,
    check_pose,
    make_pins,
    realtime_module,
)
from nml.pose import Pose


class RosePins(RtComponent):
    revolutions = pin("float out")
    theta_degrees = pin("float out", "theta_degrees")
    bigtheta_degrees = pin("float out", "bigtheta_degrees")


class RoseKins(NineJointKins):
    def __init__(self, pins: Any) -> None:
        self.pins = pins
        self.old_quadrant = 0
        self.turns = 0

    def forward(self, joints: Sequence[float]) -> Pose:
        j = self.joints_of(joints)
        theta = TO_RAD * j[2]
        return Pose(j[0] * math.cos(theta), j[0] * math.sin(theta), j[1])

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        x, y = pose.x, pose.y
        quadrant = (1 if y >= 0 else 4) if x >= 0 else (2 if y >= 0 else 3)
        if self.old_quadrant == 2 and quadrant == 3:
            self.turns += 1
        if self.old_quadrant == 3 and quadrant == 2:
            self.turns -= 1
        self.old_quadrant = quadrant
        theta = math.atan2(y, x)
        big_theta = theta + 2 * math.pi * self.turns
        self.pins.revolutions = self.turns
        self.pins.theta_degrees = theta * TO_DEG
        self.pins.bigtheta_degrees = big_theta * TO_DEG
        return [math.hypot(x, y), pose.z, TO_DEG * big_theta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]


def create(hal: HalContext | None = None) -> RoseKins:
    return RoseKins(make_pins(RosePins, hal, "rosekins"))


rtapi_app_main: Any = realtime_module(create)
