"""Spindles as motion drives them (MOT-065): the ``spindle.N.*`` pins' speed, direction,
CSS from the X position and M19 orientation, their commands, and the feedback read each
period (at-speed, the orient cycle, the index handshake and the revolutions the planner's
spindle-synchronised moves follow: G33, G33.1, G95).

``SpindleControl`` is a part of ``MotionController`` (motion/controller.py): it uses the
controller's ``spindles``, ``tp`` (the trajectory planner), ``sync_spindle``,
``carte_pos_cmd``, ``period_s``, ``is_enabled``, ``errors``, ``fault()`` and
``_orient_wait`` (a M19 wait the planner holds its next move for).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from nml import emc
from nml.commands import Refused, handler

AT_SPEED_SETTLE_PERIODS = 2  # see Spindle.settle_periods


class OrientState(enum.IntEnum):
    """EMC_SPINDLE_STAT.orient_state (LinuxCNC's EMCMOT_ORIENT_*)."""

    NONE = 0
    IN_PROGRESS = 1
    COMPLETE = 2
    FAULTED = 3


@dataclass
class Spindle:
    """One spindle as motion drives it (the ``spindle.N.*`` pins, MOT-065)."""

    speed: float = 0.0  # signed rpm commanded (negative: reverse); in CSS the maximum
    scale: float = 1.0
    css_factor: float = 0.0  # G96: rpm = css_factor / radius (signed); 0: fixed speed
    css_xoffset: float = 0.0  # machine X of the spindle axis (G5x + G92 + tool offsets)
    increasing: int = 0  # 1 after EMC_SPINDLE_INCREASE, -1 after DECREASE
    is_brake_on: bool = True
    is_override_enabled: bool = True
    # [SPINDLE_n] speed limits (rpm, positive): a commanded speed is clamped into them
    max_forward: float = math.inf
    min_forward: float = 0.0
    max_reverse: float = math.inf
    min_reverse: float = 0.0
    # M19: the orient pins and the cycle's state
    is_orienting: bool = False
    orient_angle: float = 0.0
    orient_mode: int = 0
    is_locked: bool = False
    orient_state: OrientState = OrientState.NONE
    orient_fault: int = 0
    # per period: speed output, index handshake and the feedback seen
    speed_out: float = 0.0  # rpm to the drive, after CSS, override, inhibit, rigid tap
    is_index_enabled: bool = False
    is_at_speed: bool = True
    is_inhibited: bool = False
    # periods during which at-speed is taken as false after a speed change: the pin
    # still tells about the old speed until the drive has seen the new one
    settle_periods: int = 0

    def clamp_speed(self) -> None:
        """Keep a commanded speed within the [SPINDLE_n] limits of its direction (0 is
        stop, never clamped), as LinuxCNC's motion does for each new speed."""
        if self.speed > 0:
            self.speed = min(max(self.speed, self.min_forward), self.max_forward)
        elif self.speed < 0:
            self.speed = -min(max(-self.speed, self.min_reverse), self.max_reverse)

    def stop_orienting(self) -> None:
        """M3, M4, M5 end any orient cycle and unlock the spindle."""
        self.is_orienting = self.is_locked = False
        self.orient_state = OrientState.NONE
        self.orient_fault = 0


@dataclass
class SpindleInputs:
    """HAL inputs of one spindle for one period (``spindle.N.*``)."""

    revs: float = 0.0  # encoder position in revolutions, reset to 0 at the index
    speed_in: float = 0.0  # measured revolutions per second
    is_at_speed: bool = True
    index_enable: bool = False  # cleared by the encoder at the index
    is_oriented: bool = False
    orient_fault: int = 0
    is_inhibited: bool = False
    is_amp_fault: bool = False


class SpindleControl:
    """The spindle commands and the spindles' part of each servo period."""

    spindles: list[Spindle]

    def stop_spindles(self) -> None:
        for spindle in self.spindles:
            spindle.stop_orienting()
            spindle.speed = spindle.css_factor = 0.0
            spindle.is_brake_on = True

    def _spindle_of(self, cmd: emc.EMC_SPINDLE_CMD_MSG) -> Spindle:
        """The spindle a command names; a new command ends a speed ramp (increasing) and
        at-speed settles again (MOT-065; ``spindle.N.*`` pins)."""
        if not 0 <= cmd.spindle < len(self.spindles):
            raise Refused(
                f"spindle {cmd.spindle} does not exist (num_spindles {len(self.spindles)})"
            )
        spindle = self.spindles[cmd.spindle]
        spindle.increasing = 0
        spindle.settle_periods = AT_SPEED_SETTLE_PERIODS
        return spindle

    @handler(emc.EMC_SPINDLE_SET_PARAMS)
    def _spindle_set_params(self, cmd: emc.EMC_SPINDLE_SET_PARAMS) -> None:
        """The [SPINDLE_n] speed limits, sent by task at start-up."""
        spindle = self._spindle_of(cmd)
        limits = (cmd.max_forward, cmd.min_forward, cmd.max_reverse, cmd.min_reverse)
        if not all(limit >= 0 for limit in limits):  # (NaN too)
            raise Refused(f"spindle {cmd.spindle}: speed limits must be >= 0, got {limits}")
        spindle.max_forward, spindle.min_forward = cmd.max_forward, cmd.min_forward
        spindle.max_reverse, spindle.min_reverse = cmd.max_reverse, cmd.min_reverse

    @handler(emc.EMC_SPINDLE_ON)
    def _spindle_on(self, cmd: emc.EMC_SPINDLE_ON) -> None:
        """M3/M4 (G96: the CSS factor)."""
        spindle = self._spindle_of(cmd)
        spindle.stop_orienting()
        spindle.speed = cmd.speed
        spindle.clamp_speed()
        spindle.css_factor, spindle.css_xoffset = cmd.factor, cmd.xoffset
        spindle.is_brake_on = False
        if cmd.wait_for_spindle_at_speed:
            self.tp.wait_for_spindle_at_speed()

    @handler(emc.EMC_SPINDLE_OFF)
    def _spindle_off(self, cmd: emc.EMC_SPINDLE_OFF) -> None:
        """M5."""
        spindle = self._spindle_of(cmd)
        spindle.stop_orienting()
        spindle.speed = spindle.css_factor = 0.0
        spindle.is_brake_on = True

    @handler(emc.EMC_SPINDLE_SPEED)
    def _spindle_speed(self, cmd: emc.EMC_SPINDLE_SPEED) -> None:
        """S: a new speed in the direction it turns (none while stopped)."""
        spindle = self._spindle_of(cmd)
        sign = -1.0 if spindle.speed < 0 else 1.0
        spindle.speed = sign * abs(cmd.speed) if spindle.speed else 0.0
        spindle.clamp_speed()
        spindle.css_factor = math.copysign(cmd.factor, sign) if spindle.speed else 0.0
        spindle.css_xoffset = cmd.xoffset
        if spindle.speed:  # feed moves wait for the new speed (motion(9) at-speed)
            self.tp.wait_for_spindle_at_speed()

    @handler(emc.EMC_SPINDLE_INCREASE, emc.EMC_SPINDLE_DECREASE)
    def _spindle_step(self, cmd: emc.EMC_SPINDLE_INCREASE | emc.EMC_SPINDLE_DECREASE) -> None:
        """Faster or slower by ``speed`` (100 rpm if 0), never through zero."""
        spindle = self._spindle_of(cmd)
        step = abs(cmd.speed) or 100.0
        spindle.increasing = 1
        if isinstance(cmd, emc.EMC_SPINDLE_DECREASE):
            step = -min(step, abs(spindle.speed))
            spindle.increasing = -1
        spindle.speed += step if spindle.speed >= 0 else -step
        spindle.clamp_speed()

    @handler(emc.EMC_SPINDLE_BRAKE_ENGAGE)
    def _spindle_brake_engage(self, cmd: emc.EMC_SPINDLE_BRAKE_ENGAGE) -> None:
        self._spindle_of(cmd).is_brake_on = True

    @handler(emc.EMC_SPINDLE_BRAKE_RELEASE)
    def _spindle_brake_release(self, cmd: emc.EMC_SPINDLE_BRAKE_RELEASE) -> None:
        self._spindle_of(cmd).is_brake_on = False

    @handler(emc.EMC_SPINDLE_ORIENT)
    def _spindle_orient(self, cmd: emc.EMC_SPINDLE_ORIENT) -> None:
        """M19: stop, then the drive turns to the angle and answers on is-oriented."""
        spindle = self._spindle_of(cmd)
        spindle.speed = spindle.css_factor = 0.0
        spindle.is_brake_on = spindle.is_locked = False
        spindle.is_orienting = True
        spindle.orient_angle, spindle.orient_mode = cmd.orientation, cmd.mode
        spindle.orient_state, spindle.orient_fault = OrientState.IN_PROGRESS, 0

    @handler(emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE)
    def _spindle_wait_orient(self, cmd: emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE) -> None:
        """The moves after it wait; inpos stays false until it completes (task waits)."""
        spindle = self._spindle_of(cmd)
        if spindle.orient_state == OrientState.FAULTED:
            raise Refused(f"spindle {cmd.spindle} orient fault {spindle.orient_fault}")
        timeout = cmd.timeout if cmd.timeout > 0 else math.inf
        if spindle.orient_state == OrientState.IN_PROGRESS:
            self._orient_wait = (cmd.spindle, timeout)

    @handler(emc.EMC_TRAJ_SET_SPINDLESYNC)
    def _spindle_sync(self, cmd: emc.EMC_TRAJ_SET_SPINDLESYNC) -> None:
        """G33, G76, G95: the moves queued next follow the spindle (MOT-062, MOT-065)."""
        if not 0 <= cmd.spindle < len(self.spindles):
            raise Refused(
                f"spindle {cmd.spindle} does not exist (num_spindles {len(self.spindles)})"
            )
        self.tp.set_spindle_sync(cmd.feed_per_revolution, bool(cmd.velocity_mode))
        if cmd.feed_per_revolution:
            self.sync_spindle = cmd.spindle

    @handler(emc.EMC_TRAJ_SET_SPINDLE_SCALE)
    def _spindle_scale(self, cmd: emc.EMC_TRAJ_SET_SPINDLE_SCALE) -> None:
        if not 0 <= cmd.spindle < len(self.spindles):
            raise Refused(
                f"spindle {cmd.spindle} does not exist (num_spindles {len(self.spindles)})"
            )
        self.spindles[cmd.spindle].scale = cmd.scale

    def _read_spindles(self, inputs: list[SpindleInputs]) -> None:
        """Spindle feedback: orient cycle, index handshake, the planner's spindle inputs."""
        for index, (spindle, pins) in enumerate(zip(self.spindles, inputs, strict=False)):
            spindle.is_at_speed = pins.is_at_speed and not spindle.settle_periods
            spindle.settle_periods = max(spindle.settle_periods - 1, 0)
            spindle.is_inhibited = pins.is_inhibited
            if pins.is_amp_fault and self.is_enabled:
                self.fault(f"spindle {index} amplifier fault")
            if spindle.is_orienting:
                if pins.orient_fault:
                    spindle.is_orienting = False
                    spindle.orient_state = OrientState.FAULTED
                    spindle.orient_fault = pins.orient_fault
                    self.errors.append(f"spindle {index} orient fault {pins.orient_fault}")
                elif pins.is_oriented:  # done: the spindle is held at the angle
                    spindle.is_orienting = False
                    spindle.is_locked = spindle.is_brake_on = True
                    spindle.orient_state = OrientState.COMPLETE
        self._check_orient_wait()
        tp = self.tp
        tp.is_start_held = self._orient_wait is not None
        if not inputs:
            return
        sync = self.spindles[self.sync_spindle]
        pins = inputs[self.sync_spindle]
        if not tp.is_waiting_for_index:
            sync.is_index_enabled = False  # (also when an abort ended the wait)
        elif sync.is_index_enabled and not pins.index_enable:  # the encoder saw the index
            sync.is_index_enabled = False
            tp.index_found()
        else:
            sync.is_index_enabled = True
        # revolutions counted in the programmed direction (a rigid tap's reversal excluded)
        direction = -1.0 if sync.speed < 0 else 1.0
        tp.spindle_revs = pins.revs * direction
        tp.spindle_rps = abs(pins.speed_in)
        tp.is_spindle_at_speed = all(
            s.is_at_speed for s in self.spindles if s.speed or s.css_factor
        )

    def _check_orient_wait(self) -> None:
        """EMC_SPINDLE_WAIT_ORIENT_COMPLETE: done, faulted (run aborted) or timed out."""
        if self._orient_wait is None:
            return
        index, seconds_left = self._orient_wait
        state = self.spindles[index].orient_state
        if state == OrientState.IN_PROGRESS and seconds_left > 0:
            self._orient_wait = (index, seconds_left - self.period_s)
            return
        self._orient_wait = None
        if state == OrientState.IN_PROGRESS:
            self.errors.append(f"spindle {index} orient timed out")
        if state != OrientState.COMPLETE:
            self.tp.abort()

    def _drive_spindles(self) -> None:
        """The speed each spindle is told: fixed or from the radius (G96 CSS), times the
        override, reversed by a rigid tap, 0 while inhibited or orienting."""
        x = self.carte_pos_cmd.x
        for index, spindle in enumerate(self.spindles):
            rpm = spindle.speed
            if spindle.css_factor:
                radius = abs(x - spindle.css_xoffset)
                css_rpm = abs(spindle.css_factor) / radius if radius > 0 else math.inf
                rpm = math.copysign(min(css_rpm, abs(spindle.speed)), spindle.css_factor)
            rpm *= spindle.scale
            if index == self.sync_spindle:
                rpm *= self.tp.spindle_reversal
            if spindle.is_orienting or spindle.is_inhibited:
                rpm = 0.0
            spindle.speed_out = rpm
