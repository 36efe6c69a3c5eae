"""SHMEM buffers within one process: kinds, timeouts, access rules, corrupt content."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import random
import signal
import threading
import time
from collections.abc import Callable, Iterator

import pytest

from nml.config import NmlConfig, parse
from nml.errors import NmlAccessError, NmlFormatError, NmlTimeoutError
from nml.ipcnames import instance_objects
from nml.shmem import RECORD, ShmBuffer
from tests.nml.sample_messages import TEST_BIG, TEST_CMD, TEST_STAT

NML = """\
B q  SHMEM localhost 2048  0 0 1 4 11 queue
B s  SHMEM localhost 40000 0 0 2 4 12
B sm SHMEM localhost 40000 1 0 3 4 13
B tiny SHMEM localhost 1024 0 0 4 2 14
P m  q  LOCAL localhost RW 0 0.2 1 0
P m  s  LOCAL localhost RW 0 0.2 1 0
P m  sm LOCAL localhost RW 0 0.2 1 0
P m  tiny LOCAL localhost RW 0 0.2 1 0
P r  q  LOCAL localhost RW 0 0.2 0 1
P r  s  LOCAL localhost R  0 0.2 0 1
P r  sm LOCAL localhost R  0 0.2 0 1
P r  tiny LOCAL localhost R 0 0.2 0 1
P w  q  LOCAL localhost W  0 0   0 2
P late q LOCAL localhost R 0 0.3 0 3
"""


@pytest.fixture
def cfg() -> NmlConfig:
    return parse(NML, "test.nml")


def hold_lock(buffer: ShmBuffer, seconds: float) -> threading.Thread:
    """Another thread takes ``buffer``'s mutex and keeps it ``seconds`` (a busy process);
    returns once it holds it."""
    is_held = threading.Event()

    def hold() -> None:
        buffer._lock()
        is_held.set()
        time.sleep(seconds)
        buffer._unlock()

    holder = threading.Thread(target=hold)
    holder.start()
    assert is_held.wait(5)
    return holder


def test_queue_is_fifo_and_each_message_is_read_once(opened) -> None:
    master, reader = opened("m", "q"), opened("r", "q")
    for i in range(5):
        master.write(TEST_CMD(index=i, text=f"#{i}"))
    assert reader.peek().index == 0  # peek does not remove
    assert [reader.read().index for _ in range(5)] == [0, 1, 2, 3, 4]
    assert reader.read() is None
    assert master.read() is None


def test_queue_wraps_around_many_times_without_loss(opened) -> None:
    master, reader = opened("m", "q"), opened("r", "q")
    expected = 0
    for i in range(500):
        master.write(TEST_CMD(index=i, text="x" * (i % 60)))
        if i % 3 == 2:  # drain in uneven batches so records straddle the ring's end
            while (msg := reader.read()) is not None:
                assert (msg.index, msg.text) == (expected, "x" * (expected % 60))
                expected += 1
    while (msg := reader.read()) is not None:
        assert msg.index == expected
        expected += 1
    assert expected == 500


def test_serial_numbers_increase_per_channel(opened) -> None:
    master, writer = opened("m", "q"), opened("w", "q")
    serials = [master.write(TEST_CMD()), writer.write(TEST_CMD()), master.write(TEST_CMD())]
    assert serials == [1, 2, 3]
    reader = opened("r", "q")
    assert [reader.read().serial_number for _ in range(3)] == [1, 2, 3]


def test_full_queue_waits_for_the_timeout_then_fails(opened) -> None:
    master = opened("m", "q")
    written = 0
    with pytest.raises(NmlTimeoutError, match=r"buffer q: queue full \(\d+ messages\) for 0.2 s"):
        while True:
            master.write(TEST_CMD(index=written))
            written += 1
    assert written > 5
    start = time.monotonic()
    with pytest.raises(NmlTimeoutError):
        master.write(TEST_CMD())
    assert time.monotonic() - start >= 0.19  # it did wait (NML-031 timeout > 0)
    reader = opened("r", "q")
    assert [reader.read().index for _ in range(written)] == list(range(written))


def test_zero_timeout_never_waits(opened) -> None:
    opened("m", "q")
    writer = opened("w", "q")  # timeout 0 (NML-031: fail at once)
    with pytest.raises(NmlTimeoutError):
        for _ in range(1000):
            writer.write(TEST_CMD())


def test_oversize_message_is_refused_not_truncated(opened) -> None:
    master = opened("m", "q")
    too_big = r"buffer q: TEST_BIG is 32.* bytes encoded, more than"
    with pytest.raises(NmlFormatError, match=too_big):
        master.write(TEST_BIG())
    assert master.stats()["count"] == 0


@pytest.mark.parametrize("buffer", ["s", "sm"])
def test_latest_value_read_tells_new_from_seen_and_peek_repeats(opened, buffer: str) -> None:
    master, reader = opened("m", buffer), opened("r", buffer)
    assert reader.read() is None and reader.peek() is None
    status = TEST_STAT(counter=1, echo_serial_number=7)
    status.values[:] = 1.5
    master.write(status)
    first = reader.read()
    assert (first.counter, first.echo_serial_number, first.values[1999]) == (1, 7, 1.5)
    assert reader.read() is None  # already seen
    assert reader.peek().counter == 1
    status.counter = 2
    master.write(status)
    master.write(status)  # two writes, one new value
    assert reader.read().counter == 2
    assert reader.read() is None


def test_ops_are_enforced(opened) -> None:
    opened("m", "s")
    reader = opened("r", "s")
    with pytest.raises(NmlAccessError, match="process r may not write buffer s"):
        reader.write(TEST_STAT())
    opened("m", "q")
    writer = opened("w", "q")
    with pytest.raises(NmlAccessError, match="process w may not read buffer q"):
        writer.read()


def test_max_procs_is_enforced(cfg: NmlConfig, opened) -> None:
    opened("m", "tiny")
    opened("r", "tiny")
    with pytest.raises(NmlAccessError, match="already 2 connections"):
        opened("r", "tiny")


def test_attach_without_master_fails_after_timeout(cfg: NmlConfig) -> None:
    start = time.monotonic()
    with pytest.raises(NmlAccessError, match="buffer q: shared memory segment does not exist"):
        ShmBuffer(cfg.buffers["q"], cfg.process("late", "q"))
    assert time.monotonic() - start >= 0.29


def test_master_removes_everything_at_close(cfg: NmlConfig, cnc_instance: str) -> None:
    master = ShmBuffer(cfg.buffers["q"], cfg.process("m", "q"))
    reader = ShmBuffer(cfg.buffers["q"], cfg.process("r", "q"))
    master.write(TEST_CMD())
    reader.blocking_read(0)
    assert instance_objects(cnc_instance)
    reader.close()
    master.close()
    assert instance_objects(cnc_instance) == []


def test_blocking_read_waits_for_a_busy_lock_even_with_a_zero_p_line_timeout(opened) -> None:
    master = opened("m", "q")
    impatient = opened("w", "q")  # timeout 0: a plain write fails at once when busy
    reader = ShmBuffer(master.config, dataclasses.replace(impatient.process, ops="RW"))
    try:
        releaser = hold_lock(master, 0.2)
        with pytest.raises(NmlTimeoutError):
            impatient.write(TEST_CMD())
        assert reader.blocking_read(0.1) is None  # still busy: a timeout, not an error
        releaser.join()
        master.write(TEST_CMD(index=5))
        assert reader.blocking_read(5).index == 5
    finally:
        reader.close()


def test_blocking_read_times_out_with_none(opened) -> None:
    opened("m", "q")
    reader = opened("r", "q")
    start = time.monotonic()
    assert reader.blocking_read(0.1) is None
    assert time.monotonic() - start >= 0.09
    assert reader.blocking_read(0) is None


def test_garbage_in_a_status_buffer_is_a_clear_error(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT(counter=5))
    start = master.layout.data_offset
    master._mm[start : start + 4] = b"\x99\x99\x00\x00"  # unknown type
    with pytest.raises(NmlFormatError, match="buffer s: unknown message type 39321"):
        reader.peek()
    master._put("latest_len", 10**9)
    with pytest.raises(NmlFormatError, match="corrupt"):
        reader.peek()
    master.write(TEST_STAT(counter=6))  # the next good write is read normally
    assert reader.peek().counter == 6


def test_wrong_layout_and_short_payload_are_reported(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT())
    start = master.layout.data_offset
    master._mm[start + 8 : start + 12] = b"\x01\x02\x03\x04"  # layout checksum
    with pytest.raises(NmlFormatError, match="different field layout"):
        reader.peek()
    master.write(TEST_STAT())
    master._mm[start + 4 : start + 8] = (12).to_bytes(4, "little")  # payload length
    with pytest.raises(NmlFormatError, match="payload is 12 bytes, expected"):
        reader.peek()


def test_garbage_in_a_queue_is_dropped_with_a_clear_error(opened) -> None:
    master, reader = opened("m", "q"), opened("r", "q")
    master.write(TEST_CMD(index=1))
    master.write(TEST_CMD(index=2))
    base = master.layout.data_offset
    first = base + RECORD.size  # the first message, after its record header
    master._mm[first : first + 4] = b"\xff\xff\x00\x00"  # unknown type
    with pytest.raises(NmlFormatError, match="unknown message type"):
        reader.read()
    assert reader.read().index == 2  # the bad message was consumed, the good one survives
    master.write(TEST_CMD(index=3))
    head = master._get("head")
    master._mm[base + head : base + head + 4] = (10**6).to_bytes(4, "little")  # record length
    with pytest.raises(
        NmlFormatError, match=r"queue record at offset 0 claims 1000000 bytes \(corrupt\); 1 queued"
    ):
        reader.read()
    master.write(TEST_CMD(index=4))
    assert reader.read().index == 4


def test_msgpack_buffer_round_trips_text_and_arrays(opened) -> None:
    master, reader = opened("m", "sm"), opened("r", "sm")
    status = TEST_STAT(counter=9)
    status.values[::2] = -2.25
    master.write(status)
    assert reader.read() == status


def test_overwritten_segment_header_is_reported_once_and_repaired(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT(counter=1))
    master._mm[0:4] = b"JUNK"
    with pytest.raises(NmlFormatError, match=r"buffer s: segment header is corrupt.*rewritten"):
        reader.peek()
    assert reader.peek() is None  # sound again; what it held is gone until the next write
    master.write(TEST_STAT(counter=2))
    assert reader.peek().counter == 2


def test_garbage_over_a_status_buffer_is_reported_once_then_sound(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT(counter=1))
    size = master.layout.segment_size
    master._mm[:size] = random.Random(1).randbytes(size)  # over everything, slots too
    with pytest.raises(NmlFormatError):
        reader.peek()
    assert reader.peek() is None
    master.write(TEST_STAT(counter=3))
    assert reader.peek().counter == 3


def test_a_status_write_that_never_ends_is_a_corrupt_counter(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT(counter=1))
    master._put("seq", master._get("seq") + 1)  # odd: "in progress", but nobody writes
    with pytest.raises(NmlFormatError, match="never finished"):
        reader.peek()
    master.write(TEST_STAT(counter=4))
    assert reader.peek().counter == 4


def test_a_corrupt_queue_header_is_reset_and_reported_once(opened) -> None:
    master, reader = opened("m", "q"), opened("r", "q")
    master.write(TEST_CMD(index=1))
    master._put("head", master.layout.capacity + 8)  # out of the buffer
    with pytest.raises(NmlFormatError, match="queue header was corrupt"):
        reader.read()
    assert reader.read() is None
    master.write(TEST_CMD(index=2))
    assert reader.read().index == 2


def test_a_writer_repairs_a_corrupt_queue_and_its_message_goes_in(opened) -> None:
    master, reader = opened("m", "q"), opened("r", "q")
    master._put("count", 7)  # with nothing used: impossible
    master.write(TEST_CMD(index=5))
    assert reader.read().index == 5
    assert reader.read() is None


def test_a_signal_during_a_blocking_read_ends_the_wait_cleanly(opened) -> None:
    opened("m", "q")
    reader = opened("r", "q")
    received = []
    previous = signal.signal(signal.SIGUSR1, lambda *_: received.append(1))
    try:
        threading.Timer(0.1, os.kill, (os.getpid(), signal.SIGUSR1)).start()
        assert reader.blocking_read(5) is None  # interrupted: no message, no exception
        assert received == [1]
    finally:
        signal.signal(signal.SIGUSR1, previous)


@pytest.mark.parametrize("buffer", ["s", "sm"])
def test_peek_into_copies_the_status_in_place(opened, buffer: str) -> None:
    master, reader = opened("m", buffer), opened("r", buffer)
    target = TEST_STAT()
    view = target.byte_view()
    assert reader.peek_into(target, view if buffer == "s" else None) is False  # nothing yet
    status = TEST_STAT(counter=4)
    status.values[7] = 2.5
    master.write(status)
    assert reader.peek_into(target, view if buffer == "s" else None) is True
    assert (target.counter, target.values[7]) == (4, 2.5)


def test_peek_into_checks_what_it_copies(opened) -> None:
    master, reader = opened("m", "s"), opened("r", "s")
    master.write(TEST_STAT(counter=1))
    with pytest.raises(NmlFormatError, match="holds a 90002 message, not TEST_CMD"):
        reader.peek_into(TEST_CMD())
    start = master.layout.data_offset
    master._mm[start : start + 4] = b"\x99\x99\x00\x00"
    with pytest.raises(NmlFormatError, match="unknown message type 39321"):
        reader.peek_into(TEST_STAT())


def test_a_write_can_wait_longer_than_its_p_line_says(opened) -> None:
    master = opened("m", "q")
    impatient = opened("w", "q")  # P-line timeout 0
    holder = hold_lock(master, 0.2)
    with pytest.raises(NmlTimeoutError):
        impatient.write(TEST_CMD())
    assert impatient.write(TEST_CMD(index=8), timeout=5) > 0  # waits for the lock
    assert master.read().index == 8
    holder.join()


class HandlerError(Exception):
    """What the tests' signal handler raises, as Ctrl-C's raises KeyboardInterrupt."""


def raise_handler_error(*_: object) -> None:
    raise HandlerError


class SignalledAsTaken:
    """A buffer's mutex whose every acquire is followed by ``send()``: a signal arriving
    just as the mutex is taken."""

    def __init__(self, mutex: object, send: Callable[[], None]) -> None:
        self.mutex, self.send = mutex, send

    def acquire(self, timeout: float | None = None) -> None:
        self.mutex.acquire(timeout)
        self.send()

    def __getattr__(self, name: str) -> object:
        return getattr(self.mutex, name)


@contextlib.contextmanager
def signal_raising_as_taken(buffer: ShmBuffer, send: Callable[[], None]) -> Iterator[None]:
    """SIGUSR1's handler raises HandlerError, sent by ``send`` as ``buffer``'s mutex is
    taken; the handler's exception must come out of the block."""
    mutex = buffer._mutex
    previous = signal.signal(signal.SIGUSR1, raise_handler_error)
    buffer._mutex = SignalledAsTaken(mutex, send)
    try:
        with pytest.raises(HandlerError):
            yield
    finally:
        signal.signal(signal.SIGUSR1, previous)
        buffer._mutex = mutex


def test_a_handler_raising_as_the_mutex_is_taken_runs_once_it_is_free(opened) -> None:
    """A signal to this thread, whose handler raises, arriving as the mutex is taken, is
    held back until the write is done and the mutex free (it left the mutex taken by this
    live process)."""
    master, reader = opened("m", "q"), opened("r", "q")
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ())
    me = threading.get_ident()
    with signal_raising_as_taken(master, lambda: signal.pthread_kill(me, signal.SIGUSR1)):
        master.write(TEST_CMD(index=3))
    assert master._mutex.value == 1 and master.lock_holder() is None  # free
    assert reader.read().index == 3  # written before the handler ran
    assert signal.pthread_sigmask(signal.SIG_BLOCK, ()) == mask  # nothing left held back


def test_a_handler_raising_as_another_thread_takes_the_signal_frees_the_mutex(opened) -> None:
    """In a threaded process another thread can take the signal; the main thread runs its
    handler as the wait for the mutex returns. The write is given up, the mutex freed."""
    master, reader = opened("m", "q"), opened("r", "q")
    is_done = threading.Event()
    other = threading.Thread(target=is_done.wait)  # started here: its signals are not held back
    other.start()

    def send_to_the_other_thread() -> None:
        signal.pthread_kill(other.ident, signal.SIGUSR1)
        time.sleep(0.05)  # its handler trips; this thread runs the Python handler next

    try:
        with signal_raising_as_taken(master, send_to_the_other_thread):
            master.write(TEST_CMD(index=3))
    finally:
        is_done.set()
        other.join()
    assert master._mutex.value == 1 and master.lock_holder() is None  # free
    assert reader.read() is None
    master.write(TEST_CMD(index=4))
    assert reader.read().index == 4


def test_a_handler_raising_as_the_mutex_is_let_go_is_caught_up_with(opened) -> None:
    """A handler raising at the first bytecode of _unlock (in a threaded process) leaves the
    mutex taken; the thread's next lock of the buffer lets it go first, instead of waiting
    for itself."""
    master, reader = opened("m", "q"), opened("r", "q")
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ())
    unlock = master._unlock

    def unlock_interrupted() -> None:
        master._unlock = unlock  # once
        raise HandlerError

    master._unlock = unlock_interrupted
    with pytest.raises(HandlerError):
        master.write(TEST_CMD(index=1))
    assert master._mutex.value == 0  # left taken
    master.write(TEST_CMD(index=2))
    assert master._mutex.value == 1 and master.lock_holder() is None
    assert [reader.read().index, reader.read().index] == [1, 2]
    assert signal.pthread_sigmask(signal.SIG_BLOCK, ()) == mask


def test_a_signal_ends_a_wait_for_a_mutex_a_live_holder_keeps(opened) -> None:
    """Ctrl-C ends a wait for a stuck holder's mutex (signals are held back only while the
    mutex is held), and the mutex is the holder's until it lets it go."""
    master, writer = opened("m", "q"), opened("r", "q")
    holder = hold_lock(master, 1.5)
    previous = signal.signal(signal.SIGALRM, raise_handler_error)
    signal.setitimer(signal.ITIMER_REAL, 0.3)
    try:
        with pytest.raises(HandlerError):
            writer.write(TEST_CMD(index=4), timeout=30)
        assert master.lock_holder() is not None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        holder.join()
    assert master.lock_holder() is None
    writer.write(TEST_CMD(index=5))
    assert master.read().index == 5
