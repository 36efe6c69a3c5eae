"""pentakins: a pentapod, five struts (joints 0-4, their lengths) between base points
(``pentakins.base.N.x/y/z`` parameters) and an effector with pivots on a radius
``effector.N.r`` at heights ``effector.N.z``; the effector's pose is X Y Z and its tilts A
and B (degrees). ``pentakins.tool-offset`` moves the pivot along Z. Forward kinematics
iterates (``convergence-criterion``, ``limit-iterations``, ``max-error``;
``last-iterations`` and ``max-iterations`` show the work), from the last pose.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, param, pin
from motion.kinematics import (
    HalContext,
    KinematicsError,
    KinematicsType,
    check_joints,
    check_pose,
    make_pins,
    realtime_module,
)
from motion.kinematics._parallel import solve_forward
from motion.kinematics._rotation import rpy_matrix
from nml.pose import Pose

STRUTS = 5
BASE = (
    (-418.03, 324.56, 895.56),
    (417.96, 324.56, 895.56),
    (-418.03, -325.44, 895.56),
    (417.96, -325.44, 895.56),
    (-0.06, -492.96, 895.56),
)
EFFECTOR_R = (80.32,) * STRUTS
EFFECTOR_Z = (-185.50, -159.50, -67.50, -41.50, -14.00)


class PentaPins(RtComponent):
    # (LinuxCNC makes six of each; the sixth is not used)
    base_x = param("float rw", "base.{}.x", count=6)
    base_y = param("float rw", "base.{}.y", count=6)
    base_z = param("float rw", "base.{}.z", count=6)
    effector_r = param("float rw", "effector.{}.r", count=6)
    effector_z = param("float rw", "effector.{}.z", count=6)
    last_iterations = pin("u32 out")
    max_iterations = pin("u32 out")
    max_error = pin("float io", default=100.0)
    convergence_criterion = pin("float io", default=1e-9)
    limit_iterations = pin("u32 io", default=120)
    tool_offset = pin("float in")


class PentaKins:
    num_joints = STRUTS
    joint_axes = [0, 1, 2, 3, 4]
    axis_mask = 0b11111

    def __init__(self, pins: Any) -> None:
        self.pins = pins
        for i, (x, y, z) in enumerate(BASE):
            pins.base_x[i], pins.base_y[i], pins.base_z[i] = x, y, z
            pins.effector_r[i], pins.effector_z[i] = EFFECTOR_R[i], EFFECTOR_Z[i]
        self.last = [0.0] * STRUTS  # x y z a b (radians): where forward iterates from

    def _struts(self, coord: Sequence[float]) -> list[float]:
        """Strut lengths of a pose (x, y, z, roll, pitch in radians)."""
        p = self.pins
        offset = p.tool_offset
        m = rpy_matrix(coord[3], coord[4], 0.0)
        lengths = []
        for i in range(STRUTS):
            dx = p.base_x[i] - coord[0]
            dy = p.base_y[i] - coord[1]
            dz = p.base_z[i] + offset - coord[2]
            # the base point in the effector's frame: the rotation's transpose times it
            ex = m[0][0] * dx + m[0][1] * dy + m[0][2] * dz
            ey = m[1][0] * dx + m[1][1] * dy + m[1][2] * dz
            ez = m[2][0] * dx + m[2][1] * dy + m[2][2] * dz
            lengths.append(
                math.hypot(ez - (p.effector_z[i] + offset), math.hypot(ex, ey) - p.effector_r[i])
            )
        return lengths

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        return self._struts([pose.x, pose.y, pose.z, math.radians(pose.a), math.radians(pose.b)])

    def forward(self, joints: Sequence[float]) -> Pose:
        values = check_joints(joints, STRUTS)
        if any(v <= 0.0 for v in values[:STRUTS]):
            raise KinematicsError("pentakins: strut lengths must be positive")
        p = self.pins
        coord, iterations = solve_forward(
            self._struts,
            values,
            self.last,
            max_error=p.max_error,
            criterion=p.convergence_criterion,
            iteration_limit=p.limit_iterations,
            name="pentakins",
        )
        self.last = coord
        p.last_iterations = iterations
        if iterations > p.max_iterations:
            p.max_iterations = iterations
        return Pose(
            coord[0], coord[1], coord[2], coord[3] * 180.0 / math.pi, coord[4] * 180.0 / math.pi
        )

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, STRUTS)[:STRUTS]
        return self.forward(values), values


def create(hal: HalContext | None = None) -> PentaKins:
    return PentaKins(make_pins(PentaPins, hal, "pentakins"))


rtapi_app_main: Any = realtime_module(create)
