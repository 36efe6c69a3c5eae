"""error_channel(): every channel, in this process or another, sees every operator message."""

from __future__ import annotations

import json
import textwrap

import pytest

import cnc
from nml import emc
from nml.channels import EMC_ERROR, Nml
from tests.conftest import Processes

READER = textwrap.dedent(
    """
    import json, sys, time
    import cnc
    channel = cnc.error_channel()
    print("ready", flush=True)
    got = []
    deadline = time.monotonic() + 20
    while len(got) < int(sys.argv[1]) and time.monotonic() < deadline:
        message = channel.poll()
        if message is None:
            time.sleep(0.005)
        else:
            got.append(list(message))
    print(json.dumps(got), flush=True)
    """
)


def test_each_channel_gets_every_message(controller: Nml, procs: Processes) -> None:
    other_process = procs.python("-c", READER, "3")
    assert other_process.stdout.readline().strip() == "ready"
    first, second = cnc.error_channel(), cnc.error_channel()
    errors = controller[EMC_ERROR]
    errors.write(emc.EMC_OPERATOR_ERROR(error="spindle fault"))
    errors.write(emc.EMC_OPERATOR_TEXT(text="tool 3 loaded"))
    errors.write(emc.EMC_OPERATOR_DISPLAY(display="look here"))
    expected = [
        (cnc.OPERATOR_ERROR, "spindle fault"),
        (cnc.OPERATOR_TEXT, "tool 3 loaded"),
        (cnc.OPERATOR_DISPLAY, "look here"),
    ]
    for channel in (first, second):
        assert [channel.poll() for _ in range(3)] == expected
        assert channel.poll() is None
    out, _ = other_process.communicate(timeout=20)
    assert [tuple(item) for item in json.loads(out)] == expected


def test_a_new_channel_gets_what_is_still_queued_then_everything_after(controller: Nml) -> None:
    first = cnc.error_channel()
    errors = controller[EMC_ERROR]
    errors.write(emc.EMC_OPERATOR_TEXT(text="read by all"))
    assert first.poll() == (cnc.OPERATOR_TEXT, "read by all")  # dropped: every reader has it
    errors.write(emc.EMC_OPERATOR_TEXT(text="still queued"))
    late = cnc.error_channel()
    errors.write(emc.EMC_OPERATOR_TEXT(text="after"))
    assert [late.poll(), late.poll(), late.poll()] == [(12, "still queued"), (12, "after"), None]
    assert [first.poll(), first.poll()] == [(12, "still queued"), (12, "after")]


def test_poll_before_the_controller_is_up_raises_cnc_error() -> None:
    with pytest.raises(cnc.error, match="not running"):
        cnc.error_channel().poll()


def test_a_reader_is_told_how_many_messages_it_missed_when_the_channel_was_full(
    controller: Nml,
) -> None:
    channel = cnc.error_channel()
    errors = controller[EMC_ERROR]
    written = 0
    while not errors.stats()["read_count"]:  # until the writer had to drop the oldest
        errors.write(emc.EMC_OPERATOR_TEXT(text=f"burst {written}"), is_oldest_dropped=True)
        written += 1
    errors.write(emc.EMC_OPERATOR_TEXT(text="last"), is_oldest_dropped=True)
    kind, text = channel.poll()
    assert kind == cnc.OPERATOR_ERROR and text.startswith("2 operator message(s) were dropped")
    got = []
    while (message := channel.poll()) is not None:
        got.append(message[1])
    assert got[0] == "burst 2" and got[-1] == "last"  # the rest, in order, none twice
    assert len(got) == written + 1 - 2
