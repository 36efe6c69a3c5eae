"""Free-mode planning: one trapezoidal planner per joint (MOT-015, MOT-045..052).

``FreePlanner.step(dt)`` is called once per servo period; it moves ``pos`` toward
``target`` with speed at most ``min(vel_limit * scale, max_vel)`` and acceleration at most
``max_acc``. The target may change at any time (retargeting); the planner then brakes or
reverses within the acceleration limit.

Integration is trapezoidal (``pos += (v_old + v_new) / 2 * dt``): with it the discrete
braking distance equals the continuous one, so the planner stops exactly at the target.

Jog rules (``jog_cont`` / ``jog_incr`` / ``jog_abs`` / ``stop``) keep targets inside the
soft limits (MOT-074), never planning past them unless limits are overridden (MOT-042).
"""

from __future__ import annotations

import math


class JogLimitError(ValueError):
    """A jog that would move further past a soft limit the joint is already at (MOT-046)."""


def check_finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return value


def check_positive(name: str, value: float) -> float:
    value = check_finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be positive, got {value}")
    return value


def braking_speed(dist: float, v_toward: float, acc: float, dt: float, v_end: float = 0.0) -> float:
    """Largest speed for the next period that still lets trapezoidal integration reach
    ``v_end`` within ``dist`` at deceleration ``acc``, given the current speed ``v_toward``.

    From ``v_new**2 <= v_end**2 + 2*acc*(dist - (v_toward + v_new)/2*dt)``. Negative when a
    stop within ``dist`` is no longer possible."""
    adt = acc * dt
    disc = adt * adt + 4.0 * (v_end * v_end + 2.0 * acc * dist - adt * v_toward)
    if disc < 0.0:
        return -1.0
    return 0.5 * (math.sqrt(disc) - adt)


class FreePlanner:
    """Trapezoidal single-joint planner with a retargetable position target."""

    def __init__(
        self,
        max_vel: float,
        max_acc: float,
        min_limit: float = -math.inf,
        max_limit: float = math.inf,
        pos: float = 0.0,
    ) -> None:
        self.set_limits(max_vel, max_acc, min_limit, max_limit)
        self.pos = check_finite("position", pos)
        self.vel = 0.0
        self.target = self.pos
        self.vel_limit = self.max_vel
        self.acc_fraction = 1.0  # of max_acc; a wheel jog may ask for less
        self.scale = 1.0
        self.is_enabled = False  # planning on; set by a move, cleared when it ends
        self.is_stopping = False

    # ------------------------------------------------------------------ setup
    def set_limits(
        self, max_vel: float, max_acc: float, min_limit: float, max_limit: float
    ) -> None:
        self.max_vel = check_positive("max velocity", max_vel)
        self.max_acc = check_positive("max acceleration", max_acc)
        min_limit, max_limit = float(min_limit), float(max_limit)
        if math.isnan(min_limit) or math.isnan(max_limit) or min_limit > max_limit:
            raise ValueError(f"invalid soft limits [{min_limit}, {max_limit}]")
        self.min_limit, self.max_limit = min_limit, max_limit

    def reset(self, pos: float) -> None:
        """Stand still at ``pos``, disabled (entering free mode, MOT-024)."""
        self.pos = check_finite("position", pos)
        self.vel = 0.0
        self.target = self.pos
        self.is_enabled = False
        self.is_stopping = False

    @property
    def is_active(self) -> bool:
        """Moving or about to move."""
        return self.is_enabled

    # ------------------------------------------------------------------ moves
    def move_to(self, target: float, vel: float) -> None:
        """Plan to ``target`` at speed ``vel`` (no limit check; see the jog methods)."""
        self.target = check_finite("target", target)
        self.vel_limit = min(check_positive("velocity", vel), self.max_vel)
        self.acc_fraction = 1.0
        self.is_stopping = False
        self.is_enabled = True

    def stop(self) -> None:
        """Decelerate at the acceleration limit to a stop (JOG_STOP, ABORT: MOT-020/052)."""
        if self.is_enabled:
            self.is_stopping = True

    def jog_cont(self, vel: float, is_override_limits: bool = False) -> None:
        """Jog at signed speed ``vel`` until the soft limit (MOT-045/047)."""
        vel = check_finite("jog velocity", vel)
        if vel == 0:
            raise ValueError("jog velocity must not be zero")
        end = math.inf if vel > 0 else -math.inf
        if not is_override_limits:
            self._check_limit_direction(vel)
            end = self.max_limit if vel > 0 else self.min_limit
        if math.isinf(end):  # no limit that way: a target far beyond any travel (MOT-045)
            end = self.pos + math.copysign(1e9, vel)
        self.move_to(end, abs(vel))

    def jog_incr(self, offset: float, vel: float, is_override_limits: bool = False) -> None:
        """Jog by ``offset``; increments add to a jog still running (MOT-048)."""
        offset = check_finite("jog increment", offset)
        base = self.target if self.is_enabled and not self.is_stopping else self.pos
        self._jog_to(base + offset, vel, is_override_limits)

    def jog_abs(self, position: float, vel: float, is_override_limits: bool = False) -> None:
        """Jog to an absolute joint position; a new one replaces the target (MOT-051)."""
        self._jog_to(check_finite("jog position", position), vel, is_override_limits)

    def jog_wheel(
        self,
        offset: float,
        acc_fraction: float,
        is_vel_mode: bool,
        is_override_limits: bool = False,
    ) -> None:
        """An MPG wheel turned by ``offset`` (jog-counts * jog-scale): move that much more at
        the velocity limit and ``acc_fraction`` of the acceleration limit. In velocity
        mode the target stays within braking distance, so the joint stops soon after the
        wheel does, even if the counts are not all travelled (motion(9) jog-vel-mode)."""
        base = self.target if self.is_enabled and not self.is_stopping else self.pos
        target = base + check_finite("wheel jog", offset)
        if not 0.0 < acc_fraction <= 1.0:
            acc_fraction = 1.0  # as LinuxCNC: other values are ignored
        if is_vel_mode:
            reach = self.max_vel * self.max_vel / (2.0 * self.max_acc * acc_fraction)
            target = min(max(target, self.pos - reach), self.pos + reach)
        self._jog_to(target, self.max_vel, is_override_limits)
        self.acc_fraction = acc_fraction

    def _jog_to(self, target: float, vel: float, is_override_limits: bool) -> None:
        if not is_override_limits:
            if target != self.pos:
                self._check_limit_direction(target - self.pos)
            target = min(max(target, self.min_limit), self.max_limit)
        self.move_to(target, abs(check_finite("jog velocity", vel)))

    def _check_limit_direction(self, direction: float) -> None:
        if direction > 0 and self.pos >= self.max_limit:
            raise JogLimitError(
                f"at or beyond the positive soft limit {self.max_limit:g}: cannot jog further"
            )
        if direction < 0 and self.pos <= self.min_limit:
            raise JogLimitError(
                f"at or beyond the negative soft limit {self.min_limit:g}: cannot jog further"
            )

    # ------------------------------------------------------------------ servo period
    def step(self, dt: float) -> float:
        """Advance one period; returns the new position command."""
        if not self.is_enabled:
            self.vel = 0.0
            return self.pos
        acc = self.max_acc * self.acc_fraction
        adt = acc * dt
        v = self.vel
        if self.is_stopping:
            v_new = max(v - adt, 0.0) if v > 0 else min(v + adt, 0.0)
        else:
            dist = self.target - self.pos
            sign = 1.0 if dist >= 0 else -1.0
            v_cap = min(self.vel_limit * self.scale, self.max_vel)
            v_brake = braking_speed(abs(dist), v * sign, acc, dt)
            v_des = sign * min(v_cap, max(v_brake, 0.0))
            v_new = min(max(v_des, v - adt), v + adt)
        before = self.target - self.pos
        self.pos += 0.5 * (v + v_new) * dt
        self.vel = v_new
        if self.is_stopping:
            if v_new == 0.0:
                self.target = self.pos
                self.is_enabled = self.is_stopping = False
            return self.pos
        after = self.target - self.pos
        is_crossing = after == 0.0 or (after > 0.0) != (before > 0.0) or abs(after) < 1e-12
        if is_crossing and abs(v_new) <= adt:
            self.pos = self.target  # arrival: the last fraction of a period
            self.vel = 0.0
            self.is_enabled = False
        return self.pos
