"""Cartesian pose with the nine named axes X Y Z A B C U V W (KIN-002)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from nml.axes import AXIS_LETTERS as _LETTERS
from nml.axes import NUM_AXES as NUM_AXES

AXIS_LETTERS = _LETTERS.lower()  # (the names of EmcPose's fields)


@dataclass(slots=True)
class EmcPose:
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
    def from_seq(cls, values: Iterable[float]) -> EmcPose:
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
        return getattr(self, axis_attr(letter))

    def __setitem__(self, letter: str, value: float) -> None:
        setattr(self, axis_attr(letter), float(value))

    def is_finite(self) -> bool:
        return all(map(math.isfinite, self.as_tuple()))


def axis_attr(letter: str) -> str:
    """Lower-case axis letter, or ValueError naming the bad letter."""
    low = letter.lower()
    if len(low) != 1 or low not in AXIS_LETTERS:
        raise ValueError(f"unknown axis letter {letter!r} (expected one of XYZABCUVW)")
    return low


def axis_index(letter: str) -> int:
    return AXIS_LETTERS.index(axis_attr(letter))
