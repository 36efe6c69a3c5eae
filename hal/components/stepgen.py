"""stepgen: software step pulse generation, position or velocity mode.

``loadrt stepgen step_type=T[,T...] [ctrl_type=p|v[,...]] [user_step_type=#,#...]``, up to
16 channels. The step type picks the outputs (``man 9 stepgen``):

- 0: ``step`` and ``dir`` (parameters ``stepspace``, ``dirsetup``, ``dirhold``);
- 1: ``up`` and ``down`` pulses (``stepspace``, ``dirdelay``);
- 2-14: ``phase-A`` ... ``phase-E`` stepping through a fixed pattern, one state per step,
  backwards when reversing (``dirdelay``): 2 quadrature, 3/4 three phase full/half step,
  5-8 four phase full step, 9/10 four phase half step, 11/12 five phase full step, 13/14
  five phase half step;
- 15: the pattern given by ``user_step_type`` (up to 10 states of up to 5 phases, phase A
  in bit 0).

Types 2 and up may step every period (no ``stepspace``). Functions:

- ``stepgen.make-pulses`` (no floating point; the base thread when one exists) runs a
  direct digital synthesis accumulator: a fixed-point position in steps with 28 fraction
  bits, starting half a step in, so steps happen half-way between whole positions. Each
  call adds the current rate (ramped towards the target by the acceleration limit) and
  makes a step when the whole part changes. ``step`` stays high ``steplen`` ns, ``dir``
  may change ``dirhold`` ns after a step, and a reversal waits ``dirsetup`` ns more (types
  1 and up: a reversal waits ``dirdelay`` ns after the end of the last step).
- ``stepgen.update-freq`` (servo thread) turns ``velocity-cmd`` (v mode) or
  ``position-cmd`` (p mode: match the command's velocity, then close the position error)
  into the step rate ``frequency``, limited by ``maxvel``/``maxaccel`` (0: only the limit
  that steplen + stepspace allow) in units scaled by ``position-scale`` steps per unit.
  Timing parameters are rounded up to whole base-thread periods, and written back.
- ``stepgen.capture-position`` publishes ``counts`` and ``position-fb`` (with the fraction
  of a step).
"""

from __future__ import annotations

import functools
import sys
from typing import Any, ClassVar

from hal.api import RtComponent, module_funct, param, pin
from hal.core import HalError

FRACTION_BITS = 28
ONE_STEP = 1 << FRACTION_BITS
HALF_STEP = 1 << (FRACTION_BITS - 1)
DEFAULT_BASE_NS = 50_000  # until make-pulses has run and told us its period
DEFAULT_SERVO_NS = 1_000_000
MAX_CHANNELS = 16
PHASE_NAMES = "ABCDE"
USER_STEP_TYPE = 15
MAX_USER_STATES = 10

# The output patterns of step types 2-14 (man 9 stepgen, HAL manual): the phases that are
# high in each state, in forward order; a reverse step goes back one state.
PATTERNS: dict[int, tuple[str, ...]] = {
    2: ("A", "AB", "B", ""),  # quadrature: A leads B going forward
    3: ("A", "B", "C"),  # three phase, full step
    4: ("A", "AB", "B", "BC", "C", "AC"),  # three phase, half step
    5: ("A", "B", "C", "D"),  # unipolar full step, one winding on
    6: ("AB", "BC", "CD", "AD"),  # unipolar full step, two windings on
    7: ("A", "ABC", "BCD", "D"),  # bipolar full step, one winding on
    8: ("AC", "BC", "BD", "AD"),  # bipolar full step, two windings on
    9: ("A", "AB", "B", "BC", "C", "CD", "D", "AD"),  # unipolar half step
    10: ("A", "AC", "ABC", "BC", "BCD", "BD", "D", "AD"),  # bipolar half step
    11: ("A", "B", "C", "D", "E"),  # five phase, full step
    12: ("AB", "BC", "CD", "DE", "AE"),  # five phase wave, full step
    13: ("A", "AB", "B", "BC", "C", "CD", "D", "DE", "E", "AE"),  # five phase, half step
    14: ("AB", "ABC", "BC", "BCD", "CD", "CDE", "DE", "ADE", "AE", "ABE"),  # wave, half step
}
PHASE_COUNTS = {2: 2, 3: 3, 4: 3, 11: 5, 12: 5, 13: 5, 14: 5}  # the others have 4


def pattern_bits(states: tuple[str, ...]) -> tuple[int, ...]:
    """Each state as a number with phase A in bit 0."""
    return tuple(sum(1 << PHASE_NAMES.index(phase) for phase in state) for state in states)


def _round_up(value: int, increment: int) -> int:
    """The smallest multiple of ``increment`` that is >= ``value``."""
    return 0 if value == 0 else increment * ((value - 1) // increment + 1)


class _Stepgen(RtComponent):
    """What every channel has; the step type's outputs and timing parameters come from a
    flavour below (``_StepDir``, ``_UpDown``, ``_Phases``)."""

    counts = pin("s32 out")
    enable = pin("bit in")
    position_fb = pin("float out")
    frequency = param("float ro")
    maxaccel = param("float rw")
    maxvel = param("float rw")
    position_scale = param("float rw", default=1.0)
    rawcounts = param("s32 ro")
    steplen = param("u32 rw", default=1)

    is_position_mode = True
    #: the timing parameters of the flavour: minimum space between steps (None: the outputs
    #: may change every period), direction hold after a step, direction setup before a step
    SPACE_PARAM: ClassVar[str | None] = None
    HOLD_PARAM: ClassVar[str] = "dirdelay"
    SETUP_PARAM: ClassVar[str | None] = None
    #: whether hold + setup must be at least one period (step/dir and up/down)
    is_hold_required: ClassVar[bool] = True

    def setup(self, pattern: tuple[int, ...] = ()) -> None:
        self.accum = HALF_STEP
        self.addval = 0  # accumulator increment per make-pulses call
        self.target_addval = 0
        self.deltalim = 0  # largest change of addval per call (acceleration limit)
        self.step_timer = self.dir_timer = self.reverse_timer = 0  # ns left
        self.is_holding = False  # a reversal waits for the direction setup time
        self.curr_dir = 0
        self.pattern = pattern  # output states of step types 2 and up
        self.state = 0
        self.old_pos_cmd = 0.0
        self.base_ns = DEFAULT_BASE_NS
        self.checked_base_ns = DEFAULT_BASE_NS
        self.timing: tuple[int, int, int, int] | None = None  # validated steplen...setup
        self.has_warned = False

    # ------------------------------------------------------------ flavour
    def _timing_values(self) -> tuple[int, int, int, int]:
        """(steplen, step space, direction hold, direction setup) in ns."""
        space = getattr(self, self.SPACE_PARAM) if self.SPACE_PARAM else 0
        setup = getattr(self, self.SETUP_PARAM) if self.SETUP_PARAM else 0
        return self.steplen, space, getattr(self, self.HOLD_PARAM), setup

    def write_outputs(self) -> None:
        raise NotImplementedError

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
            steplen, _, hold, setup = self._timing_values()
            self.step_timer = steplen
            self.dir_timer = self.step_timer + hold
            self.reverse_timer = self.dir_timer + setup
            if self.pattern:
                self.state = (self.state + self.curr_dir) % len(self.pattern)
        self.write_outputs()

    # ------------------------------------------------------------ servo thread
    def _check_timing(self) -> None:
        """Round the timing parameters up to whole base periods (and keep them non-zero)."""
        base = self.base_ns
        current = self._timing_values()
        if current == self.timing and base == self.checked_base_ns:
            return
        steplen, space, hold, setup = current
        if hold + setup == 0 and self.is_hold_required:
            hold = 1
        self.timing = (
            _round_up(max(steplen, 1), base),
            _round_up(space, base),
            _round_up(hold, base),
            _round_up(setup, base),
        )
        self.steplen, rounded_space, rounded_hold, rounded_setup = self.timing
        setattr(self, self.HOLD_PARAM, rounded_hold)
        if self.SPACE_PARAM:
            setattr(self, self.SPACE_PARAM, rounded_space)
        if self.SETUP_PARAM:
            setattr(self, self.SETUP_PARAM, rounded_setup)
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
        steplen, space, _, _ = self._timing_values()
        max_freq = 1.0 / ((steplen + space) * 1e-9)
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


class _StepDir(_Stepgen):
    """Step type 0: a ``step`` pulse per step, ``dir`` high for reverse."""

    step = pin("bit out")
    dir = pin("bit out")
    stepspace = param("u32 rw", default=1)
    dirsetup = param("u32 rw", default=1)
    dirhold = param("u32 rw", default=1)
    SPACE_PARAM, HOLD_PARAM, SETUP_PARAM = "stepspace", "dirhold", "dirsetup"

    def write_outputs(self) -> None:
        self.step = self.step_timer != 0
        self.dir = self.curr_dir < 0


class _UpDown(_Stepgen):
    """Step type 1: forward steps pulse ``up``, reverse steps pulse ``down``."""

    up = pin("bit out")
    down = pin("bit out")
    stepspace = param("u32 rw", default=1)
    dirdelay = param("u32 rw", default=1)
    SPACE_PARAM = "stepspace"

    def write_outputs(self) -> None:
        is_pulse = self.step_timer != 0
        self.up = is_pulse and self.curr_dir >= 0
        self.down = is_pulse and self.curr_dir < 0


class _Phases(_Stepgen):
    """Step types 2 and up: ``phase-A`` ... show the current state of the pattern."""

    dirdelay = param("u32 rw", default=1)
    is_hold_required = False
    PHASE_ATTRS: ClassVar[tuple[str, ...]] = ()

    def write_outputs(self) -> None:
        bits = self.pattern[self.state]
        for attr in self.PHASE_ATTRS:
            setattr(self, attr, bits & 1)
            bits >>= 1


@functools.cache
def _channel_class(is_position_mode: bool, step_type: int, phases: int) -> type[_Stepgen]:
    """The class of one channel: its command pin, then its step type's outputs."""
    if step_type == 0:
        flavour: type[_Stepgen] = _StepDir
    elif step_type == 1:
        flavour = _UpDown
    else:
        flavour = _Phases
    attrs: dict[str, Any] = {"is_position_mode": is_position_mode}
    if is_position_mode:
        attrs["position_cmd"] = pin("float in")
    else:
        attrs["velocity_cmd"] = pin("float in")
    if flavour is _Phases:
        names = PHASE_NAMES[:phases]
        attrs["PHASE_ATTRS"] = tuple(f"phase_{letter.lower()}" for letter in names)
        for letter in names:
            attrs[f"phase_{letter.lower()}"] = pin("bit out", f"phase-{letter}")
    return type(f"Stepgen{step_type}{'p' if is_position_mode else 'v'}", (flavour,), attrs)


def _user_pattern(text: str) -> tuple[int, ...]:
    """``user_step_type=#,#...``: up to 10 states, each a number of up to 5 phase bits."""
    try:
        states = tuple(int(word, 0) for word in text.split(",") if word)
    except ValueError:
        raise HalError(f"stepgen: bad user_step_type '{text}' (want numbers)") from None
    if len(states) > MAX_USER_STATES:
        raise HalError(f"stepgen: user_step_type has more than {MAX_USER_STATES} states")
    if any(not 0 <= state < 1 << len(PHASE_NAMES) for state in states):
        raise HalError("stepgen: bad user step type uses more than 5 phases")
    return states


class Stepgen(RtComponent):
    """Dispatches each channel to the class of its control and step type."""

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        unknown = set(args) - {"step_type", "ctrl_type", "user_step_type"}
        if unknown:
            raise HalError(f"stepgen: unknown argument '{sorted(unknown)[0]}'")
        words = [t for t in args.get("step_type", "").split(",") if t]
        if not words:
            raise HalError("stepgen: no channels configured (step_type=...)")
        if len(words) > MAX_CHANNELS:
            raise HalError(f"stepgen: at most {MAX_CHANNELS} channels")
        user_pattern = _user_pattern(args.get("user_step_type", ""))
        modes = [m for m in args.get("ctrl_type", "").split(",") if m]
        modes += ["p"] * (len(words) - len(modes))
        wanted = []
        for index, (word, mode) in enumerate(zip(words, modes, strict=False)):
            if not word.isdigit() or int(word) > USER_STEP_TYPE:
                raise HalError(f"stepgen: bad stepping type '{word}', axis {index}")
            if mode not in ("p", "v"):
                raise HalError(
                    f"stepgen: bad control type '{mode}' for axis {index} (must be 'p' or 'v')"
                )
            step_type = int(word)
            if step_type == USER_STEP_TYPE:
                if not user_pattern:
                    raise HalError(f"stepgen: axis {index}: step_type 15 needs user_step_type=")
                pattern = user_pattern
            elif step_type >= 2:
                pattern = pattern_bits(PATTERNS[step_type])
            else:
                pattern = ()
            options = {"is_position_mode": mode == "p", "step_type": step_type}
            wanted.append((f"stepgen.{index}", {**options, "pattern": pattern}))
        return wanted

    @classmethod
    def create(cls, hal: Any, comp: str, name: str, options: dict[str, Any] | None = None) -> Any:
        options = options or {}
        pattern = options.get("pattern", ())
        if options.get("step_type") == USER_STEP_TYPE:
            phases = max(pattern).bit_length()
        else:
            phases = PHASE_COUNTS.get(options.get("step_type", 0), 4)
        channel = _channel_class(
            options.get("is_position_mode", True), options.get("step_type", 0), phases
        )
        return channel.create(hal, comp, name, {"pattern": pattern})

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
