"""Kinematics modules (KIN-001..020), found by name: one file each, named as LinuxCNC's
module (``loadrt xyzac-trt-kins`` loads ``xyzac_trt_kins.py``, ``-`` read as ``_``).

A kinematics module's ``create(hal=None, **params)`` returns an object with this interface
(the Python form of KIN-014):

- ``num_joints``: how many joints the module maps.
- ``forward(joints) -> Pose``: joints to world; raises ``SingularityError`` where the
  joints have no single cartesian equivalent (KIN-012), and the caller keeps its old pose.
- ``inverse(pose) -> list[float]``: world to joints; raises ``KinematicsError`` if unreachable.
- ``kinematics_type() -> KinematicsType`` (KIN-018).
- ``home(pose, joints) -> (pose, joints)``: the known home position; the arguments are the
  initial values (e.g. from the INI file) and are used where any start is acceptable (KIN-015).
- optional ``axis_mask`` (bit n set when axis n of XYZABCUVW is used, MOT-068),
  ``switch(kinstype)`` for LinuxCNC's switchable kinematics (``motion.switchkins-type``,
  see ``SwitchKins``) and ``teardown()`` (the equivalent of ``rtapi_app_exit``, KIN-016).

``params`` are LinuxCNC's module parameters as text (``coordinates="xyzac"``). ``hal`` is
a ``HalContext`` when the module is loaded into the realtime host by ``loadrt`` (the
module's HAL pins are made there, with LinuxCNC's names; ``make_pins``), None when it is
made directly (``load_kinematics``, tests): the pins are then plain attributes holding
their defaults. Each module file ends with ``rtapi_app_main = realtime_module(create)``,
which makes it loadable by ``loadrt``; motmod takes the kinematics the last one made.

Writing a new module: copy ``corexykins.py`` and change the two formulas.
"""

from __future__ import annotations

import enum
import importlib
import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from hal.api import RtComponent, pin
from hal.core import HalError
from motion.modules import ModuleInterfaceError, require
from nml.pose import AXIS_NAMES, Pose

REQUIRED_FUNCTIONS = ("forward", "inverse", "kinematics_type", "home")
MAX_JOINTS = 16  # EMCMOT_MAX_JOINTS
TO_RAD = math.pi / 180.0  # as LinuxCNC's posemath defines it
TO_DEG = 180.0 / math.pi


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

    def forward(self, joints: Sequence[float]) -> Pose: ...

    def inverse(self, pose: Pose) -> list[float]: ...

    def kinematics_type(self) -> KinematicsType: ...

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]: ...


def check_joints(joints: Sequence[float], count: int) -> list[float]:
    """Joint values as floats; a clear error on a wrong count or a NaN."""
    values = [float(j) for j in joints]
    if len(values) < count:
        raise KinematicsError(f"expected {count} joint values, got {len(values)}")
    for n, value in enumerate(values[:count]):
        if value != value or value in (float("inf"), float("-inf")):
            raise KinematicsError(f"joint {n} position is not finite: {value}")
    return values


def check_pose(pose: Pose) -> None:
    if not pose.is_finite():
        raise KinematicsError(f"pose is not finite: {pose}")


class NineJointKins:
    """What most of LinuxCNC's modules share: nine joints (XYZABCUVW pass through where the
    module does not map them), both transformations, and home at the forward position of
    the given joints. Subclasses write ``forward`` and ``inverse``."""

    num_joints = 9
    joint_axes = list(range(9))
    axis_mask = 0x1FF

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values  # type: ignore[attr-defined]

    def joints_of(self, joints: Sequence[float]) -> list[float]:
        """Checked joint values, nine of them (missing ones 0)."""
        values = [float(j) for j in joints]
        values = (values + [0.0] * 9)[: max(9, len(values))]
        return check_joints(values, 9)


# ---------------------------------------------------------------- HAL pins of a module
@dataclass
class HalContext:
    """Where a kinematics module loaded by ``loadrt`` makes its HAL pins."""

    hal: Any  # hal.core.Hal
    comp: str


class _Unwired:
    """A module's pins without HAL: attributes holding the declared defaults."""

    def __init__(self, spec: type[RtComponent]) -> None:
        for decl in spec.declarations():
            count = decl.count_for({})
            if count is None:
                setattr(self, decl.attr, decl.default)
            else:
                setattr(self, decl.attr, [decl.default] * count)


def make_pins(spec: type[RtComponent], hal: HalContext | None, prefix: str) -> Any:
    """The pins ``spec`` declares, named ``<prefix>.<pin>`` (``prefix`` "" for names of
    their own, as switchkins' ``kinstype.is-0``), read as attributes (``pins.tool_offset``)."""
    if hal is None:
        return _Unwired(spec)
    return spec.create(hal.hal, hal.comp, prefix)


# ---------------------------------------------------------------- joints and coordinates
class JointMap:
    """LinuxCNC's ``coordinates=`` rule: letters assign joints in order (spaces ignored,
    either case); a letter may repeat so that several joints follow one axis (gantry).
    Forward takes an axis from the first joint given it (its principal joint)."""

    def __init__(
        self, coordinates: str, name: str, *, is_repeat_allowed: bool = True, max_joints: int = 9
    ) -> None:
        letters = "".join(coordinates.split()).lower()
        if not letters:
            raise KinematicsError(f"{name}: coordinates= is empty")
        bad = sorted({c for c in letters if c not in AXIS_NAMES})
        if bad:
            raise KinematicsError(
                f"{name}: coordinates={coordinates!r} has unknown axis letters {bad}"
            )
        if len(letters) > max_joints:
            raise KinematicsError(
                f"{name}: too many coordinates {coordinates!r} for {max_joints} joints"
            )
        if not is_repeat_allowed and len(set(letters)) != len(letters):
            raise KinematicsError(f"{name}: duplicates not allowed in coordinates={coordinates}")
        self.letters = letters
        self.num_joints = len(letters)
        self.axis_of_joint = [AXIS_NAMES.index(c) for c in letters]
        self.axis_mask = 0
        #: axis index -> its principal joint (first given it)
        self.principal: dict[int, int] = {}
        for joint, axis in enumerate(self.axis_of_joint):
            self.axis_mask |= 1 << axis
            self.principal.setdefault(axis, joint)

    def joint_of(self, letter: str) -> int:
        """The principal joint of an axis letter, -1 when the axis has none."""
        return self.principal.get(AXIS_NAMES.index(letter.lower()), -1)

    def to_pose(self, joints: Sequence[float]) -> Pose:
        """Identity forward kinematics (unmapped axes are 0)."""
        world = [0.0] * len(AXIS_NAMES)
        for axis, joint in self.principal.items():
            world[axis] = joints[joint]
        return Pose(*world)

    def to_joints(self, pose: Pose | Sequence[float]) -> list[float]:
        """Identity inverse kinematics: each joint takes its axis's value."""
        world = pose.as_tuple() if isinstance(pose, Pose) else tuple(pose)
        return [world[axis] for axis in self.axis_of_joint]


# ---------------------------------------------------------------- switchable kinematics
class KinsTypePins(RtComponent):
    """switchkins' pins (LinuxCNC names them without a module prefix)."""

    is_0 = pin("bit out", "kinstype.is-0")
    is_1 = pin("bit out", "kinstype.is-1")
    is_2 = pin("bit out", "kinstype.is-2")


class TwoKinsTypePins(RtComponent):
    """The pins of halcompile-made switchable kinematics with two types (millturn)."""

    is_0 = pin("bit out", "kinstype.is-0")
    is_1 = pin("bit out", "kinstype.is-1")


class UserKPins(RtComponent):
    """The demonstration user kinematics' call counters (``userk.fct``, ``userk.ict``)."""

    fct = pin("s32 io", "userk.fct")
    ict = pin("s32 io", "userk.ict")


class Identity:
    """Identity kinematics over a joint map (switchkins' identity type, trivkins)."""

    def __init__(self, joints: JointMap) -> None:
        self.map = joints
        self.num_joints = joints.num_joints

    def forward(self, joints: Sequence[float]) -> Pose:
        return self.map.to_pose(joints)

    def inverse(self, pose: Pose) -> list[float]:
        return self.map.to_joints(pose)


class UserK(Identity):
    """switchkins' type 2 as LinuxCNC ships it: identity, counting the calls on
    ``userk.fct`` and ``userk.ict`` (a place for a user's own kinematics)."""

    def __init__(self, joints: JointMap, pins: Any) -> None:
        super().__init__(joints)
        self.pins = pins

    def forward(self, joints: Sequence[float]) -> Pose:
        self.pins.fct = self.pins.fct + 1
        return super().forward(joints)

    def inverse(self, pose: Pose) -> list[float]:
        self.pins.ict = self.pins.ict + 1
        return super().inverse(pose)


class SwitchKins:
    """LinuxCNC's switchable kinematics: up to three kinematics types, chosen by
    ``switch(kinstype)`` (motmod calls it when ``motion.switchkins-type`` changes),
    shown on ``kinstype.is-0/1/2``. Type 0 is used from the start. ``forward_iterates``
    holds the types whose forward kinematics iterate from the last pose (restarted on
    each switch)."""

    is_switchable = True

    def __init__(self, types: Sequence[Any], joints: JointMap, hal: HalContext | None) -> None:
        self.types = list(types)
        self.map = joints
        self.num_joints = joints.num_joints
        self.axis_mask = joints.axis_mask
        self.type_pins = make_pins(KinsTypePins, hal, "")
        self.kinstype = 0
        self.switch(0)

    def switch(self, kinstype: int) -> None:
        if not 0 <= kinstype < len(self.types):
            self.type_pins.is_0 = self.type_pins.is_1 = self.type_pins.is_2 = False
            raise KinematicsError(f"kinematicsSwitch: bad kinstype {kinstype}")
        self.kinstype = kinstype
        self.type_pins.is_0 = kinstype == 0
        self.type_pins.is_1 = kinstype == 1
        self.type_pins.is_2 = kinstype == 2
        restart = getattr(self.types[kinstype], "restart", None)
        if restart is not None:
            restart()

    def forward(self, joints: Sequence[float]) -> Pose:
        return self.types[self.kinstype].forward(check_joints(joints, self.num_joints))

    def inverse(self, pose: Pose) -> list[float]:
        check_pose(pose)
        return self.types[self.kinstype].inverse(pose)

    def kinematics_type(self) -> KinematicsType:
        return KinematicsType.BOTH

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = check_joints(joints, self.num_joints)[: self.num_joints]
        return self.forward(values), values


def switchkins_types(first: Any, joints: JointMap, sparm: str, hal: HalContext | None) -> list:
    """LinuxCNC's order: the module's own kinematics as type 0 and identity as type 1, or
    the other way round when ``sparm`` holds ``identityfirst``; the user type is 2."""
    identity = Identity(joints)
    user = UserK(joints, make_pins(UserKPins, hal, ""))
    own = [identity, first] if "identityfirst" in (sparm or "") else [first, identity]
    return [*own, user]


def switchable(
    name: str,
    own: Any,
    required: str,
    coordinates: str,
    sparm: str,
    hal: HalContext | None,
) -> SwitchKins:
    """A switchable module whose own kinematics map the joints of ``required`` (``xyzabc``)
    in order: ``coordinates=`` (default ``required``, no letter twice, at most as many
    joints) gives the identity type its joints, ``sparm=`` is as ``switchkins_types``."""
    joints = JointMap(
        coordinates or required, name, is_repeat_allowed=False, max_joints=len(required)
    )
    return SwitchKins(switchkins_types(own, joints, sparm, hal), joints, hal)


# ---------------------------------------------------------------- loading
def realtime_module(create: Callable[..., Any]) -> Callable[[Any, str, dict[str, str]], None]:
    """The ``rtapi_app_main`` of a kinematics module: ``loadrt NAME params...`` makes the
    kinematics with its HAL pins, and motmod (loaded next) uses it."""

    def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
        try:
            host.kinematics = create(hal=HalContext(host.hal, comp), **args)
        except TypeError as exc:
            raise HalError(f"{comp}: bad module parameter: {exc}") from None
        except (KinematicsError, ValueError) as exc:
            raise HalError(f"{comp}: {exc}") from None

    return rtapi_app_main


def module_name(name: str) -> str:
    """The Python module of a kinematics name: LinuxCNC's module name with ``-`` as ``_``
    (``xyzac-trt-kins`` -> ``motion.kinematics.xyzac_trt_kins``), or a dotted path."""
    if "." in name:
        return name
    return f"{__name__}.{name.replace('-', '_')}"


def load_kinematics(name: str, **params: Any) -> Kinematics:
    """Make kinematics by name (``trivkins``, ``xyzac-trt-kins``, or a dotted module path)
    with its module parameters, e.g. ``coordinates="xyyz"``; without HAL pins.

    Refuses a module that lacks ``create`` or whose object lacks any required function,
    listing everything missing (ARCH-008 style)."""
    if not name or not all(c.isalnum() or c in "_-." for c in name):
        raise ModuleInterfaceError(f"invalid kinematics module name {name!r}")
    wanted = module_name(name)
    try:
        module = importlib.import_module(wanted)
    except ModuleNotFoundError as exc:
        if exc.name is not None and not wanted.startswith(exc.name):
            raise  # the module exists but one of its own imports is missing
        try:
            module = importlib.import_module(name)
        except (ModuleNotFoundError, ValueError):
            raise ModuleInterfaceError(
                f"kinematics module {name!r} not found (tried {wanted}, {name})"
            ) from None
    require(module, ("create",), f"kinematics module {name!r}")
    accepts_hal = "hal" in inspect.signature(module.create).parameters
    try:
        kins = module.create(hal=None, **params) if accepts_hal else module.create(**params)
    except TypeError as exc:
        raise ModuleInterfaceError(f"kinematics module {name!r}: bad parameters: {exc}") from exc
    require(kins, REQUIRED_FUNCTIONS, f"kinematics module {name!r}")
    if not isinstance(getattr(kins, "num_joints", None), int):
        raise ModuleInterfaceError(f"kinematics module {name!r} is incomplete: missing num_joints")
    return kins


class JointCountFit:
    """Kinematics seen through motion's joint count, as LinuxCNC's motion sees any module:
    joints it lacks are 0 for forward kinematics, and joints the module maps beyond that
    count are left out of inverse results (``loadrt trivkins`` with ``motmod
    num_joints=3`` is an XYZ machine)."""

    def __init__(self, kins: Kinematics, num_joints: int) -> None:
        self.kins = kins
        self.num_joints = num_joints
        self._missing = max(kins.num_joints - num_joints, 0)
        # the axes of the joints motion has (a module mapping joints 1:1 says which)
        axes = getattr(kins, "joint_axes", None)
        if axes is None:
            self.axis_mask = getattr(kins, "axis_mask", (1 << num_joints) - 1)
        else:
            self.axis_mask = sum({1 << axis for axis in axes[:num_joints]})

    def __getattr__(self, name: str) -> Any:
        return getattr(self.kins, name)

    def forward(self, joints: Sequence[float]) -> Pose:
        return self.kins.forward([*joints[: self.num_joints], *[0.0] * self._missing])

    def inverse(self, pose: Pose) -> list[float]:
        values = self.kins.inverse(pose)[: self.num_joints]
        return values + [0.0] * (self.num_joints - len(values))

    def kinematics_type(self) -> KinematicsType:
        return self.kins.kinematics_type()

    def home(self, pose: Pose, joints: Sequence[float]) -> tuple[Pose, list[float]]:
        values = [*joints[: self.num_joints], *[0.0] * self._missing]
        home_pose, home_joints = self.kins.home(pose, values)
        return home_pose, home_joints[: self.num_joints]


def fit_joints(kins: Kinematics, num_joints: int) -> Kinematics:
    """``kins`` for a motion of ``num_joints`` joints (itself when the counts agree)."""
    if kins.num_joints == num_joints:
        return kins
    return JointCountFit(kins, num_joints)  # type: ignore[return-value]
