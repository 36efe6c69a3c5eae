"""The bipod of KIN-009..013: two cables from motors A = (0, 0) and B = (Bx, 0) hold the
tool at D = (x, y); joint 0 is the length AD, joint 1 the length BD.

Forward kinematics has a singularity where the two cables cannot meet (y^2 < 0): it raises
``SingularityError`` and the caller keeps its previous pose (KIN-010/012).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from motion.kinematics import (
    KinematicsError,
    KinematicsType,
    SingularityError,
    check_joints,
    check_pose,
)
from nml.pose import Pose


class Bipod:
    num_joints = 2
    axis_mask = 0b11

    def __init__(self, bx: float = 10.0) -> None:
        if not (math.isfinite(bx) and bx > 0):
            raise KinematicsError(f"bipod: Bx must be a positive distance, got {bx}")
        self.bx = bx

    def forward(self, joints: Sequence[float]) -> Pose:
        j0, j1 = check_joints(joints, 2)[:2]
        ad2, bd2 = j0 * j0, j1 * j1
        x = (ad2 - bd2 + self.bx * self.bx) / (2 * self.bx)
        y2 = ad2 - x * x
        if y2 < 0:
            raise SingularityError(
                f"bipod: cable lengths {j0:g}, {j1:g} cannot meet (y^2 = {y2:g} < 0)"
            )
        return Pose(x=x, y=math.sqrt(y2))

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        return [math.hypot(pose.x, pose.y), math.hypot(self.bx - pose.x, pose.y)]

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        # any reachable start is acceptable: keep the given joints if they are valid (KIN-015)
        values = check_joints(joints, 2)[:2]
        return self.forward(values), values


def create(bx: float | str = 10.0) -> Bipod:
    return Bipod(float(bx))
