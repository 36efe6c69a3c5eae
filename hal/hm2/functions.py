"""The HostMot2 functions as the driver runs them: HAL pins, registers, per-period work.

Each class drives one function of the firmware (its module descriptor) with LinuxCNC's
pin and parameter names under ``hm2_<board>.<n>.``. A function asks the board for
register regions to read every period (``board.add_read``) and to write every period
(``board.add_write``); ``process_read`` turns the read values into pins, ``prepare_write``
turns pins into the values to write. Settings that change seldom (step timing, PWM
frequency, GPIO direction) are written only when they change (``write_changes`` queues
those writes into the same packet) and all at once by ``force_write`` at start-up and
after the watchdog bit.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from hal.api import RtComponent, make_accessor, param, pin
from hal.core import HAL_BIT, HAL_FLOAT, HAL_IN, HAL_OUT, HAL_RW, HAL_S32
from hal.hm2.idrom import (
    GTAG_ENCODER,
    GTAG_INM,
    GTAG_OUTM,
    GTAG_PWMGEN,
    GTAG_SSR,
    GTAG_STEPGEN,
    Module,
)

if TYPE_CHECKING:
    from hal.hm2.driver import Board

MASK32 = 0xFFFFFFFF
NS_PER_S = 1e9


def _to_s32(value: int) -> int:
    return value - (1 << 32) if value & 0x80000000 else value


class Function:
    """Base of the per-function drivers; see the module docstring."""

    gtag = 0
    hal_name = ""  # "stepgen": pins are <board>.stepgen.NN.*

    def __init__(self, board: Board, module: Module, count: int) -> None:
        self.board = board
        self.module = module
        self.count = count
        self.prefix = f"{board.name}.{self.hal_name}"

    def address(self, register: int, instance: int = 0) -> int:
        return self.module.address(register, instance)

    def say(self, text: str) -> None:
        self.board.say(text)

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        """Turn this period's read registers into pins."""

    def prepare_write(self, out: list[int], period: int) -> None:
        """Fill this function's slots of the per-period write values."""

    def write_changes(self, period: int) -> None:
        """Queue writes of settings whose parameters changed since last written."""

    def settings_checks(self) -> list:
        """The checks for changed settings, each cheap: the board runs one per period in
        turn (a parameter change takes effect within a few periods, and no period pays
        for checking them all)."""
        return [self.write_changes]

    def force_write(self) -> None:
        """Queue every setting (start-up, recovery after a watchdog bite)."""


# ---------------------------------------------------------------- IOPort and GPIO
class GpioInputPins(RtComponent):
    in_ = pin("bit out", "in")
    in_not = pin("bit out", "in_not")


class GpioFullPins(RtComponent):
    out = pin("bit in")
    is_output = param("bit rw", "is_output")


class GpioOutputParams(RtComponent):
    invert_output = param("bit rw", "invert_output")
    is_opendrain = param("bit rw", "is_opendrain")


class IOPort(Function):
    """Every I/O pin: ``gpio.NNN.in``/``in_not``; pins no function owns are full GPIO
    (``out``, ``is_output``); outputs have ``invert_output`` and ``is_opendrain``."""

    hal_name = "gpio"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.ports = module.descriptor.instances
        self.width = board.idrom.port_width
        self.read_at = board.add_read(self.address(0), self.ports)
        self.write_at = board.add_write(self.address(0), self.ports)
        self.inputs: list[Any] = []
        self.full: dict[int, Any] = {}  # io -> its out/is_output pins
        self.outputs: dict[int, Any] = {}  # io -> invert/open-drain params
        self.last_ports: list[int | None] = [None] * self.ports
        self.written: tuple | None = None

    def make_pins(self) -> None:
        """After every function took its pins: the HAL objects of each I/O pin."""
        board = self.board
        for io, owner in enumerate(board.pin_owner):
            prefix = f"{self.prefix}.{io:03d}"
            self.inputs.append(GpioInputPins.create(board.hal, board.comp, prefix))
            if owner is None:
                self.full[io] = GpioFullPins.create(board.hal, board.comp, prefix)
            if owner is None or board.pin_is_output[io]:
                self.outputs[io] = GpioOutputParams.create(board.hal, board.comp, prefix)

    def _registers(self) -> tuple[tuple[int, ...], ...]:
        """(direction, alternate source, open drain, inversion) per port, from the pins."""
        board = self.board
        ddr, alt, od, inv = ([0] * self.ports for _ in range(4))
        for io, owner in enumerate(board.pin_owner):
            port, bit = divmod(io, self.width)
            mask = 1 << bit
            if owner is None:
                if self.full[io].is_output:
                    ddr[port] |= mask
            else:
                alt[port] |= mask
                if board.pin_is_output[io]:
                    ddr[port] |= mask
            params = self.outputs.get(io)
            if params is not None:
                if params.is_opendrain:
                    od[port] |= mask
                if params.invert_output:
                    inv[port] |= mask
        return tuple(ddr), tuple(alt), tuple(od), tuple(inv)

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        at, width, last = self.read_at, self.width, self.last_ports
        for port in range(self.ports):
            word = values[at + port]
            if word == last[port]:
                continue
            last[port] = word
            base = port * width
            for bit in range(width):
                io = base + bit
                if io >= len(self.inputs):
                    break
                level = bool(word >> bit & 1)
                pins = self.inputs[io]
                pins.in_ = level
                pins.in_not = not level

    def prepare_write(self, out: list[int], period: int) -> None:
        words = [0] * self.ports
        width = self.width
        for io, pins in self.full.items():
            if pins.out:
                words[io // width] |= 1 << io % width
        out[self.write_at : self.write_at + self.ports] = words

    def write_changes(self, period: int) -> None:
        registers = self._registers()
        if registers != self.written:
            self._queue(registers)

    def settings_checks(self) -> list:
        return [lambda period, p=port: self._check_port(p) for port in range(self.ports)]

    def _check_port(self, port: int) -> None:
        """Whether one port's direction, open-drain or inversion parameters changed."""
        width, board = self.width, self.board
        ddr = od = inv = 0
        for io in range(port * width, min((port + 1) * width, len(board.pin_owner))):
            mask = 1 << (io - port * width)
            full = self.full.get(io)
            if full is not None and full.is_output:
                ddr |= mask
            params = self.outputs.get(io)
            if params is not None:
                if params.is_opendrain:
                    od |= mask
                if params.invert_output:
                    inv |= mask
        written = self.written
        if written is None:
            return
        module_ddr = self.module_ddr[port]
        if (ddr | module_ddr, od, inv) != (written[0][port], written[2][port], written[3][port]):
            self.write_changes(0)

    def force_write(self) -> None:
        self._queue(self._registers())

    def _queue(self, registers: tuple[tuple[int, ...], ...]) -> None:
        ddr, alt, od, inv = registers
        self.module_ddr = [
            sum(
                1 << bit
                for bit in range(self.width)
                if port * self.width + bit < len(self.board.pin_owner)
                and self.board.pin_owner[port * self.width + bit] is not None
                and self.board.pin_is_output[port * self.width + bit]
            )
            for port in range(self.ports)
        ]
        for register, words in ((1, ddr), (2, alt), (3, od), (4, inv)):
            self.board.queue_write(self.address(register), list(words))
        self.written = registers


# ---------------------------------------------------------------- watchdog
class WatchdogPins(RtComponent):
    has_bit = pin("bit io", "has_bit")
    timeout_ns = param("u32 rw", "timeout_ns", default=5_000_000)


class Watchdog(Function):
    """``watchdog.has_bit`` (set when it bit; clear it to resume) and ``timeout_ns``.

    The board's watchdog starts disabled; the first ``write`` arms it, and from then on
    every ``write`` pets it. If the writes stop for ``timeout_ns``, the board turns every
    pin into an input (outputs off) and says so in its status register."""

    hal_name = "watchdog"
    PET = 0x5A000000
    DISABLED = 0x80000000

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.pins = WatchdogPins.create(board.hal, board.comp, self.prefix)
        self.status_at = board.add_read(self.address(1), 1)
        self.reset_at = board.add_write(self.address(2), 1)
        self.is_enabled = False
        self.written: tuple[int, bool] | None = None
        self.has_warned_short = False

    def timer_value(self) -> int:
        if not self.is_enabled:
            return self.DISABLED
        counts = int(self.pins.timeout_ns * self.module.clock_hz / NS_PER_S) - 1
        if counts >= self.DISABLED:
            counts = self.DISABLED - 1
            self.pins.timeout_ns = int((counts + 1) * NS_PER_S / self.module.clock_hz)
            self.say(
                f"requested watchdog timeout is out of range, set to {self.pins.timeout_ns} ns"
            )
        return max(counts, 0)

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        board = self.board
        if board.needs_reset:
            return
        if values[self.status_at] & 1:
            self.pins.has_bit = True
            board.needs_reset = True
            board.report_fault("Watchdog has bit! (set the .has_bit pin to False to resume)")

    def prepare_write(self, out: list[int], period: int) -> None:
        out[self.reset_at] = self.PET

    def write_changes(self, period: int) -> None:
        """Arm the watchdog, follow ``timeout_ns``, and after a bite that the user
        acknowledged (``has_bit`` cleared) rewrite every setting."""
        board = self.board
        if self.pins.has_bit:
            return  # bitten: wait for the user
        self.is_enabled = True
        if board.needs_reset or board.needs_soft_reset:
            if board.needs_reset:
                board.say("trying to recover from IO error or Watchdog bite")
            board.force_write()
            if board.needs_reset:
                board.say("error recovery successful!")
            board.needs_reset = board.needs_soft_reset = False
            return
        timeout = self.pins.timeout_ns
        if (timeout, self.is_enabled) != self.written:
            if timeout < 1.5 * period and not self.has_warned_short:
                self.has_warned_short = True
                board.say(
                    f"Watchdog timeout ({timeout} ns) is dangerously short compared to "
                    f"hm2_write() period ({period} ns)"
                )
            self.force_write()

    def force_write(self) -> None:
        self.board.queue_write(self.address(0), [self.timer_value()])
        self.board.queue_write(self.address(1), [0])  # clear the has-bit status
        self.written = (self.pins.timeout_ns, self.is_enabled)


# ---------------------------------------------------------------- stepgen
STEP_TIMING_MAX = 0x3FFF  # clocks


class StepgenPins(RtComponent):
    control_type = pin("bit in", "control-type")
    counts = pin("s32 out")
    dbg_err_at_match = pin("float out", "dbg_err_at_match")
    dbg_ff_vel = pin("float out", "dbg_ff_vel")
    dbg_pos_minus_prev_cmd = pin("float out", "dbg_pos_minus_prev_cmd")
    dbg_s_to_match = pin("float out", "dbg_s_to_match")
    dbg_step_rate = pin("s32 out", "dbg_step_rate")
    dbg_vel_error = pin("float out", "dbg_vel_error")
    enable = pin("bit in")
    position_cmd = pin("float in")
    position_fb = pin("float out")
    position_reset = pin("bit in")
    velocity_cmd = pin("float in")
    velocity_fb = pin("float out")
    dirhold = param("u32 rw")
    dirsetup = param("u32 rw")
    maxaccel = param("float rw", default=1.0)
    maxvel = param("float rw")
    position_scale = param("float rw", default=1.0)
    step_type = param("u32 rw", "step_type")
    steplen = param("u32 rw")
    stepspace = param("u32 rw")
    table_data = param("u32 rw", "table-data-{}", count=4)


class StepgenModulePins(RtComponent):
    timer_number = pin("s32 in", "timer-number", default=-1)


class _StepgenState:
    __slots__ = ("old_position_cmd", "prev_accumulator", "subcounts", "written")

    def __init__(self) -> None:
        self.old_position_cmd = 0.0
        self.prev_accumulator = 0
        self.subcounts = 0  # position in 1/65536 steps
        self.written: tuple | None = None


class StepGen(Function):
    """Hardware step generators (``stepgen.NN``): position mode (``control-type`` 0, a
    velocity command that reaches the commanded position within the acceleration limit)
    or velocity mode (1); ``position-fb`` from the board's step accumulator."""

    gtag = GTAG_STEPGEN
    hal_name = "stepgen"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.clock = module.clock_hz
        max_ns = int(STEP_TIMING_MAX * NS_PER_S / self.clock)
        self.instances = []
        self.states = []
        for i in range(count):
            pins = StepgenPins.create(board.hal, board.comp, f"{self.prefix}.{i:02d}")
            pins.steplen = pins.stepspace = pins.dirsetup = pins.dirhold = max_ns
            self.instances.append(pins)
            self.states.append(_StepgenState())
        self.module_pins = (
            StepgenModulePins.create(board.hal, board.comp, self.prefix)
            if board.has_dpll and count
            else None
        )
        self.written_timer = None
        self.accumulator_at = board.add_read(self.address(1), count)
        self.rate_at = board.add_write(self.address(0), count)
        self.rate_scale = 4294967296.0 / self.clock

    def _clocks(self, pins: Any, name: str, index: int) -> int:
        """A timing parameter in clocks, clipped to what the board can do."""
        value = getattr(pins, name)
        clocks = int(value * self.clock / NS_PER_S)
        if clocks > STEP_TIMING_MAX:
            self.say(f"stepgen {index} has invalid {name}, resetting to max")
            clocks = STEP_TIMING_MAX
            setattr(pins, name, int(clocks * NS_PER_S / self.clock))
        return clocks

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        at = self.accumulator_at
        for i, pins in enumerate(self.instances):
            state = self.states[i]
            scale = pins.position_scale
            if abs(scale) < 1e-6:
                scale = 1.0 if scale >= 0 else -1.0
                pins.position_scale = scale
                self.say(f"stepgen {i} position_scale is too close to 0, resetting to {scale}")
            acc = values[at + i]
            delta = (acc - state.prev_accumulator) & MASK32
            if delta >= 0x80000000:
                delta -= 1 << 32
            state.prev_accumulator = acc
            state.subcounts += delta
            if pins.position_reset:
                state.subcounts = 0
            pins.counts = state.subcounts >> 16
            pins.position_fb = state.subcounts / 65536.0 / scale

    def _position_control(self, pins: Any, state: _StepgenState, period_s: float) -> float:
        """The velocity that brings the motor to the command: match the command's
        velocity at the acceleration limit, then close the remaining position error."""
        position_cmd = pins.position_cmd
        velocity_fb = pins.velocity_fb
        maxaccel = pins.maxaccel
        pins.dbg_pos_minus_prev_cmd = pins.position_fb - state.old_position_cmd
        ff_vel = (position_cmd - state.old_position_cmd) / period_s
        pins.dbg_ff_vel = ff_vel
        state.old_position_cmd = position_cmd
        velocity_error = velocity_fb - ff_vel
        pins.dbg_vel_error = velocity_error
        if velocity_error > 0:
            match_accel = -maxaccel if maxaccel else -velocity_error / period_s
        elif velocity_error < 0:
            match_accel = maxaccel if maxaccel else velocity_error / period_s
        else:
            match_accel = 0.0
        seconds_to_match = 0.0 if match_accel == 0 else -velocity_error / match_accel
        pins.dbg_s_to_match = seconds_to_match
        average_v = (ff_vel + velocity_fb) * 0.5
        position_at_match = pins.position_fb + average_v * (seconds_to_match + period_s)
        cmd_at_match = position_cmd + ff_vel * seconds_to_match
        error_at_match = position_at_match - cmd_at_match
        pins.dbg_err_at_match = error_at_match
        if seconds_to_match < period_s:
            velocity = ff_vel - 0.5 * error_at_match / period_s
            if maxaccel > 0:
                step = maxaccel * period_s
                velocity = min(max(velocity, velocity_fb - step), velocity_fb + step)
            return velocity
        # still accelerating: keep ramping, the way that ends closer to the command
        dp = -2.0 * match_accel * period_s * seconds_to_match
        if abs(error_at_match + 2.0 * dp) < abs(error_at_match):
            match_accel = -match_accel
        return velocity_fb + match_accel * period_s

    def prepare_write(self, out: list[int], period: int) -> None:
        period_s = period / NS_PER_S
        at = self.rate_at
        for i, pins in enumerate(self.instances):
            state = self.states[i]
            if not pins.enable:
                out[at + i] = 0
                state.old_position_cmd = pins.position_cmd
                pins.velocity_fb = 0.0
                continue
            scale = pins.position_scale
            min_ns_per_step = pins.steplen + pins.stepspace
            physical_maxvel = (
                NS_PER_S / min_ns_per_step / abs(scale) if min_ns_per_step else math.inf
            )
            maxvel = pins.maxvel
            if maxvel < 0:
                maxvel = pins.maxvel = -maxvel
            if maxvel > physical_maxvel:
                self.say(
                    f"stepgen.{i:02d}.maxvel is too big for current step timings & "
                    "position-scale, clipping to max possible"
                )
                maxvel = pins.maxvel = physical_maxvel
            limit = maxvel or physical_maxvel
            if pins.maxaccel < 0:
                pins.maxaccel = -pins.maxaccel
            if pins.control_type:
                velocity = pins.velocity_cmd
                maxaccel = pins.maxaccel
                if maxaccel > 0:
                    step = maxaccel * period_s
                    velocity_fb = pins.velocity_fb
                    velocity = min(max(velocity, velocity_fb - step), velocity_fb + step)
            else:
                velocity = self._position_control(pins, state, period_s)
            velocity = min(max(velocity, -limit), limit)
            pins.velocity_fb = velocity
            rate = int(velocity * scale * self.rate_scale) & MASK32
            out[at + i] = rate
            pins.dbg_step_rate = _to_s32(rate)

    def _settings(self, index: int) -> tuple[int, ...]:
        pins = self.instances[index]
        step_type = pins.step_type
        mode = step_type if step_type <= 2 else 3
        tables = tuple(pins.table_data[n] for n in range(4))
        return (
            self._clocks(pins, "dirsetup", index),
            self._clocks(pins, "dirhold", index),
            self._clocks(pins, "steplen", index),
            self._clocks(pins, "stepspace", index),
            mode,
            step_type,
            *tables,
        )

    def _queue(self, index: int, settings: tuple[int, ...]) -> None:
        board = self.board
        setup, hold, length, space, mode, step_type, *tables = settings
        for register, value in ((3, setup), (4, hold), (5, length), (6, space)):
            board.queue_write(self.address(register, index), [value])
        if mode == 3:  # table mode: the pattern, last state first, then its length
            for state in range(step_type - 1, -1, -1):
                byte = tables[state // 4] >> (state % 4 * 8) & 0xFF
                board.queue_write(self.address(7, index), [byte])
            board.queue_write(self.address(8, index), [step_type - 1])
        board.queue_write(self.address(2, index), [mode])
        self.states[index].written = settings

    def write_changes(self, period: int) -> None:
        for i in range(self.count):
            self._check(i)
        self._write_timer(is_forced=False)

    def _check(self, index: int) -> None:
        settings = self._settings(index)
        if settings != self.states[index].written:
            self._queue(index, settings)

    def settings_checks(self) -> list:
        checks = [lambda period, i=i: self._check(i) for i in range(self.count)]
        return [*checks, lambda period: self._write_timer(is_forced=False)]

    def force_write(self) -> None:
        for i in range(self.count):
            self._queue(i, self._settings(i))
        self.board.queue_write(self.address(9), [0xFFFFFFFF])  # full-rate master DDS
        self._write_timer(is_forced=True)

    def _write_timer(self, *, is_forced: bool) -> None:
        if self.module_pins is None:
            return
        timer = self.module_pins.timer_number
        if timer == self.written_timer and not is_forced:
            return
        if not -1 <= timer <= 4:
            timer = self.module_pins.timer_number = 0
        data = (timer << 12 | 1 << 15) if timer > -1 else 0
        self.board.queue_write(self.address(10), [data])
        self.written_timer = timer


# ---------------------------------------------------------------- encoder
class EncoderPins(RtComponent):
    count = pin("s32 out")
    count_latched = pin("s32 out", "count-latched")
    index_enable = pin("bit io", "index-enable")
    input_a = pin("bit out", "input-a")
    input_b = pin("bit out", "input-b")
    input_index = pin("bit out", "input-index")
    position = pin("float out")
    position_latched = pin("float out", "position-latched")
    quad_error = pin("bit out", "quad-error")
    quad_error_enable = pin("bit in", "quad-error-enable")
    rawcounts = pin("s32 out")
    rawlatch = pin("s32 out")
    reset = pin("bit in")
    velocity = pin("float out")
    velocity_rpm = pin("float out", "velocity-rpm")
    counter_mode = param("bit rw", "counter-mode")
    filter = param("bit rw", default=True)
    index_invert = param("bit rw", "index-invert")
    index_mask = param("bit rw", "index-mask")
    index_mask_invert = param("bit rw", "index-mask-invert")
    scale = param("float rw", default=1.0)
    vel_timeout = param("float rw", "vel-timeout", default=0.5)


class EncoderModulePins(RtComponent):
    hires_timestamp = pin("bit in", "hires-timestamp")
    sample_frequency = pin("u32 in", "sample-frequency", default=25_000_000)


class EncoderTimerPin(RtComponent):
    timer_number = pin("s32 in", "timer-number", default=-1)


_ENC_INPUTS = 0x7
_ENC_LATCH_ON_INDEX = 1 << 4
_ENC_CLEAR_ON_INDEX = 1 << 5
_ENC_JUST_ONCE = 1 << 6
_ENC_INDEX_POLARITY = 1 << 3
_ENC_INDEX_MASK_POLARITY = 1 << 8
_ENC_INDEX_MASK = 1 << 9
_ENC_COUNTER_MODE = 1 << 10
_ENC_FILTER = 1 << 11
_ENC_QUAD_ERROR = 1 << 15


class _EncoderState:
    __slots__ = ("index_armed", "prev_count", "rawcounts", "still_s", "written", "zero")

    def __init__(self) -> None:
        self.prev_count: int | None = None
        self.rawcounts = 0
        self.zero = 0  # rawcounts where count is 0 (reset, index)
        self.still_s = 0.0  # time since the last count
        self.index_armed = False
        self.written: int | None = None


class Encoder(Function):
    """Quadrature counters (``encoder.NN``): 16-bit hardware counts extended to 32, reset
    and index (``index-enable``) handling, velocity from the count change per period
    (falling to 0 after ``vel-timeout`` without counts)."""

    gtag = GTAG_ENCODER
    hal_name = "encoder"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.instances = [
            EncoderPins.create(board.hal, board.comp, f"{self.prefix}.{i:02d}")
            for i in range(count)
        ]
        self.states = [_EncoderState() for _ in range(count)]
        self.module_pins = EncoderModulePins.create(board.hal, board.comp, self.prefix)
        self.timer_pin = (
            EncoderTimerPin.create(board.hal, board.comp, self.prefix) if board.has_dpll else None
        )
        self.counter_at = board.add_read(self.address(0), count)
        self.control_at = board.add_read(self.address(1), count)
        self.written_sample: int | None = None

    def _control(self, index: int) -> int:
        pins = self.instances[index]
        value = 0
        if pins.index_enable:
            value |= _ENC_LATCH_ON_INDEX | _ENC_CLEAR_ON_INDEX | _ENC_JUST_ONCE
        if pins.index_invert:
            value |= _ENC_INDEX_POLARITY
        if pins.index_mask:
            value |= _ENC_INDEX_MASK
        if pins.index_mask_invert:
            value |= _ENC_INDEX_MASK_POLARITY
        if pins.counter_mode:
            value |= _ENC_COUNTER_MODE
        if pins.filter:
            value |= _ENC_FILTER
        if pins.quad_error_enable:
            value |= _ENC_QUAD_ERROR
        return value

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        period_s = period / NS_PER_S
        for i, pins in enumerate(self.instances):
            state = self.states[i]
            counter = values[self.counter_at + i]
            control = values[self.control_at + i]
            count16 = counter & 0xFFFF
            pins.input_a = bool(control & 1)
            pins.input_b = bool(control & 2)
            pins.input_index = bool(control & 4)
            pins.quad_error = bool(control & _ENC_QUAD_ERROR) and pins.quad_error_enable
            if state.prev_count is None:
                state.prev_count = count16
            delta = (count16 - state.prev_count) & 0xFFFF
            if delta >= 0x8000:
                delta -= 0x10000
            state.prev_count = count16
            state.rawcounts += delta
            if state.index_armed and not control & _ENC_CLEAR_ON_INDEX:
                # the index came: the board cleared its count there and latched it
                state.zero = state.rawcounts - count16
                state.index_armed = False
                pins.index_enable = False
                pins.rawlatch = state.zero
            if pins.reset:
                state.zero = state.rawcounts
            count = state.rawcounts - state.zero
            scale = pins.scale or 1.0
            pins.rawcounts = state.rawcounts
            pins.count = count
            pins.position = count / scale
            if delta:
                state.still_s = 0.0
                velocity = delta / scale / period_s
            else:
                state.still_s += period_s
                velocity = pins.velocity if state.still_s < pins.vel_timeout else 0.0
                if state.still_s >= period_s * 2:
                    velocity = 0.0 if state.still_s >= pins.vel_timeout else velocity * 0.5
            pins.velocity = velocity
            pins.velocity_rpm = velocity * 60.0

    def prepare_write(self, out: list[int], period: int) -> None:
        """``index-enable`` is looked at every period (homing to an index, spindle sync)."""
        for i, pins in enumerate(self.instances):
            state = self.states[i]
            if bool(pins.index_enable) != state.index_armed and state.written is not None:
                self._write_control(i)

    def _write_control(self, index: int) -> None:
        control = self._control(index)
        state = self.states[index]
        self.board.queue_write(self.address(1, index), [control])
        state.written = control
        state.index_armed = bool(self.instances[index].index_enable)

    def write_changes(self, period: int) -> None:
        for i in range(self.count):
            if self._control(i) != self.states[i].written:
                self._write_control(i)
        sample = self.module_pins.sample_frequency
        if sample != self.written_sample:
            self._write_filter(sample)

    def _write_filter(self, sample: int) -> None:
        divisor = max(int(self.module.clock_hz / max(sample, 1)) - 2, 0) & 0xFFFF
        self.board.queue_write(self.address(4), [divisor])
        self.written_sample = sample

    def force_write(self) -> None:
        for i in range(self.count):
            self.states[i].written = None
        self.board.queue_write(self.address(2), [int(self.module.clock_hz / 2e6) - 2])
        self._write_filter(self.module_pins.sample_frequency)
        self.write_changes(0)


# ---------------------------------------------------------------- pwmgen
class PwmgenPins(RtComponent):
    enable = pin("bit in")
    value = pin("float in")
    offset_mode = param("bit rw", "offset-mode")
    output_type = param("s32 rw", "output-type", default=1)
    scale = param("float rw", default=1.0)


class PwmgenModulePins(RtComponent):
    pdm_frequency = param("u32 rw", "pdm_frequency", default=20000)
    pwm_frequency = param("u32 rw", "pwm_frequency", default=20000)


class PwmGen(Function):
    """PWM generators (``pwmgen.NN``): ``value / scale`` is the duty cycle, -1..1;
    output types 1 PWM+direction, 2 up/down, 3 PDM+direction, 4 direction+PWM."""

    gtag = GTAG_PWMGEN
    hal_name = "pwmgen"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.instances = [
            PwmgenPins.create(board.hal, board.comp, f"{self.prefix}.{i:02d}") for i in range(count)
        ]
        self.module_pins = PwmgenModulePins.create(board.hal, board.comp, self.prefix)
        self.value_at = board.add_write(self.address(0), count)
        self.bits = 9
        self.written: tuple | None = None

    def _rates(self) -> tuple[int, int, int]:
        """(PWM master DDS, PWM bits, PDM master DDS) for the requested frequencies."""
        clock = self.module.clock_hz
        pwm_hz = self.module_pins.pwm_frequency
        for bits in (12, 11, 10, 9):
            dds = int(pwm_hz * 65536.0 * (1 << bits) / clock)
            if dds < 65536:
                break
        else:
            bits, dds = 9, 65535
            self.module_pins.pwm_frequency = int(clock * 65535.0 / (65536.0 * 512.0))
            self.say(f"max PWM frequency is {self.module_pins.pwm_frequency} Hz")
        pdm_hz = self.module_pins.pdm_frequency
        pdm = min(max(int(pdm_hz * 65536.0 / clock), 1), 65535)
        return dds, bits, pdm

    def _settings(self) -> tuple:
        dds, bits, pdm = self._rates()
        modes = []
        for pins in self.instances:
            output_type = pins.output_type
            if output_type not in (1, 2, 3, 4):
                self.say(f"invalid pwmgen output_type {output_type} requested, switching to 1")
                output_type = pins.output_type = 1
            mode = (bits - 9) | {1: 0, 2: 2, 3: 3, 4: 1}[output_type] << 3
            mode |= (0 if output_type == 3 else 1) << 5  # double buffered, but PDM
            modes.append(mode)
        enables = sum(1 << i for i, pins in enumerate(self.instances) if pins.enable)
        return dds, bits, pdm, tuple(modes), enables

    def prepare_write(self, out: list[int], period: int) -> None:
        bits = self.bits
        for i, pins in enumerate(self.instances):
            scale = pins.scale or 1.0
            duty = min(max(pins.value / scale, -1.0), 1.0) if pins.enable else 0.0
            width = 12 if pins.output_type == 3 else bits
            if pins.offset_mode:
                width -= 1
                register = duty * ((1 << width) - 1) + (1 << width)
            else:
                register = abs(duty) * ((1 << width) - 1)
            value = int(register * 65536) & 0x7FFFFFFF
            if duty < 0:
                value |= 0x80000000
            out[self.value_at + i] = value

    def write_changes(self, period: int) -> None:
        settings = self._settings()
        if settings != self.written:
            self._queue(settings)

    def force_write(self) -> None:
        self._queue(self._settings())

    def _queue(self, settings: tuple) -> None:
        dds, bits, pdm, modes, enables = settings
        self.bits = bits
        board = self.board
        board.queue_write(self.address(1), list(modes))
        board.queue_write(self.address(4), [enables])
        board.queue_write(self.address(2), [dds])
        board.queue_write(self.address(3), [pdm])
        self.written = settings


# ---------------------------------------------------------------- SSR and OutM
def _outputs_of(board: Board, gtag: int, unit: int) -> list[int]:
    """The output numbers (0-based) a function instance has pins for."""
    numbers = []
    for pd in board.pins:
        if pd.sec_tag == gtag and pd.sec_unit == unit and pd.is_output and pd.pin_number <= 31:
            numbers.append(pd.pin_number - 1)
    return sorted(numbers)


class _OutputBits:
    """``out-NN`` and ``invert-NN`` pins of one SSR or OutM instance."""

    def __init__(self, board: Board, prefix: str, numbers: list[int]) -> None:
        self.numbers = numbers
        self.outs = []
        self.inverts = []
        for n in numbers:
            self.outs.append(_bit_pin(board, f"{prefix}.out-{n:02d}"))
            self.inverts.append(_bit_pin(board, f"{prefix}.invert-{n:02d}"))

    def word(self) -> int:
        value = 0
        for n, out, invert in zip(self.numbers, self.outs, self.inverts, strict=True):
            if bool(out.__get__(None)) != bool(invert.__get__(None)):
                value |= 1 << n
        return value


def _new(board: Board, name: str, hal_type: int, direction: int, *, is_pin: bool = True) -> Any:
    """A pin (or parameter) with a name made at run time; ``.__get__(None)`` reads it."""
    make = board.hal.new_pin if is_pin else board.hal.new_param
    slot = make(board.comp, name, hal_type, direction)
    return make_accessor(board.hal, hal_type, slot, is_pin=is_pin)


def _bit_pin(board: Board, name: str) -> Any:
    return _new(board, name, HAL_BIT, HAL_IN)


class SsrRatePin(RtComponent):
    rate = pin("u32 in", default=1_000_000)


class Ssr(Function):
    """Solid-state relay outputs (``ssr.NN.out-MM``, ``invert-MM``, ``rate``)."""

    gtag = GTAG_SSR
    hal_name = "ssr"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.outputs = []
        self.rates = []
        for i in range(count):
            prefix = f"{self.prefix}.{i:02d}"
            self.outputs.append(_OutputBits(board, prefix, _outputs_of(board, self.gtag, i)))
            self.rates.append(SsrRatePin.create(board.hal, board.comp, prefix))
        self.data_at = board.add_write(self.address(0), count)
        self.written: list[int | None] = [None] * count

    def prepare_write(self, out: list[int], period: int) -> None:
        for i, bits in enumerate(self.outputs):
            out[self.data_at + i] = bits.word()

    def _rate_register(self, index: int) -> int:
        rate = self.rates[index].rate
        if rate <= 0:
            return 0
        rate = min(max(rate, 25_000), 25_000_000)
        return int(self.module.clock_hz / (2 * rate)) - 2 | 0x1000

    def write_changes(self, period: int) -> None:
        for i in range(self.count):
            register = self._rate_register(i)
            if register != self.written[i]:
                self.board.queue_write(self.address(1, i), [register])
                self.written[i] = register

    def force_write(self) -> None:
        self.written = [None] * self.count
        self.write_changes(0)


class OutM(Function):
    """Plain outputs (``outm.NN.out-MM``, ``invert-MM``)."""

    gtag = GTAG_OUTM
    hal_name = "outm"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.outputs = [
            _OutputBits(board, f"{self.prefix}.{i:02d}", _outputs_of(board, self.gtag, i))
            for i in range(count)
        ]
        self.data_at = board.add_write(self.address(0), count)

    def prepare_write(self, out: list[int], period: int) -> None:
        for i, bits in enumerate(self.outputs):
            out[self.data_at + i] = bits.word()


# ---------------------------------------------------------------- InM
class InmPins(RtComponent):
    scan_rate = param("u32 rw", "scan_rate", default=20000)
    slow_scans = param("u32 rw", "slow_scans", default=500)
    fast_scans = param("u32 rw", "fast_scans", default=5)
    scan_width = param("u32 ro", "scan_width")


class InM(Function):
    """Debounced inputs (``inm.NN.input-MM``, ``-not``, ``raw-input-MM``) and the four
    MPG counters (``encK-count``)."""

    gtag = GTAG_INM
    hal_name = "inm"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.instances = []
        for i in range(count):
            prefix = f"{self.prefix}.{i:02d}"
            control = board.link.read(self.address(0, i), 1)[0]
            width = (control & 0x1F) + 1
            params = InmPins.create(board.hal, board.comp, prefix)
            params.scan_width = width
            inputs, raws, mpgs = [], [], []
            for n in range(width):
                name = f"{prefix}.input-{n:02d}"
                inputs.append((_new(board, name, HAL_BIT, HAL_OUT),
                               _new(board, f"{name}-not", HAL_BIT, HAL_OUT)))  # fmt: skip
                _new(board, f"{name}-slow", HAL_BIT, HAL_IN)
            for n in range(width):
                name = f"{prefix}.raw-input-{n:02d}"
                raws.append((_new(board, name, HAL_BIT, HAL_OUT),
                             _new(board, f"{name}-not", HAL_BIT, HAL_OUT)))  # fmt: skip
            for k in range(4):
                mpgs.append(_new(board, f"{prefix}.enc{k}-count", HAL_S32, HAL_OUT))
                _new(board, f"{prefix}.enc{k}-reset", HAL_BIT, HAL_IN)
                _new(board, f"{prefix}.enc{k}_4xmode", HAL_BIT, HAL_RW, is_pin=False)
            self.instances.append((inputs, raws, mpgs, params))
        self.filtered_at = board.add_read(self.address(2), count)
        self.raw_at = board.add_read(self.address(3), count)
        self.last: list[tuple[int, int] | None] = [None] * count

    def process_read(self, values: tuple[int, ...], period: int) -> None:
        for i, (inputs, raws, _mpgs, _params) in enumerate(self.instances):
            words = (values[self.filtered_at + i], values[self.raw_at + i])
            if words == self.last[i]:
                continue
            self.last[i] = words
            for table, word in ((inputs, words[0]), (raws, words[1])):
                for n, (level_pin, not_pin) in enumerate(table):
                    level = bool(word >> n & 1)
                    level_pin.__set__(None, level)
                    not_pin.__set__(None, not level)

    def force_write(self) -> None:
        for i, (_inputs, _raws, _mpgs, params) in enumerate(self.instances):
            clocks = max(int(self.module.clock_hz / 4 / max(params.scan_rate, 1)) - 1, 0)
            self.board.queue_write(self.address(1, i), [clocks & 0xFFFF])


# ---------------------------------------------------------------- LED
class Led(Function):
    """The board's LEDs (``led.CR01`` ...), as many as the board has."""

    hal_name = "led"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.leds = [_bit_pin(board, f"{self.prefix}.CR{n + 1:02d}") for n in range(count)]
        self.written: int | None = None

    def _word(self) -> int:
        value = 0
        for n, led in enumerate(self.leds):
            if led.__get__(None):
                value |= 1 << (31 - n)
        return value

    def write_changes(self, period: int) -> None:
        word = self._word()
        if word != self.written:
            self.board.queue_write(self.address(0), [word])
            self.written = word

    def force_write(self) -> None:
        self.written = None
        self.write_changes(0)


# ---------------------------------------------------------------- DPLL
class DpllPins(RtComponent):
    base_freq_khz = pin("float in", "base-freq-khz", default=-1.0)
    ddsize = pin("u32 out")
    phase_error_us = pin("float out", "phase-error-us")
    plimit = pin("u32 in", default=0x400000)
    prescale = pin("u32 out", default=1)
    time_const = pin("u32 in", "time-const", default=2000)


class Dpll(Function):
    """The phase-locked timer (``dpll.*``): its pins exist as in LinuxCNC; the timers
    are written to the board, which latches positions at them."""

    hal_name = "dpll"

    def __init__(self, board: Board, module: Module, count: int) -> None:
        super().__init__(board, module, count)
        self.pins = DpllPins.create(board.hal, board.comp, self.prefix)
        self.timers_us = []  # dpll.01.timer-us .. dpll.04.timer-us
        for n in range(1, 5):
            timer = _new(board, f"{self.prefix}.{n:02d}.timer-us", HAL_FLOAT, HAL_IN)
            timer.__set__(None, 100.0)
            self.timers_us.append(timer)
        self.written: tuple | None = None

    def _settings(self, period: int) -> tuple:
        pins = self.pins
        if pins.base_freq_khz < 0 and period:
            pins.base_freq_khz = 1e6 / period
        timers = []
        for n in range(4):
            clocks = int(self.timers_us[n].__get__(None) * self.module.clock_hz / 1e6) & 0xFFFF
            timers.append(clocks)
        return (timers[0] | timers[1] << 16, timers[2] | timers[3] << 16, pins.plimit)

    def write_changes(self, period: int) -> None:
        settings = self._settings(period)
        if settings != self.written:
            timer12, timer34, plimit = settings
            self.board.queue_write(self.address(4), [timer12])
            self.board.queue_write(self.address(5), [timer34])
            self.board.queue_write(self.address(2), [plimit])
            self.written = settings

    def force_write(self) -> None:
        self.written = None


FUNCTIONS: dict[int, type[Function]] = {
    GTAG_STEPGEN: StepGen,
    GTAG_ENCODER: Encoder,
    GTAG_PWMGEN: PwmGen,
    GTAG_SSR: Ssr,
    GTAG_OUTM: OutM,
    GTAG_INM: InM,
}
