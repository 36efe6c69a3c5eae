"""sim_encoder: simulated quadrature encoder (``loadrt sim_encoder num_chan=N``).

``sim-encoder.update-speed`` (servo thread) turns ``speed`` (revolutions per second, times
``scale``) into an edge rate of 4 * ``ppr`` per revolution; ``sim-encoder.make-pulses`` (base
thread) advances phase-A/B by at most one quadrature state per call and pulses phase-Z once
per revolution. ``rawcounts`` counts the states made.
"""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, module_funct, pin

_PHASES = ((False, False), (True, False), (True, True), (False, True))


class SimEncoder(RtComponent):
    phase_A = pin("bit out")
    phase_B = pin("bit out")
    phase_Z = pin("bit out")
    ppr = pin("u32 io", default=100)
    rawcounts = pin("s32 in")
    scale = pin("float io", default=1.0)
    speed = pin("float in")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if "num_chan" in args:
            args = dict(args)
            args["count"] = args.pop("num_chan")
        return super().instances(module, args)

    def setup(self) -> None:
        self.rate = 0.0  # quadrature states per second
        self.accum = 0.0
        self.state = 0

    @module_funct("make-pulses", fp=False)
    @classmethod
    def make_pulses(cls, instances: list[SimEncoder], period: int) -> None:
        for inst in instances:
            inst.accum += inst.rate * period * 1e-9
            step = 1 if inst.accum >= 1.0 else -1 if inst.accum <= -1.0 else 0
            if step:
                inst.accum -= step
                inst.state += step
                inst.phase_A, inst.phase_B = _PHASES[inst.state % 4]
                cycle = 4 * max(inst.ppr, 1)
                inst.phase_Z = inst.state % cycle == 0
                inst.rawcounts = inst.state

    @module_funct("update-speed")
    @classmethod
    def update_speed(cls, instances: list[SimEncoder], period: int) -> None:
        for inst in instances:
            inst.rate = inst.speed * inst.scale * 4 * inst.ppr


COMPONENT = SimEncoder
