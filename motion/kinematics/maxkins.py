"""maxkins: Chris Radek's tabletop 5-axis mill 'max': a tilting head (B, turning the
opposite way to the convention) and a rotary table (C). The tool's pivot point is
``maxkins.pivot-length`` (default 0.666) above the tool tip, plus W; U and V move the tool
across the head. Nine joints, one per axis.

As LinuxCNC's, the two transformations are each other's inverse only while the table (C)
is at 0 or the head (B), U and V are: the head's offsets are added after turning the table
one way and taken off before turning it the other; and U moves Z by U sin(B) both ways.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    NineJointKins,
    check_pose,
    make_pins,
    realtime_module,
)
from nml.pose import Pose


def _rad(degrees: float) -> float:
    return degrees * math.pi / 180.0


class MaxPins(RtComponent):
    pivot_length = pin("float io", default=0.666)


class MaxKins(NineJointKins):
    def __init__(self, pins: Any) -> None:
        self.pins = pins

    def forward(self, joints: Sequence[float]) -> Pose:
        j = self.joints_of(joints)
        arm = self.pins.pivot_length + j[8]
        b = _rad(j[4])
        zb, xb = arm * math.cos(b), arm * math.sin(b)
        radius = math.hypot(j[0], j[1])
        theta = math.atan2(j[1], j[0]) + _rad(j[5])
        zv, xv = j[6] * math.sin(b), j[6] * math.cos(b)
        return Pose(
            radius * math.cos(theta) + xb - xv,
            radius * math.sin(theta) - j[7],
            j[2] - zb + zv + self.pins.pivot_length,
            *j[3:9],
        )

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        arm = self.pins.pivot_length + pose.w
        b = _rad(pose.b)
        zb, xb = arm * math.cos(b), arm * math.sin(b)
        radius = math.hypot(pose.x, pose.y)
        theta = math.atan2(pose.y, pose.x) - _rad(pose.c)
        zv, xv = pose.u * math.sin(b), pose.u * math.cos(b)
        return [
            radius * math.cos(theta) - xb + xv,
            radius * math.sin(theta) + pose.v,
            pose.z + zb + zv - self.pins.pivot_length,
            pose.a,
            pose.b,
            pose.c,
            pose.u,
            pose.v,
            pose.w,
        ]


def create(hal: HalContext | None = None) -> MaxKins:
    return MaxKins(make_pins(MaxPins, hal, "maxkins"))


rtapi_app_main: Any = realtime_module(create)
