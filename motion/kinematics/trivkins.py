"""Trivial kinematics (KIN-004..007): each joint drives one axis, 1:1.

``coordinates=`` assigns joints in order to axis letters (either case), and a letter may
repeat so that several joints drive one axis (gantry, ``xyyz``). Forward kinematics takes
an axis's value from the first joint mapped to it (KIN-007). ``kinstype=`` picks the
reported type: ``1``/``identity`` (default), ``b``/``both``, ``f``/``forward``,
``i``/``inverse``.
"""

from __future__ import annotations

from collections.abc import Sequence

from motion.kinematics import (
    KinematicsError,
    KinematicsType,
    check_joints,
    check_pose,
)
from motion.pose import AXIS_LETTERS, EmcPose

_KINSTYPES = {
    "1": KinematicsType.IDENTITY,
    "identity": KinematicsType.IDENTITY,
    "b": KinematicsType.BOTH,
    "both": KinematicsType.BOTH,
    "f": KinematicsType.FORWARD_ONLY,
    "forward": KinematicsType.FORWARD_ONLY,
    "i": KinematicsType.INVERSE_ONLY,
    "inverse": KinematicsType.INVERSE_ONLY,
}


class TrivKins:
    def __init__(self, coordinates: str = AXIS_LETTERS, kinstype: str = "1") -> None:
        letters = coordinates.replace(" ", "").lower()
        if not letters:
            raise KinematicsError("trivkins: coordinates= is empty")
        bad = sorted({c for c in letters if c not in AXIS_LETTERS})
        if bad:
            raise KinematicsError(
                f"trivkins: coordinates={coordinates!r} has unknown axis letters {bad}"
            )
        try:
            self._type = _KINSTYPES[kinstype.strip().lower()]
        except KeyError:
            raise KinematicsError(
                f"trivkins: kinstype={kinstype!r} is not one of {sorted(_KINSTYPES)}"
            ) from None
        self.coordinates = letters
        self.num_joints = len(letters)
        self.joint_axis = [AXIS_LETTERS.index(c) for c in letters]
        self.axis_mask = 0
        for axis in self.joint_axis:
            self.axis_mask |= 1 << axis
        # forward uses the first joint of each axis (KIN-007)
        self._first_joint = {}
        for joint, axis in enumerate(self.joint_axis):
            self._first_joint.setdefault(axis, joint)

    def forward(self, joints: Sequence[float]) -> EmcPose:
        values = check_joints(joints, self.num_joints)
        world = [0.0] * len(AXIS_LETTERS)
        for axis, joint in self._first_joint.items():
            world[axis] = values[joint]
        return EmcPose(*world)

    def inverse(self, pose: EmcPose) -> list[float]:
        check_pose(pose)
        world = pose.as_tuple()
        return [world[axis] for axis in self.joint_axis]

    def kinematics_type(self) -> KinematicsType:
        return self._type

    def home(self, pose: EmcPose, joints: Sequence[float]) -> tuple[EmcPose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def create(coordinates: str = AXIS_LETTERS, kinstype: str = "1") -> TrivKins:
    return TrivKins(coordinates, kinstype)
