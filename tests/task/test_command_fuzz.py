"""Any command a client can put in task's command buffer, with any field values, is answered
and leaves the machine running (task, motion, iocontrol as real processes).

Found this way: task crashed on an error text with non-ASCII characters (the launcher then
stops everything), iocontrol on a tool table name holding a NUL.
"""

from __future__ import annotations

import math
import random

import cnc
from nml.message import MessageKind, NMLmsg
from nml.registry import REGISTRY

FLOATS = [0.0, 1.0, -1.0, 0.5, 100.0, 1e9, 1e300, -1e300, math.nan, math.inf, -math.inf]
INTS = [0, 1, -1, 2, 3, 5, 9, 100, 2**31 - 1, -(2**31)]
TEXTS = [b"", b"x", b"G0 X1", b"/no/such/file.ngc", "ñ".encode() * 100, b"M2", b"a\0b"]


def random_command(rng: random.Random, cls: type[NMLmsg]) -> NMLmsg:
    """Raw bytes for every field, or odd but well-formed values."""
    if rng.random() < 0.5:
        return cls.from_bytes(rng.randbytes(cls.fixed_size()))
    values: list[object] = []
    for code in cls.flat_codes:
        if code == "d":
            values.append(rng.choice(FLOATS))
        elif code == "f":
            values.append(rng.choice([0.0, 1.0, -1.0, math.nan, math.inf]))
        elif code == "i":
            values.append(rng.choice(INTS))
        elif code == "B":
            values.append(rng.randrange(256))
        elif code == "?":
            values.append(rng.random() < 0.5)
        elif code == "Q":
            values.append(rng.randrange(2**64))
        else:  # a text field, "<n>s"
            values.append(rng.choice(TEXTS)[: int(code[:-1])])
    return cls.from_flat(values)


def test_random_commands_are_all_answered_and_the_machine_keeps_running(start_machine) -> None:
    machine = start_machine()
    commands = [cls for cls in REGISTRY.of_kind(MessageKind.COMMAND) if cls.__module__ == "nml.emc"]
    rng = random.Random(3)
    answers = set()
    for _ in range(150):
        cls = rng.choice(commands)
        machine.command._send(random_command(rng, cls))
        answer = machine.command.wait_complete(5)
        assert answer in (cnc.RCS_DONE, cnc.RCS_ERROR), cls.NAME
        assert machine.proc.poll() is None, f"the machine stopped after {cls.NAME}"
        answers.add(answer)
        machine.messages(0)  # (a UI reads them; unread, the oldest would just go)
    assert answers == {cnc.RCS_DONE, cnc.RCS_ERROR}
    c = machine.command
    c.state(cnc.STATE_ESTOP)
    assert c.wait_complete(5) == cnc.RCS_DONE
    machine.ready_to_move()  # E-stop reset, on, homed, MDI: it all still works
    c.mdi("G10 L2 P1 X0 Y0 Z0")
    assert c.wait_complete(10) == cnc.RCS_DONE
