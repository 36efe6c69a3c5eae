"""genhexkins: a generalised hexapod (Stewart platform). Six struts (joints 0-5, lengths)
join base points (``genhexkins.base.N.x/y/z``) to platform points given in the platform's
frame (``platform.N.x/y/z``); the platform's pose is X Y Z and roll, pitch, yaw A B C
(degrees). ``spindle-offset`` and ``tool-offset`` (connect motion.tooloffset.z for RTCP)
move the origin along Z. With ``screw-lead`` not 0, strut lengths are corrected for the
twist of cardan joints (``base-n.N.*``, ``platform-n.N.*`` axes; ``correction.N``).
Forward kinematics iterates from the last pose (``convergence-criterion``,
``limit-iterations``, ``max-error``; ``last-iterations``, ``max-iterations`` and
``fwd-kins-fail`` report it; ``genhexkins.x``... and ``skgui.x``... show the pose for the
vismach GUI). Switchable: type 0 hexapod, 1 identity, 2 the user type.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, pin
from motion.kinematics import (
    HalContext,
    KinematicsError,
    SingularityError,
    SwitchKins,
    make_pins,
    realtime_module,
    switchable,
)
from motion.kinematics._parallel import solve_forward
from motion.kinematics._rotation import rpy_matrix
from nml.pose import Pose

STRUTS = 6
BASE = (
    (-22.950, 13.250, 0.0), (22.950, 13.250, 0.0), (22.950, 13.250, 0.0),
    (0.000, -26.500, 0.0), (0.000, -26.500, 0.0), (-22.950, 13.250, 0.0),
)  # fmt: skip
PLATFORM = (
    (-1.000, 11.500, 0.0), (1.000, 11.500, 0.0), (10.459, -4.884, 0.0),
    (9.459, -6.616, 0.0), (-9.459, -6.616, 0.0), (-10.459, -4.884, 0.0),
)  # fmt: skip
BASE_N = (
    (0.707107, 0.0, 0.707107), (0.0, -0.707107, 0.707107), (-0.707107, 0.0, 0.707107),
    (-0.707107, 0.0, 0.707107), (0.0, 0.707107, 0.707107), (0.707107, 0.0, 0.707107),
)  # fmt: skip
PLATFORM_N = (
    (-1.0, 0.0, 0.0), (0.866025, 0.5, 0.0), (0.866025, 0.5, 0.0),
    (0.866025, -0.5, 0.0), (0.866025, -0.5, 0.0), (-1.0, 0.0, 0.0),
)  # fmt: skip
Vector = tuple[float, float, float]


class HexPins(RtComponent):
    base_x = pin("float in", "base.{}.x", count=STRUTS)
    base_y = pin("float in", "base.{}.y", count=STRUTS)
    base_z = pin("float in", "base.{}.z", count=STRUTS)
    platform_x = pin("float in", "platform.{}.x", count=STRUTS)
    platform_y = pin("float in", "platform.{}.y", count=STRUTS)
    platform_z = pin("float in", "platform.{}.z", count=STRUTS)
    base_nx = pin("float in", "base-n.{}.x", count=STRUTS)
    base_ny = pin("float in", "base-n.{}.y", count=STRUTS)
    base_nz = pin("float in", "base-n.{}.z", count=STRUTS)
    platform_nx = pin("float in", "platform-n.{}.x", count=STRUTS)
    platform_ny = pin("float in", "platform-n.{}.y", count=STRUTS)
    platform_nz = pin("float in", "platform-n.{}.z", count=STRUTS)
    correction = pin("float out", "correction.{}", count=STRUTS)
    last_iterations = pin("u32 out")
    max_iterations = pin("u32 out")
    max_error = pin("float in", default=500.0)
    convergence_criterion = pin("float in", default=1e-9)
    limit_iterations = pin("u32 in", default=120)
    tool_offset = pin("float in")
    spindle_offset = pin("float in")
    screw_lead = pin("float in")
    x = pin("float in")
    y = pin("float in")
    z = pin("float in")
    a = pin("float in")
    b = pin("float in")
    c = pin("float in")
    fwd_kins_fail = pin("bit out")


class SkGuiPins(RtComponent):
    """switchkins' pose for a vismach GUI (made for kinematics that ask for it)."""

    x = pin("float in", "skgui.x")
    y = pin("float in", "skgui.y")
    z = pin("float in", "skgui.z")
    a = pin("float in", "skgui.a")
    b = pin("float in", "skgui.b")
    c = pin("float in", "skgui.c")


def _cross(u: Vector, v: Vector) -> Vector:
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _unit(v: Vector) -> Vector:
    size = math.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
    if size == 0.0:
        raise SingularityError("genhexkins: a strut of length 0")
    return (v[0] / size, v[1] / size, v[2] / size)


def _rotate(m: Any, v: Vector) -> Vector:
    return (
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    )


class Hexapod:
    def __init__(self, pins: Any, gui: Any) -> None:
        self.pins, self.gui = pins, gui
        for i in range(STRUTS):
            pins.base_x[i], pins.base_y[i], pins.base_z[i] = BASE[i]
            pins.platform_x[i], pins.platform_y[i], pins.platform_z[i] = PLATFORM[i]
            pins.base_nx[i], pins.base_ny[i], pins.base_nz[i] = BASE_N[i]
            pins.platform_nx[i], pins.platform_ny[i], pins.platform_nz[i] = PLATFORM_N[i]
        # x y z roll pitch yaw (radians) forward starts from; None: no pose yet, start level
        # at the struts' mean length above the base (a pose on the base plane is singular)
        self.last: list[float] | None = None

    def _struts(self, coord: Sequence[float], *, is_shown: bool = False) -> list[float]:
        p = self.pins
        lift = p.spindle_offset + p.tool_offset
        m = rpy_matrix(coord[3], coord[4], coord[5])
        lead = p.screw_lead
        lengths = []
        for i in range(STRUTS):
            arm = _rotate(m, (p.platform_x[i], p.platform_y[i], p.platform_z[i] + lift))
            strut = (
                coord[0] + arm[0] - p.base_x[i],
                coord[1] + arm[1] - p.base_y[i],
                coord[2] + arm[2] - (p.base_z[i] + lift),
            )
            length = math.sqrt(strut[0] ** 2 + strut[1] ** 2 + strut[2] ** 2)
            if lead != 0.0:  # the twist of the cardan joints turns the screw
                direction = _unit(strut)
                base_axis = _unit(
                    _cross(direction, _cross((p.base_nx[i], p.base_ny[i], p.base_nz[i]), direction))
                )
                platform_axis = _rotate(m, (p.platform_nx[i], p.platform_ny[i], p.platform_nz[i]))
                turned = _unit(_cross(platform_axis, direction))
                dot = sum(a * b for a, b in zip(base_axis, turned, strict=True))
                correction = lead * math.asin(max(-1.0, min(1.0, dot))) / (2 * math.pi)
                if is_shown:
                    p.correction[i] = correction
                length += correction
            lengths.append(length)
        return lengths

    def inverse(self, pose: Pose) -> list[float]:
        coord = [pose.x, pose.y, pose.z, *(v * math.pi / 180.0 for v in (pose.a, pose.b, pose.c))]
        return self._struts(coord, is_shown=True)

    def forward(self, joints: Sequence[float]) -> Pose:
        p = self.pins
        if any(j <= 0.0 for j in joints[:STRUTS]):
            p.fwd_kins_fail = True
            raise KinematicsError("genhexkins: strut lengths must be positive")
        try:
            start = self.last or [0.0, 0.0, sum(joints[:STRUTS]) / STRUTS, 0.0, 0.0, 0.0]
            coord, iterations = solve_forward(
                self._struts,
                joints[:STRUTS],
                start,
                max_error=p.max_error,
                criterion=p.convergence_criterion,
                iteration_limit=p.limit_iterations,
                name="genhexkins",
            )
        except SingularityError:
            p.fwd_kins_fail = True
            raise
        self.last = coord
        p.last_iterations = iterations
        if iterations > p.max_iterations:
            p.max_iterations = iterations
        p.fwd_kins_fail = False
        pose = Pose(*coord[:3], *(v * 180.0 / math.pi for v in coord[3:]))
        for pins in (p, self.gui):  # the vismach GUI reads the pose from these
            pins.x, pins.y, pins.z, pins.a, pins.b, pins.c = pose.as_tuple()[:6]
        return pose


def create(coordinates: str = "", sparm: str = "", hal: HalContext | None = None) -> SwitchKins:
    own = Hexapod(make_pins(HexPins, hal, "genhexkins"), make_pins(SkGuiPins, hal, ""))
    return switchable("genhexkins", own, "xyzabc", coordinates, sparm, hal)


rtapi_app_main: Any = realtime_module(create)
