"""Broadcast queues: every reader reads every message (the error channel, issue 6).

A plain queue hands each message to one reader (LinuxCNC's emcError: a second UI steals
messages from the first). With the ``broadcast`` option each reader connection has its own
cursor, and a message is dropped once every live reader has read it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from nml.config import NmlConfig, parse
from nml.errors import NmlConfigError, NmlTimeoutError
from nml.shmem import ShmBuffer
from tests.nml.sample_messages import TEST_CMD

WORKER = str(Path(__file__).with_name("nml_worker.py"))
NML = """\
B q SHMEM localhost 2048 0 0 1 8 11 queue broadcast
P m  q LOCAL localhost W  0 0.2 1 0
P rw q LOCAL localhost RW 0 0.2 0 4
P ui q LOCAL localhost R  0 5   0 1
P w  q LOCAL localhost W  0 0.2 0 2
"""


@pytest.fixture
def cfg() -> NmlConfig:
    return parse(NML, "test.nml")


def indexes(reader: ShmBuffer) -> list[int]:
    out = []
    while (msg := reader.read()) is not None:
        out.append(msg.index)
    return out


def test_broadcast_needs_a_queue() -> None:
    with pytest.raises(NmlConfigError, match="broadcast needs the queue option"):
        parse("B a SHMEM localhost 4096 0 0 1 4 1 broadcast\n")


def test_every_reader_reads_every_message_in_order(opened) -> None:
    opened("m")
    first, second, writer = opened("ui"), opened("ui"), opened("w")
    for i in range(5):
        writer.write(TEST_CMD(index=i))
    assert indexes(first) == [0, 1, 2, 3, 4]
    assert second.peek().index == 0
    assert indexes(second) == [0, 1, 2, 3, 4]
    assert writer._get("count") == 0  # both have read everything: dropped


def test_a_new_reader_also_gets_what_is_still_queued(opened) -> None:
    opened("m")
    writer = opened("w")
    writer.write(TEST_CMD(index=1))
    late = opened("ui")
    writer.write(TEST_CMD(index=2))
    assert indexes(late) == [1, 2]


def test_only_connections_allowed_to_read_hold_messages(opened) -> None:
    master = opened("m")  # W: never holds messages
    reader, writer = opened("ui"), opened("w")
    for i in range(3):
        writer.write(TEST_CMD(index=i))
    assert indexes(reader) == [0, 1, 2]
    assert master._get("count") == 0
    both = opened("rw")  # RW: may read, so it holds what it has not read
    writer.write(TEST_CMD(index=3))
    assert indexes(reader) == [3]
    assert master._get("count") == 1
    assert indexes(both) == [3]


def test_a_slow_reader_holds_messages_and_the_writer_waits_then_fails(opened) -> None:
    opened("m")
    fast, slow, writer = opened("ui"), opened("ui"), opened("w")
    written = 0
    with pytest.raises(NmlTimeoutError, match="queue full"):
        while True:
            writer.write(TEST_CMD(index=written))
            written += 1
            assert indexes(fast) == [written - 1]
    assert indexes(slow) == list(range(written))  # nothing was lost for the slow reader
    writer.write(TEST_CMD(index=written))  # room again
    assert indexes(fast) == [written] and indexes(slow) == [written]


def test_operator_messages_drop_the_oldest_instead_of_waiting(opened) -> None:
    """A reader that never reads (a headless machine's forgotten connection) must not stall
    the writer: the oldest messages make room at once and the newest are kept, in order."""
    opened("m")
    idle, writer = opened("ui"), opened("w")
    for index in range(500):  # many times what the queue holds
        writer.write(TEST_CMD(index=index), is_oldest_dropped=True)
    kept = indexes(idle)
    assert 5 < len(kept) < 500
    assert kept == list(range(500 - len(kept), 500))


def test_a_reader_that_leaves_no_longer_holds_messages(opened) -> None:
    opened("m")
    staying, leaving, writer = opened("ui"), opened("ui"), opened("w")
    for i in range(3):
        writer.write(TEST_CMD(index=i))
    assert indexes(staying) == [0, 1, 2]
    assert writer._get("count") == 3  # still held for `leaving`
    leaving.close()
    writer.write(TEST_CMD(index=3))
    assert writer._get("count") == 1  # only the unread one is left
    assert indexes(staying) == [3]


def test_reader_processes_each_receive_every_message(procs, cfg: NmlConfig, tmp_path) -> None:
    nml_file = tmp_path / "b.nml"
    nml_file.write_text(
        NML.replace("0.2 1 0", "5 1 0").replace("ui q", "r1 q", 1)
        + "P r2 q LOCAL localhost R 0 5 0 3\n"
    )
    from nml.config import load

    config = load(nml_file)
    with ShmBuffer(config.buffers["q"], config.process("m", "q")) as master:
        readers = [
            procs.python(WORKER, "queue-reader", str(nml_file), name, "0", "1.0")
            for name in ("r1", "r2")
        ]
        while len(master.connections()) < 3:
            pass
        for i in range(200):
            master.write(TEST_CMD(writer=9, index=i))
        master.write(TEST_CMD(writer=9, index=-1))  # tells the readers to stop
        results = []
        for reader in readers:
            out, err = reader.communicate(timeout=60)
            assert reader.returncode == 0, err
            results.append(json.loads(out.strip().splitlines()[-1])["got"])
    for got in results:
        assert [index for _, index, _ in got] == [*range(200), -1]
