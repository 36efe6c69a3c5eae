"""The project's pose: a point of the nine world axes X Y Z A B C U V W (KIN-002).

``Pose`` is what code computes with (kinematics, the planners, motion's servo period):
a plain object whose fields are the axis letters, ``pose.x``. Messages carry a pose in
LinuxCNC's layout, ``nml.emc.EmcPose`` (``tran.x``, then ``a`` ... ``w``); that struct is
only the wire form of a ``Pose``: ``msg.end.pose()`` reads one, ``msg.end.set(pose)``
writes one, ``EmcPose.of(pose)`` makes one. The interpreter's Python handlers see a third
form, LinuxCNC's ``self.tool_offset.tran.x``: ``task.interp.python.view.EmcPose``, a
``Pose`` that also reads as ``tran`` and writes through to the interpreter.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from nml.axes import AXIS_LETTERS, NUM_AXES

AXIS_NAMES = AXIS_LETTERS.lower()  # the names of Pose's fields, in order


@dataclass(slots=True)
class Pose:
    """A point in world coordinates; A, B, C are rotations about X, Y, Z."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    a: float = 0.0
    b: float = 0.0
    c: float = 0.0
    u: float = 0.0
    v: float = 0.0
    w: float = 0.0

    @classmethod
    def from_seq(cls, values: Iterable[float]) -> Pose:
        """Build a pose from up to nine values in X Y Z A B C U V W order."""
        items = [float(v) for v in values]
        if len(items) > NUM_AXES:
            raise ValueError(f"a pose has {NUM_AXES} axes, got {len(items)} values")
        return cls(*items)

    def as_tuple(self) -> tuple[float, ...]:
        # spelled out: dataclasses.astuple deep-copies every field, which costs more
        # than the rest of a servo period's kinematics
        return (self.x, self.y, self.z, self.a, self.b, self.c, self.u, self.v, self.w)

    def __iter__(self) -> Iterator[float]:
        return iter(self.as_tuple())

    def __getitem__(self, letter: str) -> float:
        return getattr(self, _axis_attr(letter))

    def __setitem__(self, letter: str, value: float) -> None:
        setattr(self, _axis_attr(letter), float(value))

    def is_finite(self) -> bool:
        return all(map(math.isfinite, self.as_tuple()))


def _axis_attr(letter: str) -> str:
    """Lower-case axis letter, or ValueError naming the bad letter."""
    low = letter.lower()
    if len(low) != 1 or low not in AXIS_NAMES:
        raise ValueError(f"unknown axis letter {letter!r} (expected one of {AXIS_LETTERS})")
    return low
