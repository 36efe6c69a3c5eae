"""millturn: switchable kinematics for a mill-turn machine, LinuxCNC's template for
kinematics written with halcompile. Type 0 (the start) is the mill: joints 0-3 are X Y Z A;
type 1 the lathe: X is joint 2, Y is minus joint 1, Z is joint 0. Its demonstration pins
and parameters are there too: ``millturn.in`` is copied to ``millturn.out`` by inverse
kinematics, ``millturn.param-rw``/``param-ro``, and the function ``millturn.0.fdemo``
counts its calls on ``millturn.0.fpin``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from hal.api import RtComponent, funct, param, pin
from hal.core import HalError
from motion.kinematics import HalContext, JointMap, SwitchKins, make_pins
from nml.pose import Pose


class MillTurnPins(RtComponent):
    in_ = pin("u32 in")
    out = pin("u32 out")
    param_rw = param("float rw")
    param_ro = param("float ro")


class MillTurnInstance(RtComponent):
    fpin = pin("s32 out")

    @funct("fdemo")
    def fdemo(self, period: int) -> None:
        self.fpin = self.fpin + 1


class Mill:
    def __init__(self, pins: Any) -> None:
        self.pins = pins

    def forward(self, joints: Sequence[float]) -> Pose:
        return Pose(joints[0], joints[1], joints[2], joints[3])

    def inverse(self, pose: Pose) -> list[float]:
        self.pins.out = self.pins.in_  # (the template's example of a pin update)
        return [pose.x, pose.y, pose.z, pose.a]


class Turn(Mill):
    def forward(self, joints: Sequence[float]) -> Pose:
        return Pose(joints[2], -joints[1], joints[0], joints[3])

    def inverse(self, pose: Pose) -> list[float]:
        self.pins.out = self.pins.in_
        return [pose.z, -pose.y, pose.x, pose.a]


def create(hal: HalContext | None = None) -> SwitchKins:
    pins = make_pins(MillTurnPins, hal, "millturn")
    return SwitchKins([Mill(pins), Turn(pins)], JointMap("xyza", "millturn"), hal)


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    if args:
        raise HalError(f"millturn: unknown argument '{sorted(args)[0]}'")
    instance = MillTurnInstance.create(host.hal, comp, "millturn.0")
    host.add_function(comp, "millturn.0.fdemo", instance.fdemo)
    host.kinematics = create(hal=HalContext(host.hal, comp))
