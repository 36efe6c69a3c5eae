"""External axis offsets (LinuxCNC's ``axis.L.eoffset-*`` pins, ``[AXIS_L]OFFSET_AV_RATIO``).

An axis with ``OFFSET_AV_RATIO = r`` (0 < r <= 0.9) gives the share r of its MAX_VELOCITY
and MAX_ACCELERATION to an offset that HAL adds to its coordinate, and keeps 1 - r for the
planners (coordinated moves and teleop jogs), so the sum stays within the axis's limits.
Without the key (r = 0) the axis has no external offset.

Each period (``plan``), with the axis's ``eoffset-enable`` on, the change of
``eoffset-counts`` since the last period times ``eoffset-scale`` adds to the requested
offset (``eoffset-request``), once all joints are homed and motion is on;
``eoffset-clear`` sets the request to 0. The offset itself (``eoffset``) follows the
request with its own trapezoidal planner (r of the axis's velocity and acceleration),
independently of the path: ``add`` steps it and adds it to the pose the planners made, in
coordinated and teleop mode. In free mode the offsets stay as they are (the joints keep
them). Turning ``eoffset-enable`` off stops the offset where it is, kept until cleared.

Soft limits: the planners keep their own pose within ``[AXIS_L]MIN_LIMIT..MAX_LIMIT``;
where the pose plus an offset would cross a limit, the axis is held at the limit (the
offset shrinks to what fits, its request stays) and ``motion.eoffset-limited`` is set
until the axis is back inside.

Machine on (``reset``): every offset and request is zero; the pose keeps the offsets the
machine had (they become part of the planners' position), so nothing moves at machine
off or on. Status: ``external_offsets_applied`` and ``eoffset_pose`` (task takes them out
of the position it gives the interpreter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from motion.free import FreePlanner
from nml.axes import NUM_AXES
from nml.pose import Pose

MAX_RATIO = 0.9


@dataclass
class EoffsetInputs:
    """An axis's ``axis.L.eoffset-*`` input pins of one period."""

    is_enabled: bool = False
    is_clear: bool = False
    counts: int = 0
    scale: float = 0.0


def tiny_distance(max_acc: float, dt: float) -> float:
    """An offset this small counts as none (LinuxCNC's stopping threshold)."""
    return max_acc * dt * dt * 0.001


class ExternalOffsets:
    """The external offsets of the nine axes; ``min_limit``/``max_limit`` are the axes'
    soft limits (the controller's lists, read as they change)."""

    def __init__(self, min_limit: list[float], max_limit: list[float]) -> None:
        self.min_limit, self.max_limit = min_limit, max_limit
        self.ratio = [0.0] * NUM_AXES
        self._full_vel = [math.inf] * NUM_AXES  # the axes' whole limits, as task sent them
        self._full_acc = [math.inf] * NUM_AXES
        self.planners: dict[int, FreePlanner] = {}  # axis -> its offset's planner (r > 0)
        self.request = [0.0] * NUM_AXES  # axis.L.eoffset-request
        self._last_counts: dict[int, int | None] = {}
        self.is_active = False  # motion.eoffset-active: an offset is not zero
        self.is_limited = False  # motion.eoffset-limited
        self.notes: list[str] = []  # operator messages, taken by the controller

    @property
    def axes(self) -> list[int]:
        """The axes that have an external offset (OFFSET_AV_RATIO > 0)."""
        return list(self.planners)

    def offset(self, axis: int) -> float:
        planner = self.planners.get(axis)
        return planner.pos if planner is not None else 0.0

    def offsets(self) -> list[float]:
        return [self.offset(axis) for axis in range(NUM_AXES)]

    # ------------------------------------------------------------------ configuration
    def set_ratio(self, axis: int, ratio: float) -> None:
        """[AXIS_L]OFFSET_AV_RATIO; out of 0..0.9 is refused (ValueError)."""
        if not 0.0 <= ratio <= MAX_RATIO:
            raise ValueError(f"OFFSET_AV_RATIO must be 0..{MAX_RATIO}, got {ratio}")
        self.ratio[axis] = ratio
        if ratio == 0.0:
            self.planners.pop(axis, None)
            self._last_counts.pop(axis, None)
            return
        self.planners[axis] = FreePlanner(1.0, 1.0)
        self._last_counts[axis] = None
        self._apply_limits(axis)

    def planning_velocity(self, axis: int, vel: float) -> float:
        """[AXIS_L]MAX_VELOCITY: the offset's share is kept, the planners' returned."""
        self._full_vel[axis] = vel
        self._apply_limits(axis)
        return (1.0 - self.ratio[axis]) * vel

    def planning_acceleration(self, axis: int, acc: float) -> float:
        self._full_acc[axis] = acc
        self._apply_limits(axis)
        return (1.0 - self.ratio[axis]) * acc

    def _apply_limits(self, axis: int) -> None:
        planner = self.planners.get(axis)
        if planner is None:
            return
        vel, acc = self._full_vel[axis], self._full_acc[axis]
        ratio = self.ratio[axis]
        planner.set_limits(
            ratio * vel if math.isfinite(vel) else 1.0,
            ratio * acc if math.isfinite(acc) else 1.0,
            -math.inf,
            math.inf,
        )

    # ------------------------------------------------------------------ each period
    def plan(self, inputs: dict[int, EoffsetInputs], can_offset: bool) -> None:
        """Read the input pins (``can_offset``: motion on and every joint homed)."""
        for axis, planner in self.planners.items():
            pins = inputs.get(axis)
            if pins is None:
                continue
            last = self._last_counts[axis]
            self._last_counts[axis] = pins.counts
            delta = 0 if last is None else pins.counts - last
            if not pins.is_enabled:
                planner.stop()  # held where it is until cleared or re-enabled
                self.request[axis] = planner.pos  # (counts then add to the offset held)
                continue
            if pins.is_clear:
                self.request[axis] = 0.0
            elif delta and can_offset and math.isfinite(pins.scale):
                self.request[axis] += delta * pins.scale
            else:
                continue
            if self.request[axis] != planner.target or not planner.is_active:
                planner.move_to(self.request[axis], planner.max_vel)

    def add(self, pose: Pose, dt: float) -> Pose:
        """Coordinated and teleop mode: step the offsets and add them to the planners'
        ``pose``, holding each axis at its soft limits."""
        if not self.planners:
            return pose
        values = pose.as_tuple()
        out = list(values)
        is_limited = False
        is_active = False
        for axis, planner in self.planners.items():
            offset = planner.step(dt)
            if offset == 0.0:
                continue
            base = values[axis]
            net = base + offset
            low, high = self.min_limit[axis], self.max_limit[axis]
            if net > high:
                net, is_limited = high, True
                planner.pos, planner.vel = high - base, 0.0
            elif net < low:
                net, is_limited = low, True
                planner.pos, planner.vel = low - base, 0.0
            out[axis] = net
            if abs(planner.pos) > tiny_distance(planner.max_acc, dt):
                is_active = True
        self.is_limited = is_limited
        self.is_active = is_active
        return Pose(*out)

    def remove(self, pose: Pose) -> list[float]:
        """The planners' pose of a commanded pose that holds the offsets."""
        values = list(pose.as_tuple())
        for axis, planner in self.planners.items():
            values[axis] -= planner.pos
        return values

    def reset(self) -> bool:
        """Machine on: every offset and request zero; True if an offset was not, so the
        caller takes the pose as the planners' position."""
        had_offsets = any(p.pos for p in self.planners.values())
        if self.is_limited:
            self.notes.append(
                "Note: motion enabled after reaching a coordinate soft limit with active "
                "external offsets"
            )
        for axis, planner in self.planners.items():
            planner.reset(0.0)
            self.request[axis] = 0.0
        self.is_active = self.is_limited = False
        return had_offsets
