"""sim_parport: a stand-in for hal_parport with the same pins (load it with
``names=parport.0``), for simulated stepconf configs: ``write`` copies each output
``pin-NN-out`` (xor ``pin-NN-out-invert``) to ``pin-NN-out-fake``; ``read`` copies each
``pin-NN-in-fake`` to ``pin-NN-in`` and its inverse to ``pin-NN-in-not``; ``reset`` does
nothing."""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, funct, param, pin

OUTPUTS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 14, 16, 17)
INPUTS = (2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15)


def _read(self: Any, period: int) -> None:
    for real, fake, inverse in self.input_pins:
        value = fake.__get__(None)
        real.__set__(None, value)
        inverse.__set__(None, not value)


def _write(self: Any, period: int) -> None:
    for out, invert, fake in self.output_pins:
        fake.__set__(None, out.__get__(None) != invert.__get__(None))


def _reset(self: Any, period: int) -> None:
    """Nothing to reset: the outputs follow their pins at once."""


def _setup(self: Any) -> None:
    members = type(self).__dict__
    self.output_pins = [
        (members[f"out{n}"], members[f"out{n}_invert"], members[f"out{n}_fake"]) for n in OUTPUTS
    ]
    self.input_pins = [
        (members[f"in{n}"], members[f"in{n}_fake"], members[f"in{n}_not"]) for n in INPUTS
    ]


def _declarations() -> dict[str, Any]:
    members: dict[str, Any] = {}
    for n in OUTPUTS:
        members[f"out{n}"] = pin("bit in", f"pin-{n:02d}-out")
        members[f"out{n}_fake"] = pin("bit out", f"pin-{n:02d}-out-fake")
        members[f"out{n}_invert"] = param("bit rw", f"pin-{n:02d}-out-invert")
        members[f"out{n}_reset"] = param("bit rw", f"pin-{n:02d}-out-reset")
    for n in INPUTS:
        members[f"in{n}"] = pin("bit out", f"pin-{n:02d}-in")
        members[f"in{n}_fake"] = pin("bit in", f"pin-{n:02d}-in-fake")
        members[f"in{n}_not"] = pin("bit out", f"pin-{n:02d}-in-not")
    members["reset_time"] = pin("float in")
    members["setup"] = _setup
    members["read"] = funct("read")(_read)
    members["write"] = funct("write")(_write)
    members["reset"] = funct("reset")(_reset)
    return members


SimParport = type("SimParport", (RtComponent,), _declarations())
COMPONENT = SimParport
