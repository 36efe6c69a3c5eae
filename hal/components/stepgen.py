"""stepgen: software step pulse generation, position or velocity mode.

``loadrt stepgen step_type=0[,0...] [ctrl_type=p|v[,...]]`` (step/dir only). Functions:
``stepgen.update-freq`` (servo thread) computes the step rate from ``position-cmd`` (p mode,
with ``maxvel``/``maxaccel`` limits, 0 = no limit) or ``velocity-cmd`` (v mode), both in
machine units scaled by ``position-scale`` steps per unit; ``stepgen.make-pulses`` (base thread
when one exists) emits steps: ``step`` is high for ``steplen`` calls, ``dir`` gives the
direction; ``stepgen.capture-position`` publishes ``counts`` and ``position-fb``.
"""

from __future__ import annotations

import math
from typing import Any

from hal.api import RtComponent, module_funct, param, pin
from hal.core import HalError


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
        self.accum = 0.0  # position in steps, fractional
        self.raw = 0
        self.freq = 0.0
        self.old_cmd = None
        self.high_left = 0

    def pulses(self, period: int) -> None:
        if self.high_left > 0:
            self.high_left -= 1
            if self.high_left == 0:
                self.step = False
            return
        if not self.enable:
            return
        self.accum += self.freq * period * 1e-9
        target = math.floor(self.accum + 0.5)
        if target != self.raw:
            direction = 1 if target > self.raw else -1
            self.dir = direction < 0
            self.raw += direction
            self.rawcounts = self.raw
            self.step = True
            self.high_left = max(self.steplen, 1)

    def update(self, period: int) -> None:
        dt = period * 1e-9
        scale = self.position_scale or 1.0
        maxvel = abs(self.maxvel) * abs(scale)
        maxaccel = abs(self.maxaccel) * abs(scale)
        if not self.enable:
            self.freq = 0.0
            self.frequency = 0.0
            self.old_cmd = None
            return
        if self.is_position_mode:
            cmd = self.position_cmd * scale
            ff = 0.0 if self.old_cmd is None else (cmd - self.old_cmd) / dt
            self.old_cmd = cmd
            error = cmd - self.accum
            wanted = error / dt
            if maxaccel > 0:
                brake = math.sqrt(2 * maxaccel * abs(error)) + abs(ff)
                wanted = min(max(wanted, -brake), brake)
        else:
            wanted = self.velocity_cmd * scale
        if maxaccel > 0:
            dv = maxaccel * dt
            wanted = min(max(wanted, self.freq - dv), self.freq + dv)
        if maxvel > 0:
            wanted = min(max(wanted, -maxvel), maxvel)
        self.freq = wanted
        self.frequency = wanted

    def capture(self) -> None:
        scale = self.position_scale or 1.0
        self.counts = self.raw
        self.position_fb = self.raw / scale


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

    @module_funct("make-pulses", fp=False)
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
