"""A separate OS process for the multi-process NML tests: ``python nml_worker.py ROLE NML ...``.

Roles print one JSON line on stdout with what they saw, so the test can check it.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from nml.config import load
from nml.errors import NmlError
from nml.shmem import ShmBuffer
from tests.nml.sample_messages import TEST_CMD, TEST_STAT


def connect(nml_file: str, process: str, buffer: str) -> ShmBuffer:
    cfg = load(nml_file)
    return ShmBuffer(cfg.buffers[buffer], cfg.process(process, buffer))


def queue_writer(nml_file: str, process: str, writer: str, count: str) -> dict:
    buf = connect(nml_file, process, "q")
    serials = [buf.write(TEST_CMD(writer=int(writer), index=i)) for i in range(int(count))]
    buf.close()
    return {"serials": serials}


def queue_reader(nml_file: str, process: str, total: str, idle_s: str) -> dict:
    """Read until ``total`` messages have been read by all readers or nothing comes for idle_s."""
    buf = connect(nml_file, process, "q")
    got = []
    while True:
        msg = buf.blocking_read(float(idle_s))
        if msg is None:
            break
        got.append([msg.writer, msg.index, msg.serial_number])
        if msg.index < 0:
            break
    buf.close()
    return {"got": got}


def latest_writer(nml_file: str, process: str, count: str) -> dict:
    buf = connect(nml_file, process, "s")
    msg = TEST_STAT()
    for i in range(1, int(count) + 1):
        msg.counter = i
        msg.values[:] = i
        buf.write(msg)
    buf.close()
    return {"written": int(count)}


def latest_reader(nml_file: str, process: str, until: str) -> dict:
    """Peek continuously until the counter reaches ``until``; count torn or backwards reads."""
    buf = connect(nml_file, process, "s")
    torn = backwards = reads = 0
    last = 0
    print(json.dumps({"ready": True}), flush=True)
    deadline = time.monotonic() + 60
    while last < int(until) and time.monotonic() < deadline:
        msg = buf.peek()
        if msg is None:
            continue
        reads += 1
        values = msg.values
        if not (values == msg.counter).all():
            torn += 1
        if msg.counter < last:
            backwards += 1
        last = msg.counter
    buf.close()
    return {"torn": torn, "backwards": backwards, "reads": reads, "last": last}


def hold_lock_and_die(nml_file: str, process: str, buffer: str, half_write: str) -> dict:
    """Take the buffer's mutex (optionally leaving a status write half done) and get killed."""
    buf = connect(nml_file, process, buffer)
    buf._lock()
    if half_write == "1":
        buf._put("seq", buf._get("seq") + 1)  # as if killed in the middle of a write
    print(json.dumps({"locked": True}), flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
    return {}


def blocking_reader(nml_file: str, process: str, timeout: str) -> dict:
    buf = connect(nml_file, process, "q")
    print(json.dumps({"ready": True}), flush=True)
    start = time.monotonic()
    msg = buf.blocking_read(float(timeout))
    waited = time.monotonic() - start
    buf.close()
    return {"index": None if msg is None else msg.index, "waited": waited}


def attach_only(nml_file: str, process: str, buffer: str) -> dict:
    try:
        buf = connect(nml_file, process, buffer)
    except NmlError as exc:
        return {"error": str(exc)}
    print(json.dumps({"attached": True}), flush=True)
    sys.stdin.readline()  # stay attached until the test closes stdin
    buf.close()
    return {"closed": True}


ROLES = {
    "queue-writer": queue_writer,
    "queue-reader": queue_reader,
    "latest-writer": latest_writer,
    "latest-reader": latest_reader,
    "hold-lock-and-die": hold_lock_and_die,
    "blocking-reader": blocking_reader,
    "attach-only": attach_only,
}

if __name__ == "__main__":
    print(json.dumps(ROLES[sys.argv[1]](*sys.argv[2:])), flush=True)
