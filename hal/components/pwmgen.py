"""pwmgen: software PWM and PDM (``loadrt pwmgen output_type=0,1,2``; at most 8 channels).

``pwmgen.update`` (servo thread) turns ``value`` into a duty cycle: value / ``scale`` +
``offset``, limited to ``min-dc``..``max-dc`` in size (negative only for output types 1
and 2). ``pwmgen.make-pulses`` (base thread) makes the pulses: pure PWM at ``pwm-freq``
(rounded to whole base periods, duty cycle too; ``curr-dc`` shows the result), dithered
PWM (``dither-pwm``: the rounding error carries over to the next cycle) or, with
``pwm-freq`` 0, pulse density modulation. Output type 0 gives ``pwm``; 1 ``pwm`` and
``dir``; 2 ``up`` and ``down``. ``enable`` false stops the output.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, module_funct, pin
from hal.components._cmath import to_s32, to_s64
from hal.core import HalError

MAX_CHANNELS = 8
DISABLED, PURE, DITHER, PDM = 0, 1, 2, 3


class _Clock:
    """The base thread's period, as make-pulses last saw it (shared by all channels)."""

    def __init__(self) -> None:
        self.period_ns = -1
        self.old_period_ns = -1


class PwmGen(RtComponent):
    scale = pin("float io", default=1.0)
    offset = pin("float io")
    dither_pwm = pin("bit io")
    pwm_freq = pin("float io")
    min_dc = pin("float io")
    max_dc = pin("float io", default=1.0)
    curr_dc = pin("float out")
    enable = pin("bit in")
    value = pin("float in")
    pwm = pin("bit out", when=lambda o: o["output_type"] < 2)
    dir = pin("bit out", when=lambda o: o["output_type"] == 1)
    up = pin("bit out", when=lambda o: o["output_type"] == 2)
    down = pin("bit out", when=lambda o: o["output_type"] == 2)

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"output_type"}:
            raise HalError(f"{module}: unknown argument '{sorted(set(args) - {'output_type'})[0]}'")
        try:
            types = [int(word, 0) for word in args.get("output_type", "").split(",") if word]
        except ValueError:
            raise HalError(f"{module}: output_type must be numbers") from None
        types = types[:MAX_CHANNELS]
        if -1 in types:
            types = types[: types.index(-1)]
        for index, kind in enumerate(types):
            if not 0 <= kind <= 2:
                raise HalError(f"PWMGEN: ERROR: bad output type '{kind}', channel {index}")
        if not types:
            raise HalError("PWMGEN: ERROR: no channels configured")
        clock = _Clock()
        return [
            (f"pwmgen.{i}", {"output_type": kind, "clock": clock}) for i, kind in enumerate(types)
        ]

    def setup(self, output_type: int = 0, clock: _Clock | None = None) -> None:
        self.output_type = output_type
        self.clock = clock or _Clock()
        self.period = 50000
        self.high_time = self.period_timer = self.high_timer = 0
        self.is_high = False
        self.mode = DISABLED
        self.direction = False
        self.old_scale = self.scale + 1.0
        self.scale_recip = 1.0
        self.old_pwm_freq = -1.0
        self.periods = 1
        self.periods_recip = 1.0

    @module_funct("make-pulses", has_fp=False)
    @classmethod
    def make_pulses(cls, instances: list[PwmGen], period: int) -> None:
        for gen in instances:
            gen.clock.period_ns = period
            mode = gen.mode
            if mode == PURE:
                if gen.is_high:
                    gen.high_timer += period
                    if gen.high_timer >= gen.high_time:
                        gen.is_high = False
                gen.period_timer += period
                if gen.period_timer >= gen.period:  # a new cycle, timers restart: no jitter
                    gen.period_timer = gen.high_timer = 0
                    if gen.high_time > 0:
                        gen.is_high = True
            elif mode == DITHER:
                if gen.is_high:
                    gen.high_timer -= period
                    if gen.high_timer <= 0:
                        gen.is_high = False
                gen.period_timer += period
                if gen.period_timer >= gen.period:  # keep the remainders: finer resolution
                    gen.period_timer -= gen.period
                    gen.high_timer += gen.high_time
                    if gen.high_timer > 0:
                        gen.is_high = True
            elif mode == PDM:
                gen.high_timer += gen.high_time
                if gen.is_high:
                    gen.high_timer -= period
                gen.is_high = gen.high_timer > 0
            else:
                gen.is_high = False
                gen.high_timer = gen.period_timer = 0
            if gen.output_type < 2:
                gen.pwm = gen.is_high
            else:
                gen.up = gen.is_high and not gen.direction
                gen.down = gen.is_high and gen.direction

    @module_funct("update")
    @classmethod
    def update(cls, instances: list[PwmGen], period: int) -> None:
        clock = instances[0].clock if instances else _Clock()
        period_ns = clock.period_ns
        for gen in instances:
            gen._update(period_ns, clock.old_period_ns)
        clock.old_period_ns = period_ns

    def _update(self, period_ns: int, old_period_ns: int) -> None:
        # the duty cycle limits: 0 <= min <= max <= 1
        if self.max_dc > 1.0:
            self.max_dc = 1.0
        if self.min_dc > self.max_dc:
            self.min_dc = self.max_dc
        if self.min_dc < 0.0:
            self.min_dc = 0.0
        if self.max_dc < self.min_dc:
            self.max_dc = self.min_dc
        scale = self.scale
        if scale != self.old_scale:
            self.old_scale = scale
            if -1e-20 < scale < 1e-20:
                scale = self.scale = 1.0
            self.scale_recip = 1.0 / scale
        freq = self.pwm_freq
        if not self.enable:
            mode = DISABLED
        elif freq == 0:
            mode = PDM
        elif self.dither_pwm:
            mode = DITHER
        else:
            mode = PURE
        if freq != self.old_pwm_freq:
            self.mode = DISABLED  # a new frequency: recalculate
        if self.mode != mode or period_ns != old_period_ns:
            self.mode = DISABLED
            self._set_period(mode, period_ns)
        duty = self.value * self.scale_recip + self.offset
        if self.output_type == 0 and duty < 0.0:
            duty = 0.0
        low, high = self.min_dc, self.max_dc
        if duty >= 0.0:
            if duty > high:
                duty = high
            elif duty < low:
                duty = low
            self.direction = False
            size = duty
        else:
            if duty < -high:
                duty = -high
            elif duty > -low:
                duty = -low
            self.direction = True
            size = -duty
        if mode == PURE:
            high_periods = to_s32(self.periods * size + 0.5)
            self.high_time = high_periods * period_ns
            self.curr_dc = (high_periods if duty >= 0 else -high_periods) * self.periods_recip
        else:
            self.high_time = to_s64(self.period * size + 0.5)
            self.curr_dc = duty
        if self.output_type == 1:
            self.dir = self.direction
        self.mode = mode

    def _set_period(self, mode: int, period_ns: int) -> None:
        """The PWM period for a new mode, frequency or base period."""
        freq = self.pwm_freq
        if freq <= 0.0:  # PDM
            self.pwm_freq = 0.0
            self.period = period_ns
        else:
            if freq < 0.5:
                freq = self.pwm_freq = 0.5
            elif freq > 1e9 / 2.0 / period_ns:  # at most one cycle per two base periods
                freq = self.pwm_freq = 1e9 / 2.0 / period_ns
            if mode == PURE:  # whole base periods per cycle
                self.periods = to_s32(1e9 / freq / period_ns + 0.5)
                self.periods_recip = 1.0 / self.periods
                self.period = self.periods * period_ns
                self.pwm_freq = 1.0e9 / self.period
            else:
                self.period = to_s64(1.0e9 / freq)
        self.old_pwm_freq = self.pwm_freq


COMPONENT = PwmGen
