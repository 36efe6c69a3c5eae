"""MPG wheels and the jog-stop inputs (motion(9) ``joint.N.jog-*``, ``axis.L.jog-*``,
``motion.jog-stop``, ``motion.jog-stop-immediate``, ``motion.jog-inhibit``).

``JogWheels`` is a part of ``MotionController`` (motion/controller.py): it uses the
controller's ``joints``, ``axis_planners``, ``mode``, ``homing``, ``is_enabled``,
``is_override_limits`` and its teleop reset and stop.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from motion.free import FreePlanner, JogLimitError
from motion.modes import COORD, FREE, TELEOP

if TYPE_CHECKING:
    from motion.controller import Inputs


@dataclass
class WheelInputs:
    """An MPG wheel on ``joint.N.jog-*`` or ``axis.L.jog-*`` (motion(9))."""

    counts: int = 0
    is_enabled: bool = False
    scale: float = 0.0  # machine units per count
    is_vel_mode: bool = False
    accel_fraction: float = 1.0


class JogWheels:
    """The wheels' and jog-stop inputs' part of each servo period."""

    _wheel_counts: dict[tuple[str, int], int]  # last jog-counts seen, per wheel
    _jog_stops: tuple[bool, bool]  # jog-stop, jog-stop-immediate last period

    def _jog_wheels(self, inputs: Inputs) -> None:
        """MPG wheels: each count moves the joint (free mode) or the axis (teleop mode) by
        jog-scale within its limits; counts that arrive while a wheel cannot jog are
        dropped, as LinuxCNC does (motion(9) jog pins)."""
        self.is_jog_inhibited = inputs.is_jog_inhibited
        self._stop_jogs_on_request(inputs.is_jog_stop, inputs.is_jog_stop_immediate)
        can_jog = self.is_enabled and not self.homing.is_homing and not self.is_jog_inhibited
        for index, wheel in enumerate(inputs.joint_wheels):
            delta = self._wheel_delta(("joint", index), wheel)
            if delta and can_jog and self.mode == FREE:
                joint = self.joints[index]
                override = self.is_override_limits or not joint.is_homed
                self._wheel_jog(joint.planner, delta * wheel.scale, wheel, override)
        for index, wheel in inputs.axis_wheels.items():
            delta = self._wheel_delta(("axis", index), wheel)
            if delta and can_jog and self.mode == TELEOP:
                planner = self.axis_planners[index]
                self._wheel_jog(planner, delta * wheel.scale, wheel, self.is_override_limits)

    def _stop_jogs_on_request(self, is_stop: bool, is_stop_immediate: bool) -> None:
        """motion.jog-stop / jog-stop-immediate: a rising edge stops the jogs running,
        braking or at once."""
        was_stop, was_stop_immediate = self._jog_stops
        self._jog_stops = (is_stop, is_stop_immediate)
        if self.homing.is_homing or self.mode == COORD:
            return
        is_stop_now = is_stop_immediate and not was_stop_immediate
        is_stop_braking = is_stop and not was_stop
        if self.mode == TELEOP:  # the teleop vector stops too (a cartesian jog)
            if is_stop_now:
                self._reset_teleop()
            elif is_stop_braking:
                self._stop_teleop()
            return
        planners = [j.planner for j in self.joints]
        if is_stop_now:
            for planner in planners:
                planner.reset(planner.pos)
        elif is_stop_braking:
            for planner in planners:
                planner.stop()

    @property
    def is_jogging(self) -> bool:
        """motion.jog-is-active: a joint (free mode) or an axis (teleop mode) jogs."""
        if self.mode == FREE and not self.homing.is_homing:
            return any(j.planner.is_active for j in self.joints)
        return self.mode == TELEOP and self._is_teleop_moving()

    def _wheel_delta(self, key: tuple[str, int], wheel: WheelInputs) -> int:
        last = self._wheel_counts.get(key, wheel.counts)
        self._wheel_counts[key] = wheel.counts
        return wheel.counts - last if wheel.is_enabled else 0

    @staticmethod
    def _wheel_jog(planner: FreePlanner, offset: float, wheel: WheelInputs, override: bool) -> None:
        # at a limit, or a bad scale: the wheel does nothing, as in LinuxCNC
        with contextlib.suppress(JogLimitError, ValueError):
            planner.jog_wheel(offset, wheel.accel_fraction, wheel.is_vel_mode, override)
