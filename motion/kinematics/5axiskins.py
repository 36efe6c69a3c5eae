# ruff: noqa: N999 - named as LinuxCNC's module, which loadrt finds by name
"""5axiskins: a bridge mill with a tilting (B) and swivelling (C) spindle head; the tool tip
stays on the programmed point as the head turns (tool-centre-point). The pivot is
``5axiskins.pivot-length`` (default 250) above the tip, plus W (the tool's extension).
``coordinates=`` (default XYZBCW, which it needs) maps joints as trivkins does.
Switchable (``motion.switchkins-type``): type 0 these kinematics, 1 identity (swapped with
``sparm=identityfirst``), 2 the user type.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    TO_RAD,
    HalContext,
    JointMap,
    KinematicsError,
    SwitchKins,
    make_pins,
    realtime_module,
    switchkins_types,
)
from nml.pose import Pose

REQUIRED = "xyzbcw"


class FiveAxisPins(RtComponent):
    pivot_length = pin("float in", default=250.0)


def _arm(length: float, turn_degrees: float, tilt_degrees: float) -> tuple[float, ...]:
    """A vector of ``length`` at spherical angles: azimuth ``turn``, polar ``tilt``."""
    theta, phi = TO_RAD * turn_degrees, TO_RAD * tilt_degrees
    return (
        length * math.sin(phi) * math.cos(theta),
        length * math.sin(phi) * math.sin(theta),
        length * math.cos(phi),
    )


class FiveAxis:
    def __init__(self, joints: JointMap, pins: Any) -> None:
        self.map = joints
        self.pins = pins
        self.j = {c: joints.joint_of(c) for c in "xyzabcuvw"}

    def forward(self, joints: Sequence[float]) -> Pose:
        j, pivot = self.j, self.pins.pivot_length
        rx, ry, rz = _arm(pivot + joints[j["w"]], joints[j["c"]], 180.0 - joints[j["b"]])

        def value(letter: str) -> float:
            return joints[j[letter]] if j[letter] != -1 else 0.0

        return Pose(
            x=joints[j["x"]] + rx,
            y=joints[j["y"]] + ry,
            z=joints[j["z"]] + pivot + rz,
            a=value("a"),
            b=joints[j["b"]],
            c=joints[j["c"]],
            u=value("u"),
            v=value("v"),
            w=joints[j["w"]],
        )

    def inverse(self, pose: Pose) -> list[float]:
        j, pivot = self.j, self.pins.pivot_length
        rx, ry, rz = _arm(pivot + pose.w, pose.c, 180.0 - pose.b)
        result = Pose(
            x=pose.x - rx,
            y=pose.y - ry,
            z=pose.z - pivot - rz,
            a=pose.a if j["a"] != -1 else 0.0,
            b=pose.b,
            c=pose.c,
            u=pose.u if j["u"] != -1 else 0.0,
            v=pose.v if j["v"] != -1 else 0.0,
            w=pose.w,
        )
        return self.map.to_joints(result)


def create(
    coordinates: str = REQUIRED, sparm: str = "", hal: HalContext | None = None
) -> SwitchKins:
    joints = JointMap(coordinates or REQUIRED, "5axiskins", max_joints=16)
    missing = [c for c in REQUIRED if c not in joints.letters]
    if missing:
        raise KinematicsError(
            f"5axiskins: required coordinates {REQUIRED}, specified {coordinates}"
        )
    own = FiveAxis(joints, make_pins(FiveAxisPins, hal, "5axiskins"))
    return SwitchKins(switchkins_types(own, joints, sparm, hal), joints, hal)


rtapi_app_main: Any = realtime_module(create)
