"""scarakins: a SCARA robot (joints in degrees except the quill). Joint 0 turns the inner
arm (length D2) about a column, joint 1 the outer arm (D4) at its end, joint 2 slides the
quill down, joint 3 turns the tool, which sits D6 off the quill's centre and D5 below it;
D1 is the inner arm's height, D3 the outer arm's above it. A and B (joints 4, 5) pass
through; C is the tool's direction. Pins ``scarakins.D1``... ``D6`` (defaults 490, 340, 50,
250, 50, 50). The elbow's side comes from the last forward kinematics (joint 1 below 90
degrees: the other side), as LinuxCNC passes it on. Switchable: type 0 scara, 1 identity,
2 the user type.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    SwitchKins,
    make_pins,
    realtime_module,
    switchable,
)
from nml.pose import Pose


class ScaraPins(RtComponent):
    D1 = pin("float in", "D1", default=490.0)
    D2 = pin("float in", "D2", default=340.0)
    D3 = pin("float in", "D3", default=50.0)
    D4 = pin("float in", "D4", default=250.0)
    D5 = pin("float in", "D5", default=50.0)
    D6 = pin("float in", "D6", default=50.0)


class Scara:
    def __init__(self, pins: Any) -> None:
        self.pins = pins
        self.is_elbow_flipped = False  # LinuxCNC's iflags, set by forward for inverse

    def forward(self, joints: Sequence[float]) -> Pose:
        p = self.pins
        a0 = joints[0] * (math.pi / 180)
        a1 = joints[1] * (math.pi / 180) + a0
        a3 = joints[3] * (math.pi / 180) + a1
        self.is_elbow_flipped = joints[1] < 90
        return Pose(
            x=p.D2 * math.cos(a0) + p.D4 * math.cos(a1) + p.D6 * math.cos(a3),
            y=p.D2 * math.sin(a0) + p.D4 * math.sin(a1) + p.D6 * math.sin(a3),
            z=p.D1 + p.D3 - joints[2] - p.D5,
            a=joints[4],
            b=joints[5],
            c=a3 * 180 / math.pi,
        )

    def inverse(self, pose: Pose) -> list[float]:
        p = self.pins
        a3 = pose.c * (math.pi / 180)
        xt = pose.x - p.D6 * math.cos(a3)  # the quill's centre
        yt = pose.y - p.D6 * math.sin(a3)
        cosine = (xt * xt + yt * yt - p.D2 * p.D2 - p.D4 * p.D4) / (2 * p.D2 * p.D4)
        q1 = math.acos(min(max(cosine, -1.0), 1.0))
        if self.is_elbow_flipped:
            q1 = -q1
        q0 = math.atan2(yt, xt) - math.atan2(p.D4 * math.sin(q1), p.D2 + p.D4 * math.cos(q1))
        q0, q1 = q0 * (180 / math.pi), q1 * (180 / math.pi)
        return [q0, q1, p.D1 + p.D3 - p.D5 - pose.z, pose.c - (q0 + q1), pose.a, pose.b]


def create(coordinates: str = "", sparm: str = "", hal: HalContext | None = None) -> SwitchKins:
    own = Scara(make_pins(ScaraPins, hal, "scarakins"))
    return switchable("scarakins", own, "xyzabc", coordinates, sparm, hal)


rtapi_app_main: Any = realtime_module(create)
