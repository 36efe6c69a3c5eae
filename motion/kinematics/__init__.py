"""Kinematics modules (KIN-001..020), loaded by name.

A kinematics module is one small Python file whose ``create(**params)`` returns an object
with this interface (the Python form of KIN-014):

- ``num_joints``: how many joints the module maps.
- ``forward(joints) -> EmcPose``: joints to world; raises ``SingularityError`` where the
  joints have no single cartesian equivalent (KIN-012), and the caller keeps its old pose.
- ``inverse(pose) -> list[float]``: world to joints; raises ``KinematicsError`` if unreachable.
- ``kinematics_type() -> KinematicsType`` (KIN-018).
- ``home(pose, joints) -> (pose, joints)``: the known home position; the arguments are the
  initial values (e.g. from the INI file) and are used where any start is acceptable (KIN-015).
- optional ``axis_mask`` (bit n set when axis n of XYZABCUVW is used, MOT-068) and
  ``teardown()`` (the equivalent of ``rtapi_app_exit``, KIN-016).

Writing a new module: copy ``corexy.py`` and change the two formulas. Load it with
``load_kinematics("mypackage.mykins", **params)`` or put it in this package and use its
short name, as ``[KINS]KINEMATICS`` does.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from typing import Protocol, runtime_checkable

from motion.modules import ModuleInterfaceError, import_module, require
from motion.pose import EmcPose

REQUIRED_FUNCTIONS = ("forward", "inverse", "kinematics_type", "home")


class KinematicsType(enum.IntEnum):
    """Which transformations exist (LinuxCNC's KINEMATICS_TYPE values)."""

    IDENTITY = 1
    FORWARD_ONLY = 2
    INVERSE_ONLY = 3
    BOTH = 4

    @property
    def has_forward(self) -> bool:
        return self in (KinematicsType.IDENTITY, KinematicsType.FORWARD_ONLY, KinematicsType.BOTH)

    @property
    def has_inverse(self) -> bool:
        return self in (KinematicsType.IDENTITY, KinematicsType.INVERSE_ONLY, KinematicsType.BOTH)


class KinematicsError(ValueError):
    """A transformation has no valid result (e.g. an unreachable pose)."""


class SingularityError(KinematicsError):
    """Joint positions without a single cartesian equivalent (KIN-012)."""


@runtime_checkable
class Kinematics(Protocol):
    num_joints: int

    def forward(self, joints: Sequence[float]) -> EmcPose: ...

    def inverse(self, pose: EmcPose) -> list[float]: ...

    def kinematics_type(self) -> KinematicsType: ...

    def home(self, pose: EmcPose, joints: Sequence[float]) -> tuple[EmcPose, list[float]]: ...


def check_joints(joints: Sequence[float], count: int) -> list[float]:
    """Joint values as floats; a clear error on a wrong count or a NaN."""
    values = [float(j) for j in joints]
    if len(values) < count:
        raise KinematicsError(f"expected {count} joint values, got {len(values)}")
    for n, value in enumerate(values[:count]):
        if value != value or value in (float("inf"), float("-inf")):
            raise KinematicsError(f"joint {n} position is not finite: {value}")
    return values


def check_pose(pose: EmcPose) -> None:
    if not pose.is_finite():
        raise KinematicsError(f"pose is not finite: {pose}")


def load_kinematics(name: str, **params: str) -> Kinematics:
    """Load a kinematics module by name (``trivkins``, ``corexy``, ``bipod`` or a dotted path)
    and create it with its module parameters, e.g. ``coordinates="xyyz"``.

    Refuses a module that lacks ``create`` or whose object lacks any required function,
    listing everything missing (ARCH-008 style)."""
    module = import_module(name, __name__, "kinematics")
    require(module, ("create",), f"kinematics module {name!r}")
    try:
        kins = module.create(**params)
    except TypeError as exc:
        raise ModuleInterfaceError(f"kinematics module {name!r}: bad parameters: {exc}") from exc
    require(kins, REQUIRED_FUNCTIONS, f"kinematics module {name!r}")
    if not isinstance(getattr(kins, "num_joints", None), int):
        raise ModuleInterfaceError(f"kinematics module {name!r} is incomplete: missing num_joints")
    return kins
