"""xyzab_tdr_kins: a 5-axis machine with two rotary tables, A tilting and B turning on it
(table dual rotary), with tool-centre-point control. Switchable: type 0 (the start)
identity, type 1 the TCP kinematics, from pins ``xyzab_tdr_kins.x-rot-point``,
``y-rot-point``, ``z-rot-point``, ``x-offset``, ``z-offset`` and ``tool-offset-z``. As in
LinuxCNC it is a HAL component too (``xyzab-tdr-kins.0.dummy``); joints 0-4 are X Y Z A B.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from hal.core import HalError
from motion.kinematics import (
    TO_RAD,
    HalContext,
    JointMap,
    SwitchKins,
    make_pins,
)
from nml.pose import Pose


class TdrPins(RtComponent):
    tool_offset_z = pin("float in")
    x_offset = pin("float in")
    z_offset = pin("float in")
    x_rot_point = pin("float in")
    y_rot_point = pin("float in")
    z_rot_point = pin("float in")


class TdrInstance(RtComponent):
    dummy = pin("s32 out")


class Identity5:
    """Type 0: X Y Z A B straight through (C U V W are 0)."""

    def forward(self, joints: Sequence[float]) -> Pose:
        return Pose(*joints[:5])

    def inverse(self, pose: Pose) -> list[float]:
        return [pose.x, pose.y, pose.z, pose.a, pose.b]


class Tdr:
    """Type 1: tool-centre-point through table A and the table B on it."""

    def __init__(self, pins: Any) -> None:
        self.pins = pins

    def forward(self, j: Sequence[float]) -> Pose:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dz, dt = p.z_offset, p.tool_offset_z
        sa, ca = math.sin(j[3] * TO_RAD), math.cos(j[3] * TO_RAD)
        sb, cb = math.sin(j[4] * TO_RAD), math.cos(j[4] * TO_RAD)
        px, py, pz = j[0] - rx, j[1] - ry, j[2] - rz - dt
        return Pose(
            x=cb * px + sb * pz + rx,
            y=sa * sb * px + ca * py - cb * sa * pz + sa * dz + ry,
            z=-ca * sb * px + sa * py + ca * cb * pz - ca * dz + rz + dz + dt,
            a=j[3],
            b=j[4],
        )

    def inverse(self, pose: Pose) -> list[float]:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dx, dz, dt = p.x_offset, p.z_offset, p.tool_offset_z
        sa, ca = math.sin(pose.a * TO_RAD), math.cos(pose.a * TO_RAD)
        sb, cb = math.sin(pose.b * TO_RAD), math.cos(pose.b * TO_RAD)
        qx, qy, qz = pose.x - rx - dx, pose.y - ry, pose.z - rz - dz - dt
        return [
            cb * qx + sa * sb * qy - ca * sb * qz + cb * dx - sb * dz + rx,
            ca * qy + sa * qz + ry,
            sb * qx - sa * cb * qy + ca * cb * qz + sb * dx + cb * dz + rz + dt,
            pose.a,
            pose.b,
        ]


def create(hal: HalContext | None = None) -> SwitchKins:
    joints = JointMap("xyzab", "xyzab_tdr_kins")
    tdr = Tdr(make_pins(TdrPins, hal, "xyzab_tdr_kins"))
    return SwitchKins([Identity5(), tdr], joints, hal)


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    if args:
        raise HalError(f"xyzab_tdr_kins: unknown argument '{sorted(args)[0]}'")
    TdrInstance.create(host.hal, comp, "xyzab-tdr-kins.0")
    host.kinematics = create(hal=HalContext(host.hal, comp))
