"""rotarydeltakins: a rotary (Clavel) delta robot. Three hips on a circle of
``platformradius`` turn thighs of ``thighlength`` (joints 0-2, degrees; 0 straight out,
positive knee-down); shins of ``shinlength`` meet the effector at ``footradius``. The
origin is the centre of the hips' plane, so Z is negative below it. Joints 3-8 pass
A B C U V W through. Pins ``rotarydeltakins.platformradius`` (10), ``thighlength`` (10),
``shinlength`` (14), ``footradius`` (6).
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


class RotaryDeltaPins(RtComponent):
    platformradius = pin("float in", default=10.0)
    thighlength = pin("float in", default=10.0)
    shinlength = pin("float in", default=14.0)
    footradius = pin("float in", default=6.0)


def _radians(degrees: float) -> float:
    return degrees * math.pi / 180.0  # (as LinuxCNC's D2R rounds it)


class RotaryDelta:
    num_joints = 9
    joint_axes = list(range(9))
    axis_mask = 0x1FF

    def __init__(self, pins: Any) -> None:
        self.pins = pins

    def forward(self, joints: Sequence[float]) -> Pose:
        values = check_joints(joints, 3)
        rest = (values[3:] + [0.0] * 6)[:6]
        p = self.pins
        reach, thigh, shin = p.platformradius - p.footradius, p.thighlength, p.shinlength
        j0, j1, j2 = (_radians(v) for v in values[:3])
        y1 = -(reach + thigh * math.cos(j0))
        z1 = -thigh * math.sin(j0)
        y2 = (reach + thigh * math.cos(j1)) * 0.5
        x2 = y2 * math.sqrt(3)
        z2 = -thigh * math.sin(j1)
        y3 = (reach + thigh * math.cos(j2)) * 0.5
        x3 = -y3 * math.sqrt(3)
        z3 = -thigh * math.sin(j2)
        denom = x3 * (y2 - y1) - x2 * (y3 - y1)
        w1 = y1 * y1 + z1 * z1
        w2 = x2 * x2 + y2 * y2 + z2 * z2
        w3 = x3 * x3 + y3 * y3 + z3 * z3
        a1 = (z2 - z1) * (y3 - y1) - (z3 - z1) * (y2 - y1)
        b1 = -((w2 - w1) * (y3 - y1) - (w3 - w1) * (y2 - y1)) / 2.0
        a2 = -(z2 - z1) * x3 + (z3 - z1) * x2
        b2 = ((w2 - w1) * x3 - (w3 - w1) * x2) / 2.0
        a = a1 * a1 + a2 * a2 + denom * denom
        b = 2 * (a1 * b1 + a2 * (b2 - y1 * denom) - z1 * denom * denom)
        c = (
            (b2 - y1 * denom) * (b2 - y1 * denom)
            + b1 * b1
            + denom * denom * (z1 * z1 - shin * shin)
        )
        d = b * b - 4 * a * c
        if d < 0:
            raise SingularityError("rotarydeltakins: the shins cannot meet")
        z = (-b - math.sqrt(d)) / (2 * a)
        return Pose((a1 * z + b1) / denom, (a2 * z + b2) / denom, z, *rest)

    def _hip_angle(self, x: float, y: float, z: float) -> float:
        p = self.pins
        platform, thigh, shin, foot = p.platformradius, p.thighlength, p.shinlength, p.footradius
        if z == 0:
            raise KinematicsError("rotarydeltakins: the effector cannot be at Z 0")
        a = 0.5 * (x * x + (y - foot) ** 2 + z * z + thigh * thigh - shin * shin - platform**2) / z
        b = (foot - platform - y) / z
        d = thigh * thigh * (b * b + 1) - (a - b * platform) ** 2
        if d < 0:
            raise KinematicsError(f"rotarydeltakins: ({x:g}, {y:g}, {z:g}) is out of reach")
        knee_y = (platform + a * b + math.sqrt(d)) / (b * b + 1)
        knee_z = b * knee_y - a
        return math.atan2(knee_z, knee_y - platform) * 180.0 / math.pi

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        x, y, z = pose.x, pose.y, pose.z
        angles = [self._hip_angle(x, y, z)]
        for turn in (-2 * math.pi / 3, 2 * math.pi / 3):  # the other hips, by symmetry
            cos_t, sin_t = math.cos(turn), math.sin(turn)
            angles.append(self._hip_angle(x * cos_t - y * sin_t, x * sin_t + y * cos_t, z))
        return [*angles, pose.a, pose.b, pose.c, pose.u, pose.v, pose.w]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> RotaryDelta:
    return RotaryDelta(make_pins(RotaryDeltaPins, hal, "rotarydeltakins"))


rtapi_app_main: Any = realtime_module(create)
