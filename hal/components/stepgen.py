"""stepgen: software step pulse generation, position or velocity mode (step/dir outputs).

``loadrt stepgen step_type=0[,0...] [ctrl_type=p|v[,...]]``. Functions:

- ``stepgen.make-pulses`` (no floating point; the base thread when one exists) runs a
  direct digital synthesis accumulator: a fixed-point position in steps with 28 fraction
  bits, starting half a step in, so steps happen half-way between whole positions. Each
  call adds the current rate (ramped towards the target by the acceleration limit) and
  makes a step when the whole part changes. ``step`` stays high ``steplen`` ns, ``dir``
  may change ``dirhold`` ns after a step, and a reversal waits ``dirsetup`` ns more.
- ``stepgen.update-freq`` (servo thread) turns ``velocity-cmd`` (v mode) or
  ``position-cmd`` (p mode: match the command's velocity, then close the position error)
  into the step rate ``frequency``, limited by ``maxvel``/``maxaccel`` (0: only the limit
  that steplen + stepspace allow) in units scaled by ``position-scale`` steps per unit.
  Timing parameters are rounded up to whole base-thread periods, and written back.
- ``stepgen.capture-position`` publishes ``counts`` and ``position-fb`` (with the fraction
  of a step).
"""

from __future__ import annotations

import sys
from typing import Any

from hal.api import RtComponent, module_funct, param, pin
from hal.core import HalError

FRACTION_BITS = 28
ONE_STEP = 1 << FRACTION_BITS
HALF_STEP = 1 << (FRACTION_BITS - 1)
DEFAULT_BASE_NS = 50_000  # until make-pulses has run and told us its period
DEFAULT_SERVO_NS = 1_000_000


def _round_up(value: int, increment: int) -> int:
    """The smallest multiple of ``increment`` that is >= ``value``."""
    return 0 if value == 0 else increment * ((value - 1) // increment + 1)


class _Stepgen(RtComponent):
    counts = pin("s32 out")
    dir = pin("bit out")
    enable = pin("bit in")
    position_fb = pin("float out")
    step = pin("bit out")
    dirhold = param("u32 rw", default=1)
    dirsetup = param("u32 rw", default=1)
    frequency = param("float ro")
    maxaccel = param("float rw")
    maxvel = param("float rw")
    position_scale = param("float rw", default=1.0)
    rawcounts = param("s32 ro")
    steplen = param("u32 rw", default=1)
    stepspace = param("u32 rw", default=1)

    is_position_mode = True

    def setup(self) -> None:
        self.accum = HALF_STEP
        self.addval = 0  # accumulator increment per make-pulses call
        self.target_addval = 0
        self.deltalim = 0  # largest change of addval per call (acceleration limit)
        self.step_timer = self.dir_timer = self.reverse_timer = 0  # ns left
        self.is_holding = False  # a reversal waits for the direction setup time
        self.curr_dir = 0
        self.old_pos_cmd = 0.0
        self.base_ns = DEFAULT_BASE_NS
        self.checked_base_ns = DEFAULT_BASE_NS
        self.timing: tuple[int, int, int, int] | None = None  # validated steplen...dirsetup
        self.has_warned = False

    # ------------------------------------------------------------ base thread
    def pulses(self, period: int) -> None:
        self.base_ns = period
        self.step_timer = max(self.step_timer - period, 0)
        self.dir_timer = max(self.dir_timer - period, 0)
        if self.reverse_timer > 0:
            self.reverse_timer = max(self.reverse_timer - period, 0)
            if self.reverse_timer == 0:
                self.is_holding = False
        is_enabled = self.enable
        is_step = False
        if not self.is_holding and is_enabled:
            old = self.addval
            new = self.target_addval
            if self.deltalim:
                new = min(max(new, old - self.deltalim), old + self.deltalim)
            self.addval = new
            if (new >= 0) != (old >= 0) and self.reverse_timer:
                self.is_holding = True
        if not self.is_holding and is_enabled:
            before = self.accum
            self.accum = before + self.addval
            is_step = bool((before ^ self.accum) & ONE_STEP)
            self.rawcounts = self.accum >> FRACTION_BITS
        if self.dir_timer == 0 and self.addval:
            self.curr_dir = 1 if self.addval > 0 else -1
        if is_step:
            self.step_timer = self.steplen
            self.dir_timer = self.step_timer + self.dirhold
            self.reverse_timer = self.dir_timer + self.dirsetup
        self.step = self.step_timer != 0
        self.dir = self.curr_dir < 0

    # ------------------------------------------------------------ servo thread
    def _check_timing(self) -> None:
        """Round the timing parameters up to whole base periods (and keep them non-zero)."""
        base = self.base_ns
        current = (self.steplen, self.stepspace, self.dirhold, self.dirsetup)
        if current == self.timing and base == self.checked_base_ns:
            return
        steplen, stepspace, dirhold, dirsetup = current
        if dirhold + dirsetup == 0:
            dirhold = 1
        self.steplen = _round_up(max(steplen, 1), base)
        self.stepspace = _round_up(stepspace, base)
        self.dirsetup = _round_up(dirsetup, base)
        self.dirhold = _round_up(dirhold, base)
        self.timing = (self.steplen, self.stepspace, self.dirhold, self.dirsetup)
        self.checked_base_ns = base

    def update(self, period: int) -> None:
        dt = period * 1e-9
        base_s = self.base_ns * 1e-9
        scale = self.position_scale
        if -1e-20 < scale < 1e-20:
            self.position_scale = scale = 1.0
        self._check_timing()
        if not self.enable:
            if self.is_position_mode:
                self.old_pos_cmd = self.position_cmd * scale
            self.frequency = 0.0
            self.addval = self.target_addval = 0
            return
        max_freq = 1.0 / ((self.steplen + self.stepspace) * 1e-9)
        if self.maxvel <= 0.0:
            self.maxvel = 0.0
        elif self.maxvel * abs(scale) > max_freq:
            if not self.has_warned:
                self.has_warned = True
                print(
                    f"STEPGEN: {self.name}: maxvel of {int(self.maxvel * abs(scale))} "
                    f"steps/s is too high; the maximum is {int(max_freq)} steps/s",
                    file=sys.stderr,
                )
            self.maxvel = max_freq / abs(scale)
        else:
            max_freq = self.maxvel * abs(scale)
        max_acc = max_freq / dt  # at most: from 0 to full speed in one period
        if self.maxaccel <= 0.0:
            self.maxaccel = 0.0
        elif self.maxaccel * abs(scale) > max_acc:
            self.maxaccel = max_acc / abs(scale)
        else:
            max_acc = self.maxaccel * abs(scale)
        if self.is_position_mode:
            rate = self._position_rate(scale, dt, max_freq, max_acc)
        else:
            wanted = min(max(self.velocity_cmd * scale, -max_freq), max_freq)
            current = self.frequency
            rate = min(max(wanted, current - max_acc * dt), current + max_acc * dt)
        self.frequency = rate
        self.target_addval = int(rate * ONE_STEP * base_s)
        self.deltalim = int(max_acc * ONE_STEP * base_s * base_s)

    def _position_rate(self, scale: float, dt: float, max_freq: float, max_acc: float) -> float:
        """Step rate that matches the command's velocity, then removes the position error."""
        pos_cmd = self.position_cmd * scale
        vel_cmd = (pos_cmd - self.old_pos_cmd) / dt
        self.old_pos_cmd = pos_cmd
        curr_pos = (self.accum - HALF_STEP) / ONE_STEP
        curr_vel = self.frequency
        match_acc = max_acc if vel_cmd > curr_vel else -max_acc
        match_time = (vel_cmd - curr_vel) / match_acc
        # where output and command will be once the velocities match
        est_out = curr_pos + (vel_cmd + curr_vel) * 0.5 * match_time
        est_cmd = pos_cmd + vel_cmd * (match_time - 1.5 * dt)
        est_err = est_out - est_cmd
        if match_time < dt:  # the velocity can be matched within this period
            if abs(est_err) < 0.0001:
                rate = vel_cmd
            else:
                rate = vel_cmd - 0.5 * est_err / dt
                rate = min(max(rate, curr_vel - max_acc * dt), curr_vel + max_acc * dt)
        else:
            # ramp the other way for a period if that brings the final error down
            shift = -2.0 * match_acc * dt * match_time
            if abs(est_err + shift * 2.0) < abs(est_err):
                match_acc = -match_acc
            rate = curr_vel + match_acc * dt
        return min(max(rate, -max_freq), max_freq)

    def capture(self) -> None:
        scale = self.position_scale
        if -1e-20 < scale < 1e-20:
            self.position_scale = scale = 1.0
        self.counts = self.accum >> FRACTION_BITS
        self.position_fb = (self.accum - HALF_STEP) / ONE_STEP / scale


class _PositionStepgen(_Stepgen):
    position_cmd = pin("float in")


class _VelocityStepgen(_Stepgen):
    velocity_cmd = pin("float in")
    is_position_mode = False


class Stepgen(RtComponent):
    """Dispatches each channel to the position or velocity flavour."""

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        unknown = set(args) - {"step_type", "ctrl_type", "user_step_type"}
        if unknown:
            raise HalError(f"stepgen: unknown argument '{sorted(unknown)[0]}'")
        types = [t for t in args.get("step_type", "").split(",") if t]
        if not types:
            raise HalError("stepgen: no channels configured (step_type=...)")
        if any(t != "0" for t in types):
            raise HalError("stepgen: only step_type=0 (step/dir) is supported")
        modes = [m for m in args.get("ctrl_type", "").split(",") if m]
        modes += ["p"] * (len(types) - len(modes))
        if any(m not in ("p", "v") for m in modes):
            raise HalError("stepgen: ctrl_type must be p or v")
        return [(f"stepgen.{i}", {"mode": modes[i]}) for i in range(len(types))]

    @classmethod
    def create(cls, hal: Any, comp: str, name: str, options: dict[str, Any] | None = None) -> Any:
        flavour = _VelocityStepgen if (options or {}).get("mode") == "v" else _PositionStepgen
        return flavour.create(hal, comp, name, {})

    @module_funct("make-pulses", has_fp=False)
    @classmethod
    def make_pulses(cls, instances: list[_Stepgen], period: int) -> None:
        for inst in instances:
            inst.pulses(period)

    @module_funct("update-freq")
    @classmethod
    def update_freq(cls, instances: list[_Stepgen], period: int) -> None:
        for inst in instances:
            inst.update(period)

    @module_funct("capture-position")
    @classmethod
    def capture_position(cls, instances: list[_Stepgen], period: int) -> None:
        for inst in instances:
            inst.capture()


COMPONENT = Stepgen
