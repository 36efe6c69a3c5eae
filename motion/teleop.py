"""Teleop mode (MOT-016, MOT-021, MOT-055): follow a cartesian velocity vector.

``TeleopPlanner.step(dt)`` moves the 9-axis pose toward the commanded velocity vector.
The vector is scaled down as a whole so that no axis exceeds its velocity limit, and the
velocity changes along a straight line in velocity space, as fast as the tightest axis
acceleration allows: every axis starts and stops together (a coordinated stop, MOT-021).
Near an axis position limit the whole vector slows so that axis stops at the limit.

``JointLimiter`` keeps the joints within their own limits: the motion component adds up
what the teleop planners propose for one servo period (the axis jogs and the vector), and
the limiter slows that cartesian motion as a whole, direction kept, wherever a joint would
exceed its velocity or acceleration limit. It looks at the joints only through inverse
kinematics (finite differences of joint positions per period), so it works for any
kinematics module: exactly for linear ones (trivkins, corexy), to first order within one
period for the others.

``TeleopControl`` is teleop mode's part of the motion controller: the teleop vector
command and, each servo period, the axis jogs and the vector summed and kept within the
joint limits.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from motion.free import braking_speed
from motion.kinematics import KinematicsError
from motion.modes import TELEOP
from nml import emc
from nml.axes import AXIS_LETTERS, NUM_AXES
from nml.commands import Refused, handler
from nml.pose import Pose

# relative: rounding in finite differences of joint positions never counts as a limit crossed
LIMIT_TOLERANCE = 1e-7
# the joint limiter plans its braking for the soft limits at this fraction of the joints'
# deceleration, keeping the rest for what it cannot plan (an ABORT, a new jog mid-braking)
BRAKING_MARGIN = 0.95


class TeleopPlanner:
    def __init__(
        self,
        axis_max_vel: Sequence[float],
        axis_max_acc: Sequence[float],
        axis_min: Sequence[float] | None = None,
        axis_max: Sequence[float] | None = None,
    ) -> None:
        self.set_limits(
            axis_max_vel,
            axis_max_acc,
            [-math.inf] * NUM_AXES if axis_min is None else axis_min,
            [math.inf] * NUM_AXES if axis_max is None else axis_max,
        )
        self.pos = np.zeros(NUM_AXES)
        self.vel = np.zeros(NUM_AXES)
        self.target_vel = np.zeros(NUM_AXES)
        self.scale = 1.0

    def set_limits(
        self,
        axis_max_vel: Sequence[float],
        axis_max_acc: Sequence[float],
        axis_min: Sequence[float],
        axis_max: Sequence[float],
    ) -> None:
        """The [AXIS_L] velocity, acceleration and position limits (infinite: none)."""
        max_vel = _positive_vector("axis max velocity", axis_max_vel)
        max_acc = _positive_vector("axis max acceleration", axis_max_acc)
        min_pos, max_pos = _vector(axis_min), _vector(axis_max)
        if (min_pos > max_pos).any():
            raise ValueError("axis minimum limits must not exceed the maximum limits")
        self.max_vel, self.max_acc, self.min_pos, self.max_pos = max_vel, max_acc, min_pos, max_pos

    def reset(self, pos: Sequence[float]) -> None:
        """At rest at ``pos`` with a zero velocity command (entering teleop, MOT-027)."""
        self.pos = _vector(pos)
        self.vel = np.zeros(NUM_AXES)
        self.target_vel = np.zeros(NUM_AXES)

    def set_velocity(self, vel: Sequence[float]) -> None:
        """SET_TELEOP_VECTOR: the desired velocity of every axis."""
        values = [float(v) for v in vel]
        if not all(map(math.isfinite, values)):
            raise ValueError("teleop velocities must be finite numbers")
        self.target_vel = _vector(values)

    def abort(self) -> None:
        """ABORT in teleop: a coordinated stop within the acceleration limits (MOT-021)."""
        self.target_vel = np.zeros(NUM_AXES)

    @property
    def is_moving(self) -> bool:
        return bool(self.vel.any())

    def step(self, dt: float) -> np.ndarray:
        if not (self.target_vel.any() or self.vel.any()):
            return self.pos  # at rest, and staying there
        want = self.target_vel * self.scale
        want = want * _fit(np.abs(want), self.max_vel)
        # brake for the position limits along the line, at that line's deceleration
        line_acc = _line_limit(want, np.abs(want), self.max_acc)
        stop_speed = _stop_speed(self.pos, self.vel, want, line_acc, self.min_pos, self.max_pos, dt)
        want = want * _fit(np.array([np.linalg.norm(want)]), np.array([stop_speed]))
        change = want - self.vel
        step = change * _fit(np.abs(change), self.max_acc * dt)
        new_vel = self._brake_for_each_limit(self.vel + step, dt)
        new_pos = self.pos + 0.5 * (self.vel + new_vel) * dt
        # stop at a limit, but never pull in an axis that is already beyond one
        low, high = np.minimum(self.min_pos, self.pos), np.maximum(self.max_pos, self.pos)
        self.pos = np.clip(new_pos, low, high)
        self.vel = np.where(self.pos == new_pos, new_vel, 0.0)
        return self.pos

    def _brake_for_each_limit(self, vel: np.ndarray, dt: float) -> np.ndarray:
        """``vel`` with each axis slowed, at its own deceleration, where it could not
        otherwise stop before its position limit. A stop along one line (ABORT, a
        smaller vector) decelerates as its slowest axis allows; an axis near its limit may
        need its own, faster braking: the motion then leaves the line, never the limit.
        (Clipping at the limit instead would stop that axis within one period.)"""
        if not vel.any():
            return vel
        out = vel.tolist()
        now = self.vel.tolist()
        for i in np.flatnonzero(vel).tolist():
            v, acc = out[i], float(self.max_acc[i])
            room = self.max_pos[i] - self.pos[i] if v > 0 else self.pos[i] - self.min_pos[i]
            if not math.isfinite(room):
                continue
            room = max(float(room) - _stop_reserve(acc, dt), 0.0)
            toward = now[i] if v > 0 else -now[i]  # the speed toward that limit now (< 0: away)
            cap = braking_speed(room, toward, acc, dt)
            if abs(v) > cap:  # (never below what one period of braking leaves)
                out[i] = math.copysign(max(cap, toward - acc * dt, 0.0), v)
        return np.array(out)


@dataclass(frozen=True)
class JointLimits:
    """What the joints and axes allow, for one servo period of ``JointLimiter.fit``."""

    joint_max_vel: np.ndarray
    joint_max_acc: np.ndarray
    axis_max_acc: np.ndarray
    axis_min: np.ndarray  # soft limits; -inf / inf where overridden or absent
    axis_max: np.ndarray


@dataclass(frozen=True)
class Fit:
    """One servo period of teleop motion within the joint limits.

    The planners proposed to go from velocity ``v0`` to ``v1``. The motion aims at
    ``scale * v1`` (the proposal slowed as a whole for the joint velocity limits), or,
    when it must brake for a soft limit, at ``keep * v0`` (braking along its line, what
    the planners proposed waits); it goes ``fraction`` of the way from ``v0`` to that
    aim (joint and axis acceleration limits) and ends at ``end``. ``held``: the axes
    whose planners proposed to move on from rest against a soft limit they have reached."""

    scale: float
    keep: float
    fraction: float
    end: np.ndarray
    held: np.ndarray

    @property
    def is_exact(self) -> bool:
        """The planners' own proposal is carried out unchanged."""
        return self.scale == 1.0 and self.keep == 0.0 and self.fraction == 1.0

    def velocity(self, v0: np.ndarray, v1: np.ndarray) -> np.ndarray:
        """The velocity carried out, of the whole motion or of one planner's share."""
        return v0 + self.fraction * (self.scale * v1 + self.keep * v0 - v0)


class JointLimiter:
    """Slows a period's cartesian motion as a whole so no joint exceeds its max velocity or
    max acceleration, measured as finite differences of the joint positions per period."""

    def __init__(self, inverse: Callable[[np.ndarray], Sequence[float]]) -> None:
        self.inverse = inverse
        self.joints = np.zeros(0)  # joint positions now
        self.prev_joints = np.zeros(0)  # and one period earlier

    def reset(self, joints: Sequence[float]) -> None:
        """The joints stand still at ``joints``."""
        self.joints = np.array(joints, dtype=float)
        self.prev_joints = self.joints.copy()

    def advance(self, joints: Sequence[float]) -> None:
        """One period later the joints are at ``joints``."""
        self.prev_joints, self.joints = self.joints, np.array(joints, dtype=float)

    def fit(
        self,
        pos: np.ndarray,
        v0: np.ndarray,
        v1: np.ndarray,
        end: np.ndarray,
        limits: JointLimits,
        dt: float,
        is_braking_planned: bool = True,
    ) -> Fit:
        """The motion of one period from ``pos``: the planners move from velocity ``v0`` to
        ``v1``, to ``end`` (their own integration; used unchanged when the limits allow).
        ``is_braking_planned``: each moving axis has one planner, which brakes for its soft
        limits itself (false when a jog and the vector move the same axis)."""
        joints = self.joints
        n = len(joints)
        joint_vel, joint_acc = limits.joint_max_vel[:n], limits.joint_max_acc[:n]
        near = pos + v0 * dt  # fraction 0: the velocity kept
        q_near = np.asarray(self.inverse(near))[:n]
        joint_v0 = (q_near - joints) / dt  # joint velocities of v0 and of v1, held
        joint_v1 = np.zeros(n)
        scale, keep = 1.0, 0.0
        if v1.any():
            joint_v1 = (np.asarray(self.inverse(pos + v1 * dt))[:n] - joints) / dt
            scale = _fit(np.abs(joint_v1), joint_vel, LIMIT_TOLERANCE)
        # the soft limits, on the line of the motion (of the proposal when at rest)
        is_moving = bool(v0.any())
        line, joint_line = (v0, joint_v0) if is_moving else (scale * v1, scale * joint_v1)
        stop_speed, line_acc = _soft_limit_speed(
            pos, v0, line, joint_line, limits, dt, is_braking_planned
        )
        speed, current = float(np.linalg.norm(scale * v1)), float(np.linalg.norm(v0))
        if max(speed, current) > stop_speed * (1.0 + LIMIT_TOLERANCE):
            if is_moving:  # brake along the line; the planners' new directions wait
                scale, keep = 0.0, min(stop_speed, speed) / current
            else:
                scale *= stop_speed / speed
        held = np.zeros(len(pos), dtype=bool)
        if not is_moving and scale == 0.0 and v1.any():
            room = np.where(v1 > 0, limits.axis_max - pos, pos - limits.axis_min)
            direction = np.abs(v1) / float(np.linalg.norm(v1))
            held = (direction > _NEGLIGIBLE) & (room <= _stop_reserve(line_acc, dt) * direction)
        target_vel = scale * v1 + keep * v0
        joint_target = scale * joint_v1 + keep * joint_v0
        far = end if scale == 1.0 and keep == 0.0 else pos + 0.5 * (v0 + target_vel) * dt
        # joint velocity and acceleration are affine in the fraction between near and far
        q_far = np.asarray(self.inverse(far))[:n]
        fraction = min(
            # the velocity change of each period within the accelerations, so that the
            # finite differences (averages over two periods) are within them too, stop
            # included
            _fit(np.abs(joint_target - joint_v0), joint_acc * dt, LIMIT_TOLERANCE),
            _fit(np.abs(target_vel - v0), limits.axis_max_acc * dt, LIMIT_TOLERANCE),
            # and the finite differences themselves (a planner's own integration may differ)
            _largest_fraction((q_near - joints) / dt, (q_far - q_near) / dt, joint_vel),
            _largest_fraction(
                (q_near - 2.0 * joints + self.prev_joints) / dt**2,
                (q_far - q_near) / dt**2,
                joint_acc,
            ),
        )
        if fraction == 1.0:
            return Fit(scale, keep, 1.0, far, held)
        return Fit(scale, keep, fraction, near + fraction * (far - near), held)


def _soft_limit_speed(
    pos: np.ndarray,
    v0: np.ndarray,
    line: np.ndarray,
    joint_line: np.ndarray,
    limits: JointLimits,
    dt: float,
    is_braking_planned: bool,
) -> tuple[float, float]:
    """The highest speed along ``line`` (a velocity; ``joint_line`` the joints' at it)
    that still stops at the soft limits decelerating as the axes and joints allow, and
    that deceleration.

    The planners brake for the soft limits themselves, at their axes' acceleration: too
    late only where the joints decelerate slower along the line, or where two planners
    move one axis (``is_braking_planned`` false); elsewhere no limit (infinite)."""
    n = len(joint_line)
    axis_line_acc = _line_limit(line, np.abs(line), limits.axis_max_acc)
    joint_line_acc = _line_limit(line, np.abs(joint_line), limits.joint_max_acc[:n])
    if is_braking_planned and joint_line_acc >= axis_line_acc * (1.0 - LIMIT_TOLERANCE):
        return math.inf, math.inf
    line_acc = min(axis_line_acc, joint_line_acc) * BRAKING_MARGIN
    return _stop_speed(pos, v0, line, line_acc, limits.axis_min, limits.axis_max, dt), line_acc


# components of a direction smaller than this do not move (and are not divided by)
_NEGLIGIBLE = 1e-12


def _line_limit(vel: np.ndarray, rates: np.ndarray, limits: np.ndarray) -> float:
    """The largest speed or acceleration along the direction of ``vel`` that keeps each
    ``rates`` entry (what that entry does at velocity ``vel``) within its ``limits``."""
    speed = float(np.linalg.norm(vel))
    if not speed > 0.0:
        return math.inf
    per_speed = rates / speed
    used = per_speed > _NEGLIGIBLE
    return float(np.min(limits[used] / per_speed[used])) if used.any() else math.inf


def _stop_speed(
    pos: np.ndarray,
    vel: np.ndarray,
    line: np.ndarray,
    line_acc: float,
    min_pos: np.ndarray,
    max_pos: np.ndarray,
    dt: float,
) -> float:
    """The highest speed along the direction of ``line`` for the next period that still
    lets the motion, now at velocity ``vel``, stop before every position limit ahead
    decelerating at ``line_acc``; infinite when no limit is ahead.

    ``braking_speed`` plans a continuous stop after the next period; stopping in whole
    periods can take up to ``line_acc * dt**2 / 8`` further, which is kept in reserve
    (the motion may stop that much short of the limit)."""
    speed = float(np.linalg.norm(line))
    if not speed > 0.0 or math.isinf(line_acc):
        return math.inf
    direction = np.abs(line) / speed
    moving = direction > _NEGLIGIBLE
    room = np.where(line > 0, max_pos - pos, pos - min_pos)[moving]
    along = np.maximum(room, 0.0) / direction[moving]  # distance to each limit on the line
    if not np.isfinite(along).any():
        return math.inf
    along = np.maximum(along - _stop_reserve(line_acc, dt), 0.0)
    current = float(np.linalg.norm(vel))
    stop = min(braking_speed(dist, current, line_acc, dt) for dist in along.tolist())
    return max(stop, 0.0)


def _stop_reserve(line_acc: float, dt: float) -> float:
    """How much further than a continuous stop a stop in whole periods may take."""
    return line_acc * dt * dt / 8.0


def _largest_fraction(start: np.ndarray, slope: np.ndarray, limit: np.ndarray) -> float:
    """The largest t in [0, 1] with |start + t * slope| <= limit for every entry that is
    within its limit at t = 0 (one already beyond cannot be helped by a smaller t); 1 when
    every entry is within its limit (give or take LIMIT_TOLERANCE) at t = 1."""
    tolerance = 1.0 + LIMIT_TOLERANCE
    if (np.abs(start + slope) <= limit * tolerance).all():
        return 1.0
    fraction = 1.0
    for value, rate, bound in zip(start.tolist(), slope.tolist(), limit.tolist(), strict=True):
        if abs(value) > bound * tolerance or rate == 0.0:
            continue
        room = (bound - value) if rate > 0 else (-bound - value)
        fraction = min(fraction, room / rate)
    return max(fraction, 0.0)


def _fit(amount: np.ndarray, limit: np.ndarray, tolerance: float = 0.0) -> float:
    """The largest factor <= 1 that keeps every ``amount`` within its ``limit``; 1 while
    none exceeds its limit by more than the relative ``tolerance``."""
    over = amount > limit * (1.0 + tolerance)
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


class TeleopControl:
    """Teleop mode's part of ``MotionController`` (motion/controller.py): the teleop
    vector command, reset and stop, and each teleop servo period. It uses the
    controller's ``axis_planners`` (one per world axis: the axis jogs), ``teleop`` (the
    vector's ``TeleopPlanner``), ``joint_limiter``, ``joints``, ``kins``, ``eoffsets``,
    ``carte_pos_cmd``, ``mode``, ``is_enabled``, ``is_jog_inhibited`` and
    ``is_override_limits``, ``fault``, ``kins_joints`` and ``_set_joints_from_pose``."""

    @handler(emc.EMC_TRAJ_SET_TELEOP_VECTOR)
    def _teleop_vector(self, cmd: emc.EMC_TRAJ_SET_TELEOP_VECTOR) -> None:
        """SET_TELEOP_VECTOR (MOT-055): the cartesian velocity teleop mode follows, on top
        of any axis jogs; a zero vector brings it to a coordinated stop."""
        if self.mode != TELEOP:
            raise Refused("teleop vector needs teleop mode")
        if not self.is_enabled:
            raise Refused("teleop vector needs motion enabled")
        vector = cmd.vector.values()
        if any(vector) and self.is_jog_inhibited:
            raise Refused("jogging is inhibited (motion.jog-inhibit)")
        for index, value in enumerate(vector):
            if value and not self._has_axis(index):
                raise Refused(f"axis {AXIS_LETTERS[index]} is not used by this machine")
        self.teleop.set_velocity(vector)

    def _reset_teleop(self) -> None:
        """Teleop at rest where the pose is (entering teleop MOT-027, motion off)."""
        pose = self.eoffsets.remove(self.carte_pos_cmd)  # (hook: without external offsets)
        for planner, value in zip(self.axis_planners, pose, strict=True):
            planner.reset(value)
        self.teleop.reset(pose)
        joints = [j.pos_cmd for j in self.kins_joints]
        if pose != list(self.carte_pos_cmd):  # (external offsets held: joints without them)
            joints = self.kins.inverse(Pose(*pose))
        self.joint_limiter.reset(joints)

    def _stop_teleop(self) -> None:
        """ABORT or jog-stop in teleop (MOT-021): the jogs' velocities join the vector's,
        and the vector planner brings the sum to zero along a straight line in velocity
        space, so all axes stop together within the axis and joint limits."""
        jogs = self.axis_planners
        self.teleop.vel = self.teleop.vel + np.array([p.vel for p in jogs])
        self.teleop.abort()
        for planner in jogs:
            planner.reset(planner.pos)

    def _is_teleop_resting(self) -> bool:
        """At rest with nothing asked of teleop (no jog, no vector, no external offset):
        a period would change nothing (most periods of a homed machine at rest)."""
        return not (
            self.eoffsets.planners or self.teleop.target_vel.any() or self._is_teleop_moving()
        )

    def _is_teleop_moving(self) -> bool:
        return self.teleop.is_moving or any(p.is_active or p.vel for p in self.axis_planners)

    def _teleop_step(self, dt: float) -> None:
        """One teleop period: the axis jogs and the teleop vector each plan their own
        motion; their sum is carried out, slowed as a whole where a joint would exceed its
        velocity or acceleration limit, and each planner goes on from its share of what
        was carried out. Every planner's position is the commanded pose's."""
        jogs, vector = self.axis_planners, self.teleop
        if self._is_teleop_resting():
            return  # nothing moves and nothing will: the joints hold their commands
        start = vector.pos.copy()
        jog_v0 = np.array([p.vel for p in jogs])
        vector_v0 = vector.vel.copy()
        jog_end = np.array([p.step(dt) for p in jogs])
        vector_end = vector.step(dt)
        jog_v1 = np.array([p.vel for p in jogs])
        v0, v1 = jog_v0 + vector_v0, jog_v1 + vector.vel
        end = jog_end + (vector_end - start)
        if v0.any() or v1.any():
            # a jog and the vector on one axis: neither planner alone brakes for its limits
            is_jogging = (jog_v0 != 0) | (jog_v1 != 0)
            is_vector_moving = (vector_v0 != 0) | (vector.vel != 0)
            is_braking_planned = not (is_jogging & is_vector_moving).any()
            limits = self._teleop_limits()
            try:
                fit = self.joint_limiter.fit(start, v0, v1, end, limits, dt, is_braking_planned)
            except KinematicsError as exc:
                self.fault(f"inverse kinematics failed: {exc}; motion stopped")
                return
            end = fit.end
            if not fit.is_exact:
                self._follow_fit(fit, jog_v0, jog_v1, vector_v0)
            # jogs that have come as far as the soft limits let them end there
            for planner in itertools.compress(jogs, fit.held.tolist()):
                planner.reset(planner.pos)
        for planner, value in zip(jogs, end.tolist(), strict=True):
            planner.pos = value
            if not planner.is_enabled:
                planner.target = value
        vector.pos = end.copy()
        pose = Pose(*end.tolist())
        self._set_joints_from_pose(self.eoffsets.add(pose, dt))  # (hook: external offsets)
        if self.eoffsets.planners:
            self.joint_limiter.advance(self.kins.inverse(pose))
        else:
            self.joint_limiter.advance([j.pos_cmd for j in self.kins_joints])

    def _follow_fit(
        self, fit: Fit, jog_v0: np.ndarray, jog_v1: np.ndarray, vector_v0: np.ndarray
    ) -> None:
        """Each teleop planner's velocity becomes its share of the slowed motion."""
        jog_vel = fit.velocity(jog_v0, jog_v1)
        for planner, vel in zip(self.axis_planners, jog_vel.tolist(), strict=True):
            planner.vel = vel
        self.teleop.vel = fit.velocity(vector_v0, self.teleop.vel)

    def _teleop_limits(self) -> JointLimits:
        vector = self.teleop
        is_overridden = self.is_override_limits
        return JointLimits(
            joint_max_vel=np.array([j.planner.max_vel for j in self.joints]),
            joint_max_acc=np.array([j.planner.max_acc for j in self.joints]),
            axis_max_acc=vector.max_acc,
            axis_min=np.full(NUM_AXES, -math.inf) if is_overridden else vector.min_pos,
            axis_max=np.full(NUM_AXES, math.inf) if is_overridden else vector.max_pos,
        )
