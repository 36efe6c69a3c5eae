"""Stuck processes holding locks, and garbage written into shared memory (items 3, 11, 12).

A UI frozen while it holds a buffer's lock must not keep E-stop from any other UI, nor slow
task down; garbage in any buffer is found, reported once and repaired, and never crashes a
process, disables motion or leaves the machine moving unsupervised.
"""

from __future__ import annotations

import mmap
import random
import time

import posix_ipc
import pytest

from nml.ipcnames import ipc_name
from nml.shmem import is_process_alive
from tests.faults.conftest import WAIT_S, FaultyMachine, cnc, estop_from_another_ui

pytestmark = pytest.mark.slow

HOLD_LOCK = """
import os, signal
from cnc.api.connection import Link
buffer = Link(None).buffer({buffer!r})
buffer._lock()
print("holding", flush=True)
os.kill(os.getpid(), signal.SIGSTOP)
"""


def hold_lock_and_freeze(machine: FaultyMachine, procs, buffer: str):
    """Another UI takes ``buffer``'s lock and freezes (SIGSTOP) holding it."""
    holder = procs.python("-c", "import cnc\n" + HOLD_LOCK.format(buffer=buffer))
    assert holder.stdout.readline().strip() == "holding"
    machine.stopped_pids.append(holder.pid)  # type: ignore[attr-defined]
    return holder


def test_a_frozen_ui_holding_the_command_lock_blocks_no_estop(start_faulty, procs) -> None:
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    holder = hold_lock_and_freeze(machine, procs, "emcCommand")
    estop_from_another_ui(machine)  # returns: it does not wait behind the lock
    machine.wait_at_rest()
    machine.until(lambda s: s.task_state == cnc.STATE_ESTOP)  # task took it from the board
    texts = machine.text_of_messages(2.0)
    assert any(f"process {holder.pid} has held the command lock" in t for t in texts), texts


def test_a_frozen_reader_of_the_error_channel_does_not_slow_task(start_faulty, procs) -> None:
    machine: FaultyMachine = start_faulty()
    hold_lock_and_freeze(machine, procs, "emcError")
    c = machine.command
    for _ in range(5):  # each refusal is an operator message task cannot deliver now
        c.mdi("G999")
        assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_ERROR
    c.mdi("G0 X1")
    assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_DONE


def scribble(buffer: str, seed: int) -> None:
    """Random bytes over the whole shared-memory segment of ``buffer``."""
    shm = posix_ipc.SharedMemory(ipc_name("shm", buffer))
    with mmap.mmap(shm.fd, shm.size) as mm:
        shm.close_fd()
        mm[:] = random.Random(seed).randbytes(len(mm))


@pytest.mark.parametrize(
    "buffer",
    ["emcCommand", "emcStatus", "emcError", "toolCmd", "toolSts", "motCommand", "motStatus"],
)
def test_garbage_in_a_buffer_is_survived_and_estop_still_works(start_faulty, buffer) -> None:
    machine: FaultyMachine = start_faulty()
    pids = machine.pids()
    scribble(buffer, seed=len(buffer))
    time.sleep(1.0)
    assert machine.proc.poll() is None, machine.proc.stderr.read()
    assert all(is_process_alive(pid) for pid in pids.values()), pids
    # the machine answers again: status, commands, operator messages
    deadline = time.monotonic() + WAIT_S
    while True:
        try:
            machine.stat.poll()
            break
        except cnc.error:
            assert time.monotonic() < deadline
            time.sleep(0.1)
    burst = machine.messages(2.0)
    assert len(burst) < 20, burst  # said once (or a few times), not flooded
    if buffer == "motCommand":  # a command may have been lost: motion stops the machine
        machine.until(lambda s: s.task_state == cnc.STATE_ESTOP)
        assert not machine.pin("motion.motion-enabled")
        return
    machine.start_long_move()
    estop_from_another_ui(machine)
    machine.wait_at_rest()
