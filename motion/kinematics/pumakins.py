"""pumakins: a PUMA-style six-joint arm (joints in degrees). Link lengths and offsets come
from pins ``pumakins.A2``, ``A3``, ``D3``, ``D4`` and ``D6`` (the tool beyond the wrist;
defaults those of a PUMA 560: 300, 50, 70, 400, 70); A B C are the tool's roll, pitch and
yaw. The shoulder, elbow and wrist configuration that inverse kinematics picks is the one
the last forward kinematics saw, as LinuxCNC passes it on. Switchable: type 0 puma, 1
identity, 2 the user type.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    KinematicsError,
    SwitchKins,
    make_pins,
    realtime_module,
    switchable,
)
from motion.kinematics._rotation import matrix_rpy, rpy_matrix
from nml.pose import Pose

SINGULAR_FUZZ = FLAG_FUZZ = 0.000001
SHOULDER_RIGHT, ELBOW_DOWN, WRIST_FLIP, SINGULAR = 0x01, 0x02, 0x04, 0x08
DEG = 180 / math.pi


class PumaPins(RtComponent):
    A2 = pin("float in", "A2", default=300.0)
    A3 = pin("float in", "A3", default=50.0)
    D3 = pin("float in", "D3", default=70.0)
    D4 = pin("float in", "D4", default=400.0)
    D6 = pin("float in", "D6", default=70.0)


class Puma:
    def __init__(self, pins: Any) -> None:
        self.pins = pins
        self.flags = 0  # LinuxCNC's iflags: the configuration forward saw, for inverse
        self.last_joints = [0.0] * 6

    def forward(self, joints: Sequence[float]) -> Pose:
        p = self.pins
        a2, a3, d3, d4, d6 = p.A2, p.A3, p.D3, p.D4, p.D6
        angles = [j * math.pi / 180 for j in joints[:6]]
        s1, s2, s3, s4, s5, s6 = (math.sin(a) for a in angles)
        c1, c2, c3, c4, c5, c6 = (math.cos(a) for a in angles)
        s23, c23 = c2 * s3 + s2 * c3, c2 * c3 - s2 * s3
        t1 = c4 * c5 * c6 - s4 * s6
        t3 = s4 * c5 * c6 + c4 * s6
        t4 = c23 * t1 - s23 * s5 * c6
        col_x = (c1 * t4 + s1 * t3, s1 * t4 - c1 * t3, -s23 * t1 - c23 * s5 * c6)
        t1 = -c4 * c5 * s6 - s4 * c6
        t3 = c4 * c6 - s4 * c5 * s6
        t4 = c23 * t1 + s23 * s5 * s6
        col_y = (c1 * t4 + s1 * t3, s1 * t4 - c1 * t3, -s23 * t1 + c23 * s5 * s6)
        t1 = c23 * c4 * s5 + s23 * c5
        col_z = (-c1 * t1 - s1 * s4 * s5, -s1 * t1 + c1 * s4 * s5, s23 * c4 * s5 - c23 * c5)
        t1 = a2 * c2 + a3 * c23 - d4 * s23
        x, y = c1 * t1 - d3 * s1, s1 * t1 + d3 * c1
        z = -a3 * s23 - a2 * s2 - d4 * c23
        sum_sq = x * x + y * y - d3 * d3
        k = (sum_sq + z * z - a2 * a2 - a3 * a3 - d4 * d4) / (2.0 * a2)
        flags = 0
        if abs(angles[0] - math.atan2(y, x) + math.atan2(d3, -math.sqrt(sum_sq))) < FLAG_FUZZ:
            flags |= SHOULDER_RIGHT
        reach = a3 * a3 + d4 * d4 - k * k
        if (
            reach >= 0
            and abs(angles[2] - math.atan2(a3, d4) + math.atan2(k, -math.sqrt(reach))) < FLAG_FUZZ
        ):
            flags |= ELBOW_DOWN
        t1 = -col_z[0] * s1 + col_z[1] * c1
        t2 = -col_z[0] * c1 * c23 - col_z[1] * s1 * c23 + col_z[2] * s23
        if abs(t1) < SINGULAR_FUZZ and abs(t2) < SINGULAR_FUZZ:
            flags |= SINGULAR
        elif not abs(angles[3] - math.atan2(t1, t2)) < FLAG_FUZZ:
            flags |= WRIST_FLIP
        self.flags = flags
        self.last_joints = [float(j) for j in joints[:6]]
        roll, pitch, yaw = matrix_rpy((col_x, col_y, col_z))
        return Pose(
            x + col_z[0] * d6, y + col_z[1] * d6, z + col_z[2] * d6,
            roll * DEG, pitch * DEG, yaw * DEG,
        )  # fmt: skip

    def inverse(self, pose: Pose) -> list[float]:
        p = self.pins
        a2, a3, d3, d4, d6 = p.A2, p.A3, p.D3, p.D4, p.D6
        rot_x, _rot_y, rot_z = rpy_matrix(
            pose.a * math.pi / 180.0, pose.b * math.pi / 180.0, pose.c * math.pi / 180.0
        )
        px, py, pz = (pose.x - d6 * rot_z[0], pose.y - d6 * rot_z[1], pose.z - d6 * rot_z[2])
        flags = self.flags
        sum_sq = px * px + py * py - d3 * d3
        if sum_sq < 0:
            raise KinematicsError("pumakins: the pose is inside the shoulder offset")
        root = math.sqrt(sum_sq)
        th1 = math.atan2(py, px) - math.atan2(d3, -root if flags & SHOULDER_RIGHT else root)
        s1, c1 = math.sin(th1), math.cos(th1)
        k = (sum_sq + pz * pz - a2 * a2 - a3 * a3 - d4 * d4) / (2.0 * a2)
        reach = a3 * a3 + d4 * d4 - k * k
        if reach < 0:
            raise KinematicsError("pumakins: the pose is out of reach")
        root = math.sqrt(reach)
        th3 = math.atan2(a3, d4) - math.atan2(k, -root if flags & ELBOW_DOWN else root)
        s3, c3 = math.sin(th3), math.cos(th3)
        reach = c1 * px + s1 * py
        t1 = (-a3 - a2 * c3) * pz + reach * (a2 * s3 - d4)
        t2 = (a2 * s3 - d4) * pz + (a3 + a2 * c3) * reach
        t3 = pz * pz + reach * reach
        th2 = math.atan2(t1, t2) - th3
        s23, c23 = t1 / t3, t2 / t3
        t1 = -rot_z[0] * s1 + rot_z[1] * c1
        t2 = -rot_z[0] * c1 * c23 - rot_z[1] * s1 * c23 + rot_z[2] * s23
        if abs(t1) < SINGULAR_FUZZ and abs(t2) < SINGULAR_FUZZ:
            th4 = self.last_joints[3] * math.pi / 180  # at the singularity: keep joint 3
        else:
            th4 = math.atan2(t1, t2)
        s4, c4 = math.sin(th4), math.cos(th4)
        s5 = (
            rot_z[2] * (s23 * c4)
            - rot_z[0] * (c1 * c23 * c4 + s1 * s4)
            - rot_z[1] * (s1 * c23 * c4 - c1 * s4)
        )
        c5 = -rot_z[0] * (c1 * s23) - rot_z[1] * (s1 * s23) - rot_z[2] * c23
        th5 = math.atan2(s5, c5)
        s6 = (
            rot_x[2] * (s23 * s4)
            - rot_x[0] * (c1 * c23 * s4 - s1 * c4)
            - rot_x[1] * (s1 * c23 * s4 + c1 * c4)
        )
        c6 = (
            rot_x[0] * ((c1 * c23 * c4 + s1 * s4) * c5 - c1 * s23 * s5)
            + rot_x[1] * ((s1 * c23 * c4 - c1 * s4) * c5 - s1 * s23 * s5)
            - rot_x[2] * (s23 * c4 * c5 + c23 * s5)
        )
        th6 = math.atan2(s6, c6)
        if flags & WRIST_FLIP:
            th4, th5, th6 = th4 + math.pi, -th5, th6 + math.pi
        return [th * DEG for th in (th1, th2, th3, th4, th5, th6)]


def create(coordinates: str = "", sparm: str = "", hal: HalContext | None = None) -> SwitchKins:
    own = Puma(make_pins(PumaPins, hal, "pumakins"))
    return switchable("pumakins", own, "xyzabc", coordinates, sparm, hal)


rtapi_app_main: Any = realtime_module(create)
