"""Teleop mode planning (MOT-016, MOT-021, MOT-055): follow a cartesian velocity vector.

``TeleopPlanner.step(dt)`` moves the 9-axis pose toward the commanded velocity vector.
The vector is scaled down as a whole so that no axis exceeds its velocity limit, and the
velocity changes along a straight line in velocity space, as fast as the tightest axis
acceleration allows: every axis starts and stops together (a coordinated stop, MOT-021).
Near an axis position limit the whole vector slows so that axis stops at the limit.
The motion component converts the pose to joints through inverse kinematics.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from motion.pose import NUM_AXES


class TeleopPlanner:
    def __init__(
        self,
        axis_max_vel: Sequence[float],
        axis_max_acc: Sequence[float],
        axis_min: Sequence[float] | None = None,
        axis_max: Sequence[float] | None = None,
    ) -> None:
        self.max_vel = _positive_vector("axis max velocity", axis_max_vel)
        self.max_acc = _positive_vector("axis max acceleration", axis_max_acc)
        self.min_pos = np.full(NUM_AXES, -math.inf) if axis_min is None else _vector(axis_min)
        self.max_pos = np.full(NUM_AXES, math.inf) if axis_max is None else _vector(axis_max)
        if (self.min_pos > self.max_pos).any():
            raise ValueError("axis minimum limits must not exceed the maximum limits")
        self.pos = np.zeros(NUM_AXES)
        self.vel = np.zeros(NUM_AXES)
        self.target_vel = np.zeros(NUM_AXES)
        self.scale = 1.0

    def reset(self, pos: Sequence[float]) -> None:
        """At rest at ``pos`` with a zero velocity command (entering teleop, MOT-027)."""
        self.pos = _vector(pos)
        self.vel = np.zeros(NUM_AXES)
        self.target_vel = np.zeros(NUM_AXES)

    def set_velocity(self, vel: Sequence[float]) -> None:
        """SET_TELEOP_VECTOR: the desired velocity of every axis."""
        self.target_vel = _vector(vel)

    def abort(self) -> None:
        """ABORT in teleop: a coordinated stop within the acceleration limits (MOT-021)."""
        self.target_vel = np.zeros(NUM_AXES)

    @property
    def is_moving(self) -> bool:
        return bool(self.vel.any())

    def step(self, dt: float) -> np.ndarray:
        want = self.target_vel * self.scale
        want = want * _fit(np.abs(want), self.max_vel)
        # brake for the position limits: per axis, the speed that still stops at the limit
        room = np.where(want > 0, self.max_pos - self.pos, self.pos - self.min_pos)
        room = np.maximum(room, 0.0)
        stop_speed = np.sqrt(2.0 * self.max_acc * room)
        want = want * _fit(np.abs(want), stop_speed)
        change = want - self.vel
        step = change * _fit(np.abs(change), self.max_acc * dt)
        new_vel = self.vel + step
        new_pos = self.pos + 0.5 * (self.vel + new_vel) * dt
        self.pos = np.clip(new_pos, self.min_pos, self.max_pos)
        self.vel = np.where(self.pos == new_pos, new_vel, 0.0)
        return self.pos


def _fit(amount: np.ndarray, limit: np.ndarray) -> float:
    """The largest factor <= 1 that keeps every ``amount`` within its ``limit``."""
    over = amount > limit
    if not over.any():
        return 1.0
    return float(np.min(limit[over] / amount[over]))


def _vector(values: Sequence[float]) -> np.ndarray:
    vec = np.array(list(values), dtype=float)
    if vec.shape != (NUM_AXES,) or np.isnan(vec).any():
        raise ValueError(f"expected {NUM_AXES} numbers (X Y Z A B C U V W)")
    return vec


def _positive_vector(name: str, values: Sequence[float]) -> np.ndarray:
    vec = _vector(values)
    if (vec <= 0).any():
        raise ValueError(f"{name} must be positive on every axis")
    return vec
