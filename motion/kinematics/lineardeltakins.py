"""lineardeltakins: a linear (Rostock-style) delta robot. Three towers stand at 120 degrees
on a circle of radius ``R`` (tower 0 at (0, R)); a rod of length ``L`` joins each tower's
carriage (joints 0-2, heights) to the effector. Joints 3-8 pass A B C U V W through.
Pins ``lineardeltakins.R`` (default 130.25) and ``lineardeltakins.L`` (269), read at
every call.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    KinematicsError,
    KinematicsType,
    SingularityError,
    check_joints,
    check_pose,
    make_pins,
    realtime_module,
)
from nml.pose import Pose

DELTA_DIAGONAL_ROD = 269.0
DELTA_RADIUS = 198.25 - 33.0 - 35.0  # smooth rod offset - effector and carriage offsets
SIN_60, COS_60 = math.sqrt(3) / 2, 0.5


class DeltaPins(RtComponent):
    R = pin("float in", "R", default=DELTA_RADIUS)
    L = pin("float in", "L", default=DELTA_DIAGONAL_ROD)


class LinearDelta:
    num_joints = 9
    joint_axes = list(range(9))
    axis_mask = 0x1FF

    def __init__(self, pins: Any) -> None:
        self.pins = pins

    def _towers(self) -> tuple[float, float, tuple[float, ...]]:
        radius, rod = self.pins.R, self.pins.L
        towers = (
            0.0,
            radius,
            -SIN_60 * radius,
            -COS_60 * radius,
            SIN_60 * radius,
            -COS_60 * radius,
        )
        return radius, rod, towers

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        _, rod, (ax, ay, bx, by, cx, cy) = self._towers()
        x, y, z = pose.x, pose.y, pose.z
        rod2 = rod * rod
        heights = []
        for tx, ty in ((ax, ay), (bx, by), (cx, cy)):
            under = rod2 - (tx - x) ** 2 - (ty - y) ** 2
            if under < 0:
                raise KinematicsError(f"lineardeltakins: ({x:g}, {y:g}) is out of reach")
            heights.append(z + math.sqrt(under))
        return [*heights, pose.a, pose.b, pose.c, pose.u, pose.v, pose.w]

    def forward(self, joints: Sequence[float]) -> Pose:
        q1, q2, q3, *rest = check_joints(joints, 3)
        rest = (rest + [0.0] * 6)[:6]
        _, rod, (_ax, ay, bx, by, cx, cy) = self._towers()
        den = (by - ay) * cx - (cy - ay) * bx
        w1 = ay * ay + q1 * q1  # (tower 0 is on the Y axis: ax is 0)
        w2 = bx * bx + by * by + q2 * q2
        w3 = cx * cx + cy * cy + q3 * q3
        a1 = (q2 - q1) * (cy - ay) - (q3 - q1) * (by - ay)
        b1 = -((w2 - w1) * (cy - ay) - (w3 - w1) * (by - ay)) / 2.0
        a2 = -(q2 - q1) * cx + (q3 - q1) * bx
        b2 = ((w2 - w1) * cx - (w3 - w1) * bx) / 2.0
        a = a1 * a1 + a2 * a2 + den * den
        b = 2 * (a1 * b1 + a2 * (b2 - ay * den) - q1 * den * den)
        c = (b2 - ay * den) * (b2 - ay * den) + b1 * b1 + den * den * (q1 * q1 - rod * rod)
        discriminant = b * b - 4.0 * a * c
        if discriminant < 0:
            raise SingularityError("lineardeltakins: the rods cannot meet")
        z = -0.5 * (b + math.sqrt(discriminant)) / a
        return Pose((a1 * z + b1) / den, (a2 * z + b2) / den, z, *rest)

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> LinearDelta:
    return LinearDelta(make_pins(DeltaPins, hal, "lineardeltakins"))


rtapi_app_main: Any = realtime_module(create)
