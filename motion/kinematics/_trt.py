"""Table-rotary-tilting 5-axis kinematics (LinuxCNC's trtfuncs): the work sits on a rotary
table (C) carried by a tilting table (A for xyzac-trt-kins, B for xyzbc-trt-kins), and the
tool tip stays on the programmed path while the tables turn (tool-centre-point).

The geometry comes from HAL pins (``<module>.x-rot-point``... ``tool-offset``): the point
where the rotary axes cross, the offset of the tilting axis from it, and the tool length.
As in LinuxCNC, the rotary axes turn the opposite way to the conventional directions.
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
    switchkins_types,
)
from nml.pose import Pose


class TrtPins(RtComponent):
    x_rot_point = pin("float in")
    y_rot_point = pin("float in")
    z_rot_point = pin("float in")
    x_offset = pin("float in")
    y_offset = pin("float in")
    z_offset = pin("float in")
    tool_offset = pin("float in")


class _Trt:
    """The geometry and joint numbers shared by both machines."""

    def __init__(self, joints: JointMap, pins: Any) -> None:
        self.map = joints
        self.pins = pins
        self.jx, self.jy, self.jz = (joints.joint_of(c) for c in "xyz")
        self.ja, self.jb, self.jc = (joints.joint_of(c) for c in "abc")
        self.ju, self.jv, self.jw = (joints.joint_of(c) for c in "uvw")

    def _value(self, joints: Sequence[float], joint: int) -> float:
        return joints[joint] if joint != -1 else 0.0


class XyzacTrt(_Trt):
    """Tilting table A with rotary table C."""

    def forward(self, joints: Sequence[float]) -> Pose:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dy, dz = p.y_offset, p.z_offset + p.tool_offset
        a, c = joints[self.ja] * TO_RAD, joints[self.jc] * TO_RAD
        x = joints[self.jx] - rx
        y = joints[self.jy] - dy - ry
        z = joints[self.jz] - dz - rz
        sa, ca, sc, cc = math.sin(a), math.cos(a), math.sin(c), math.cos(c)
        value = self._value
        return Pose(
            x=cc * x + sc * ca * y + sc * sa * z + sc * dy + rx,
            y=-sc * x + cc * ca * y + cc * sa * z + cc * dy + ry,
            z=0 - sa * y + ca * z + dz + rz,
            a=joints[self.ja],
            b=value(joints, self.jb),
            c=joints[self.jc],
            u=value(joints, self.ju),
            v=value(joints, self.jv),
            w=value(joints, self.jw),
        )

    def inverse(self, pose: Pose) -> list[float]:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dy, dz = p.y_offset, p.z_offset + p.tool_offset
        a, c = pose.a * TO_RAD, pose.c * TO_RAD
        x, y, z = pose.x - rx, pose.y - ry, pose.z - rz
        sa, ca, sc, cc = math.sin(a), math.cos(a), math.sin(c), math.cos(c)
        result = Pose(
            x=cc * x - sc * y + rx,
            y=sc * ca * x + cc * ca * y - sa * z - ca * dy + sa * dz + dy + ry,
            z=sc * sa * x + cc * sa * y + ca * z - sa * dy - ca * dz + dz + rz,
            a=pose.a,
            b=pose.b if self.jb != -1 else 0.0,
            c=pose.c,
            u=pose.u if self.ju != -1 else 0.0,
            v=pose.v if self.jv != -1 else 0.0,
            w=pose.w if self.jw != -1 else 0.0,
        )
        return self.map.to_joints(result)


class XyzbcTrt(_Trt):
    """Tilting table B with rotary table C."""

    def forward(self, joints: Sequence[float]) -> Pose:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dx, dz = p.x_offset, p.z_offset + p.tool_offset
        b, c = joints[self.jb] * TO_RAD, joints[self.jc] * TO_RAD
        x = joints[self.jx] - dx - rx
        y = joints[self.jy] - ry
        z = joints[self.jz] - dz - rz
        sb, cb, sc, cc = math.sin(b), math.cos(b), math.sin(c), math.cos(c)
        value = self._value
        return Pose(
            x=cc * cb * x + sc * y - cc * sb * z + cc * dx + rx,
            y=-sc * cb * x + cc * y + sc * sb * z - sc * dx + ry,
            z=sb * x + cb * z + dz + rz,
            a=value(joints, self.ja),
            b=joints[self.jb],
            c=joints[self.jc],
            u=value(joints, self.ju),
            v=value(joints, self.jv),
            w=value(joints, self.jw),
        )

    def inverse(self, pose: Pose) -> list[float]:
        p = self.pins
        rx, ry, rz = p.x_rot_point, p.y_rot_point, p.z_rot_point
        dx, dz = p.x_offset, p.z_offset + p.tool_offset
        b, c = pose.b * TO_RAD, pose.c * TO_RAD
        x, y, z = pose.x - rx, pose.y - ry, pose.z - rz
        sb, cb, sc, cc = math.sin(b), math.cos(b), math.sin(c), math.cos(c)
        dpx = -cb * dx - sb * dz + dx
        dpz = sb * dx - cb * dz + dz
        result = Pose(
            x=cc * cb * x - sc * cb * y + sb * z + dpx + rx,
            y=sc * x + cc * y + ry,
            z=-cc * sb * x + sc * sb * y + cb * z + dpz + rz,
            a=pose.a if self.ja != -1 else 0.0,
            b=pose.b,
            c=pose.c,
            u=pose.u if self.ju != -1 else 0.0,
            v=pose.v if self.jv != -1 else 0.0,
            w=pose.w if self.jw != -1 else 0.0,
        )
        return self.map.to_joints(result)


def create_trt(
    name: str,
    machine: type[_Trt],
    coordinates: str,
    sparm: str,
    hal: HalContext | None,
) -> SwitchKins:
    """A trt module: its kinematics (type 0, or 1 with ``sparm=identityfirst``), identity
    and the user type, switchable."""
    required = "xyzac" if machine is XyzacTrt else "xyzbc"
    joints = JointMap(coordinates or required, name, max_joints=16)
    missing = [c for c in required if c not in joints.letters]
    if missing:
        raise KinematicsError(
            f"{name}: required coordinates {required}, specified {coordinates} (no {missing})"
        )
    own = machine(joints, make_pins(TrtPins, hal, name))
    return SwitchKins(switchkins_types(own, joints, sparm, hal), joints, hal)
