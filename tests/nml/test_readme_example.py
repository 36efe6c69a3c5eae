"""README.md's "Adding a message type" does what it says: its declaration and its handler,
run as written, give a command that task routes to iocontrol after checking its
precondition, and that iocontrol carries out or refuses (nml/commands.py)."""

from __future__ import annotations

import re
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

from iocontrol.controller import IoControl
from nml import emc
from nml.codec import Encoding, decode, encode
from nml.commands import Handlers, Refused, carry_out, handler
from nml.message import RCS_STATUS, Receiver
from nml.registry import REGISTRY
from task.controller import Task

README = Path(__file__).resolve().parents[2] / "README.md"


def readme_blocks() -> list[str]:
    section = README.read_text().split("### Adding a message type", 1)[1]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def as_written(source: str):
    """The README's code compiled as a file of its own (not with this module's
    ``from __future__ import annotations``, which exec would pass on)."""
    return compile(source, str(README), "exec", dont_inherit=True)


@pytest.fixture
def example() -> Iterator[dict]:
    declaration, method = readme_blocks()
    names: dict = {}
    exec(as_written(declaration), names)
    cls = names["EMC_IO_GENERIC"]
    names |= {"IoControl": IoControl, "handler": handler, "Refused": Refused}
    receiver = "class ReadmeIoControl(IoControl):\n" + textwrap.indent(
        textwrap.dedent(method), "    "
    )
    exec(as_written(receiver), names)
    try:
        yield names
    finally:
        REGISTRY.unregister(cls)


def test_the_declaration_registers_a_routed_command(example) -> None:
    cls = example["EMC_IO_GENERIC"]
    assert REGISTRY.by_type(1605) is cls and REGISTRY.symbol(1605) == "EMC_IO_GENERIC"
    assert cls.RECEIVER is Receiver.IO  # from its family, EMC_IO_CMD_MSG
    msg = cls(request=2, note="hello")
    assert msg.waits_for_motion()
    assert (msg.value, msg.note) == (1.0, "hello")
    for encoding in Encoding:
        assert decode(encode(msg, encoding)) == msg


def test_task_checks_the_precondition_then_sends_it_to_iocontrol(example) -> None:
    cls = example["EMC_IO_GENERIC"]
    sent: list[emc.NMLmsg] = []
    task = Task.__new__(Task)  # only its routing: no machine behind it
    task.handlers = Handlers(task)
    task.mode = emc.EMC_TASK_MODE_ENUM.MANUAL
    task._send_io = lambda msg, is_waiting=False: sent.append(msg)
    task.state = emc.EMC_TASK_STATE_ENUM.OFF
    answer = carry_out("task", task._carry_out, cls(request=1))
    assert (answer.status, answer.reason) == (RCS_STATUS.ERROR, "machine must be on, it is off")
    assert sent == []
    task.state = emc.EMC_TASK_STATE_ENUM.ON
    assert carry_out("task", task._carry_out, cls(request=1)).status == RCS_STATUS.DONE
    assert sent == [cls(request=1)]


def test_iocontrol_carries_it_out_or_refuses_it(example) -> None:
    cls = example["EMC_IO_GENERIC"]
    io = example["ReadmeIoControl"].__new__(example["ReadmeIoControl"])
    function = Handlers(io)[cls]
    assert carry_out("iocontrol", function, cls(request=3, value=0.5)).status == RCS_STATUS.DONE
    assert io.generic_value == 1.5
    answer = carry_out("iocontrol", function, cls(request=-1))
    assert (answer.status, answer.reason) == (RCS_STATUS.ERROR, "request -1 must be 0 or more")


def test_an_unexpected_exception_is_an_internal_error_refusal(example) -> None:
    cls = example["EMC_IO_GENERIC"]

    def broken(_msg: emc.NMLmsg) -> None:
        raise KeyError("pocket")

    answer = carry_out("iocontrol", broken, cls(request=1))
    assert (answer.status, answer.reason) == (
        RCS_STATUS.ERROR,
        "iocontrol: internal error in EMC_IO_GENERIC: KeyError: 'pocket'",
    )
