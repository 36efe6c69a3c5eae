"""trivkins: trivial kinematics (KIN-004..007), each joint drives one axis, 1:1.

``coordinates=`` (default ``XYZABCUVW``) assigns joints in order to axis letters (either
case), and a letter may repeat so that several joints drive one axis (gantry, ``xyyz``).
Forward kinematics takes an axis's value from the first joint mapped to it (KIN-007).
``kinstype=`` picks the reported type by its first letter, as LinuxCNC: ``b`` both, ``f``
forward only, ``i`` inverse only, anything else (``1``, the default) identity.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from motion.kinematics import (
    HalContext,
    JointMap,
    KinematicsError,
    KinematicsType,
    check_joints,
    check_pose,
    realtime_module,
)
from nml.pose import AXIS_NAMES, Pose

_KINSTYPES = {
    "b": KinematicsType.BOTH,
    "f": KinematicsType.FORWARD_ONLY,
    "i": KinematicsType.INVERSE_ONLY,
}


class TrivKins:
    def __init__(self, coordinates: str = AXIS_NAMES, kinstype: str = "1") -> None:
        word = kinstype.strip().lower()
        if word and word not in ("1", "identity") and word[0] not in _KINSTYPES:
            raise KinematicsError(
                f"trivkins: kinstype={kinstype!r} is not 1, both, forward or inverse"
            )
        self._type = _KINSTYPES.get(word[:1], KinematicsType.IDENTITY)
        self.map = JointMap(coordinates, "trivkins")
        self.coordinates = self.map.letters
        self.num_joints = self.map.num_joints
        self.joint_axes = self.map.axis_of_joint
        self.axis_mask = self.map.axis_mask

    def forward(self, joints: Sequence[float]) -> Pose:
        return self.map.to_pose(check_joints(joints, self.num_joints))

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        return self.map.to_joints(pose)

    def kinematics_type(self) -> KinematicsType:
        return self._type

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(
    coordinates: str = AXIS_NAMES, kinstype: str = "1", hal: HalContext | None = None
) -> TrivKins:
    return TrivKins(coordinates, kinstype)


rtapi_app_main: Any = realtime_module(create)
