"""SHMEM buffers: POSIX shared memory guarded by POSIX named semaphores (NML-043..046).

One segment per buffer, created by the master process (NML-032), laid out as::

    header (128 bytes)  | connection slots (16 bytes x max_procs) | data area

Two kinds, chosen by the B line's ``queue`` option:

- **latest value** (status): one message. Writers serialise on the buffer's mutex semaphore
  and publish under a sequence counter (seqlock): the counter is odd while a write is in
  progress, and a reader retries until it has copied the message between two equal even
  values. Readers therefore never see a torn write and never take the mutex, so any number
  of UIs can poll status without ever delaying the writer.
- **queue** (commands, errors): a FIFO ring of variable-length records, read and written
  under the mutex. A message is consumed by exactly one read; a writer that finds no room
  waits up to its timeout, then fails (NML-019).

Blocking: each connection slot has its own wake semaphore. A process that wants to wait for
data (or for room) marks its slot as waiting under the mutex and sleeps on its semaphore;
whoever changes the buffer posts every waiting slot. No polling loop.

Robustness: the mutex holder's pid is recorded. A waiter that cannot get the mutex checks
whether the holder still lives; if it died, the waiter repairs the buffer (an interrupted
status write is discarded, a queue is consistent by construction because the tail moves
last) and releases the mutex, logging what happened. A live holder never keeps it by accident:
signals are held back while a thread holds it, and a handler's exception (Ctrl-C's
KeyboardInterrupt, a SIGTERM handler's SystemExit) that lands there anyway, from a signal
another thread took, frees it (see _HELD_BACK_SIGNALS). Corrupt content raises
``NmlFormatError`` naming the buffer and never crashes the reader.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import math
import mmap
import os
import signal
import struct
import threading
import time
from dataclasses import dataclass

import posix_ipc

from nml.codec import HEADER, Encoding, decode, encode
from nml.config import BufferConfig, ProcessConfig, describe_timeout
from nml.errors import NmlAccessError, NmlFormatError, NmlTimeoutError
from nml.ipcnames import ipc_name
from nml.message import RCS_CMD_MSG, NMLmsg

log = logging.getLogger("nml")

MAGIC = 0x314C4D4E  # "NML1"
LAYOUT_VERSION = 4
KIND_LATEST, KIND_QUEUE = 0, 1
WRAP = 0xFFFFFFFF
_LOCK_SLICE_S = 0.2  # how often a waiter for the mutex checks that its holder is alive
# A live process holding the mutex longer than this is reported (once per episode) with its
# pid: a stuck process (SIGSTOP, a debugger) that blocks everyone else.
LOCK_HELD_REPORT_S = 1.0
# A status write that stays "in progress" this long with nobody holding the mutex was not
# a write: the sequence counter is corrupt, and the reader resets the buffer.
_STUCK_WRITE_S = 0.05

# Signals held back while this thread holds a buffer's mutex. A Python signal handler runs
# between two bytecodes of the main thread and may raise (Ctrl-C's KeyboardInterrupt): raised
# just after the mutex was taken, before the code that releases it, it leaves the mutex taken
# by a live process. A UI that goes on after Ctrl-C (``cnc sh``) then waits for itself forever
# at its next read, and every other process (task writing an error) waits for it. Held back,
# a signal is delivered when the mutex is released, outside the critical section. The faults
# a thread raises itself (SIGSEGV...) and SIGABRT (faulthandler's dump) stay deliverable.
# Another thread of the process (numpy's BLAS threads) may take a signal meant for the
# process while this one holds it back, and the main thread then runs the handler between
# any two bytecodes: so the wait for the mutex also frees it when a handler raises as it
# returns, and a handler raising as the thread lets the mutex go is caught up with at that
# thread's next lock (see _lock).
_HELD_BACK_SIGNALS = frozenset(signal.valid_signals()) - {
    signal.SIGKILL,
    signal.SIGSTOP,
    signal.SIGSEGV,
    signal.SIGBUS,
    signal.SIGFPE,
    signal.SIGILL,
    signal.SIGTRAP,
    signal.SIGSYS,
    signal.SIGABRT,
}
# libc's pthread_sigmask: signal.pthread_sigmask turns every mask it returns into a set of
# enum members, ~110 us for a lock and unlock holding back this many signals; this is 2-5 us.
_pthread_sigmask = ctypes.CDLL(None, use_errno=True).pthread_sigmask
_SigSet = ctypes.c_uint64 * 16  # glibc's sigset_t (signal n is bit n - 1 of word 0)
_SIG_BLOCK, _SIG_UNBLOCK = 0, 1
_HELD_BACK_BITS = sum(1 << (number - 1) for number in _HELD_BACK_SIGNALS)
_HELD_BACK_SET = _SigSet(_HELD_BACK_BITS)


def _hold_back_signals() -> int:
    """Block _HELD_BACK_SIGNALS in this thread; the bits of those this call blocked."""
    before = _SigSet()
    _pthread_sigmask(_SIG_BLOCK, _HELD_BACK_SET, before)
    return _HELD_BACK_BITS & ~before[0]


def _let_signals_through(bits: int) -> None:
    """Unblock the signals ``_hold_back_signals`` blocked: a pending one is delivered now."""
    if bits:
        _pthread_sigmask(_SIG_UNBLOCK, _SigSet(bits), None)


# Header fields: name -> (offset, struct format). All offsets are 8-byte aligned.
_HEADER_FIELDS = {
    "magic": (0, "<I"),
    "version": (4, "<I"),
    "kind": (8, "<I"),
    "encoding": (12, "<I"),
    "capacity": (16, "<Q"),
    "max_procs": (24, "<I"),
    "buffer_number": (28, "<I"),
    "creator_pid": (32, "<q"),
    "holder_pid": (40, "<q"),
    "seq": (48, "<Q"),
    "write_count": (56, "<Q"),
    "latest_len": (64, "<Q"),
    "read_count": (72, "<Q"),
    "head": (80, "<Q"),
    "tail": (88, "<Q"),
    "used": (96, "<Q"),
    "count": (104, "<Q"),
    "next_serial": (112, "<Q"),
    "locked_at": (120, "<Q"),  # monotonic ns when the holder took the mutex
}
HEADER_SIZE = 128
# Connection slot fields: name -> (offset in the slot, struct format).
_SLOT_FIELDS = {
    "pid": (0, "<i"),
    "c_num": (4, "<i"),
    "is_waiting": (8, "<I"),  # sleeping on its wake semaphore
    "is_reader": (12, "<I"),  # holds broadcast messages until it has read them
    "cursor": (16, "<Q"),  # broadcast: sequence number of the last message it read
    "missed": (24, "<I"),  # broadcast: messages dropped before it read them (queue full)
}
SLOT_SIZE = 32
# (code of the typed view, item index) of each header field, and (offset, code, item size)
# of each slot field: see ShmBuffer._map
_FIELD_CODES = ("I", "Q", "q", "i")
_HEADER_INDEX = {
    key: (fmt[1], offset // struct.calcsize(fmt)) for key, (offset, fmt) in _HEADER_FIELDS.items()
}
_SLOT_INDEX = {
    key: (offset, fmt[1], struct.calcsize(fmt)) for key, (offset, fmt) in _SLOT_FIELDS.items()
}
_SEQ_INDEX = _HEADER_INDEX["seq"][1]
_WRITE_COUNT_INDEX = _HEADER_INDEX["write_count"][1]
_LATEST_LEN_INDEX = _HEADER_INDEX["latest_len"][1]
RECORD = struct.Struct("<IIQ")  # queue record: length, reserved, sequence number
_IDENTITY = struct.Struct("<II")  # magic, version at offset 0


# this process's pid, kept up to date across fork: getpid is a system call, and a lock
# records its holder on every read and write
_pid = os.getpid()


def _refresh_pid() -> None:
    global _pid
    _pid = os.getpid()


os.register_at_fork(after_in_child=_refresh_pid)


def _slot_field_struct(key: str, slots: int) -> struct.Struct:
    """A struct that reads field ``key`` of every slot at once, from the first slot on."""
    offset, fmt = _SLOT_FIELDS[key]
    size = struct.calcsize(fmt)
    return struct.Struct("<" + f"{offset}x{fmt[1:]}{SLOT_SIZE - offset - size}x" * slots)


def _align8(n: int) -> int:
    return (n + 7) & ~7


PID_MAX = 1 << 22  # Linux's largest pid_max: anything above is not a pid (garbage)


def is_process_alive(pid: int) -> bool:
    if not 0 < pid <= PID_MAX:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@dataclass(frozen=True)
class BufferLayout:
    """Where things are in a buffer's segment. The B line's ``size`` is all for messages: the
    header and connection slots come on top, so LinuxCNC's own sizes keep their meaning."""

    size: int
    max_procs: int

    @property
    def slots_offset(self) -> int:
        return HEADER_SIZE

    @property
    def data_offset(self) -> int:
        return _align8(HEADER_SIZE + SLOT_SIZE * self.max_procs)

    @property
    def capacity(self) -> int:
        return max(0, self.size & ~7)

    @property
    def segment_size(self) -> int:
        return self.data_offset + self.capacity

    @staticmethod
    def bytes_needed(buffer: BufferConfig, largest_message: int) -> int:
        """The smallest B-line size that holds ``largest_message`` encoded bytes."""
        return largest_message + (RECORD.size + 7 if buffer.is_queue else 0)


class ShmBuffer:
    """One process's connection to one SHMEM buffer (the CMS of NML-046)."""

    def __init__(
        self,
        buffer: BufferConfig,
        process: ProcessConfig,
        *,
        is_observer: bool = False,
        lock_timeout: float | None = None,
    ) -> None:
        """Create (master) or attach to a buffer. An observer (``cnc nml ls``/``dump``) takes
        no connection slot and only looks: peek, stats, queued. ``lock_timeout`` replaces
        the P line's for taking a connection slot (under the buffer's lock, which a stuck
        process may hold)."""
        self.config = buffer
        self.process = process
        self.name = buffer.name
        self.layout = BufferLayout(buffer.size, buffer.max_procs)
        # every slot's is_waiting flag in one read (a write and a read check them all)
        self._waiting_flags = _slot_field_struct("is_waiting", buffer.max_procs)
        self.encoding = Encoding.from_neut(buffer.is_neutral)
        self.is_queue = buffer.is_queue
        self.is_broadcast = buffer.is_broadcast
        self.is_master = process.is_master
        self.timeout = process.timeout
        self._shm_name = ipc_name("shm", buffer.name)
        self._mutex_name = ipc_name("mutex", buffer.name)
        self._repair_name = ipc_name("repair", buffer.name)
        self._wake: dict[int, posix_ipc.Semaphore] = {}
        self._slot = -1
        self._last_seen = 0
        self._is_locked = False
        self._held_back = 0  # the signals _lock held back, let through by _unlock
        self._locking_thread = 0  # the thread that holds the mutex (while _is_locked)
        self._reported_holder = 0  # the stuck lock holder last logged
        self._mm: mmap.mmap | None = None
        self._view: memoryview | None = None
        if self.is_master:
            self._create()
        else:
            self._attach()
        if is_observer:
            return
        try:
            self._claim_slot(lock_timeout)
        except BaseException:
            self._release_resources(is_unlinking=self.is_master)
            raise

    # ------------------------------------------------------------------ lifecycle
    def _create(self) -> None:
        try:
            shm = posix_ipc.SharedMemory(
                self._shm_name, posix_ipc.O_CREX, mode=0o660, size=self.layout.segment_size
            )
        except posix_ipc.ExistentialError:
            self._remove_stale_segment()
            shm = posix_ipc.SharedMemory(
                self._shm_name, posix_ipc.O_CREX, mode=0o660, size=self.layout.segment_size
            )
        self._map(shm)
        for name in (self._mutex_name, self._repair_name):
            with contextlib.suppress(posix_ipc.ExistentialError):
                posix_ipc.unlink_semaphore(name)
        self._mutex = posix_ipc.Semaphore(self._mutex_name, posix_ipc.O_CREX, 0o660, 1)
        self._repair = posix_ipc.Semaphore(self._repair_name, posix_ipc.O_CREX, 0o660, 1)
        self._put("creator_pid", os.getpid())
        self._write_identity()  # magic last: attachers wait for it

    def _remove_stale_segment(self) -> None:
        """A segment with our name exists: reuse its name only if its creator is gone."""
        try:
            shm = posix_ipc.SharedMemory(self._shm_name)
            with mmap.mmap(shm.fd, HEADER_SIZE) as mm:
                creator = struct.unpack_from("<q", mm, _HEADER_FIELDS["creator_pid"][0])[0]
            shm.close_fd()
        except (posix_ipc.ExistentialError, ValueError, OSError):
            creator = 0
        if creator != os.getpid() and is_process_alive(creator):
            raise NmlAccessError(
                f"{self.config.where}: buffer {self.name} already exists and its master "
                f"(pid {creator}) is running: is another instance of this machine up?"
            )
        log.warning(
            "buffer %s: removing a stale segment left by pid %s, which is gone", self.name, creator
        )
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(self._shm_name)

    def _attach(self) -> None:
        deadline = None if math.isinf(self.timeout) else time.monotonic() + self.timeout
        delay = 0.001
        while True:
            problem = self._try_attach()
            if problem is None:
                return
            if deadline is not None and time.monotonic() >= deadline:
                raise NmlAccessError(
                    f"buffer {self.name}: {problem} after waiting "
                    f"{describe_timeout(self.timeout)} (is its master process running?)"
                )
            time.sleep(delay)
            delay = min(delay * 2, 0.05)

    def _try_attach(self) -> str | None:
        try:
            shm = posix_ipc.SharedMemory(self._shm_name)
        except posix_ipc.ExistentialError:
            return "shared memory segment does not exist"
        if shm.size < self.layout.segment_size:
            shm.close_fd()
            return f"segment is {shm.size} bytes, expected {self.layout.segment_size}"
        self._map(shm)
        if self._get("magic") != MAGIC:
            self._unmap()
            return "segment is not initialised"
        mismatch = self._layout_mismatch()
        if mismatch:
            self._unmap()
            raise NmlAccessError(f"buffer {self.name}: {mismatch} (created from another NML file?)")
        try:
            self._mutex = posix_ipc.Semaphore(self._mutex_name)
            self._repair = posix_ipc.Semaphore(self._repair_name)
        except posix_ipc.ExistentialError:
            self._unmap()
            return "semaphores do not exist"
        return None

    def _layout_mismatch(self) -> str | None:
        expected = {
            "version": LAYOUT_VERSION,
            "kind": KIND_QUEUE if self.is_queue else KIND_LATEST,
            "encoding": int(self.encoding),
            "capacity": self.layout.capacity,
            "max_procs": self.config.max_procs,
        }
        for key, value in expected.items():
            actual = self._get(key)
            if actual != value:
                return f"segment has {key}={actual}, expected {value}"
        return None

    def _map(self, shm: posix_ipc.SharedMemory) -> None:
        self._mm = mmap.mmap(shm.fd, self.layout.segment_size)
        shm.close_fd()
        self._view = memoryview(self._mm)
        # Header and slot fields are read and written whole, one aligned load or store,
        # through these typed views: struct.pack_into zeroes a field before writing it, and
        # a reader without the lock (status, has_new_data) would see the zeros.
        self._typed = {code: self._view.cast(code) for code in _FIELD_CODES}

    def _unmap(self) -> None:
        for typed in getattr(self, "_typed", {}).values():
            typed.release()
        self._typed = {}
        if self._view is not None:
            self._view.release()
            self._view = None
        if self._mm is not None:
            self._mm.close()
            self._mm = None

    def close(self) -> None:
        """Detach; the master also removes the segment and semaphores (ARCH-011)."""
        if self._mm is None:
            return
        if self._slot >= 0:
            with contextlib.suppress(NmlTimeoutError, ValueError):
                self._lock(timeout=1.0)
                try:
                    self._slot_clear(self._slot)
                finally:
                    self._unlock()
        self._release_resources(is_unlinking=self.is_master)

    def _release_resources(self, is_unlinking: bool) -> None:
        self._unmap()
        for sem in self._wake.values():
            sem.close()
        self._wake.clear()
        for attr in ("_mutex", "_repair"):
            sem = getattr(self, attr, None)
            if sem is not None:
                sem.close()
                setattr(self, attr, None)
        if is_unlinking:
            with contextlib.suppress(posix_ipc.ExistentialError):
                posix_ipc.unlink_shared_memory(self._shm_name)
            for name in [self._mutex_name, self._repair_name] + [
                self._wake_name(i) for i in range(self.config.max_procs)
            ]:
                with contextlib.suppress(posix_ipc.ExistentialError):
                    posix_ipc.unlink_semaphore(name)

    def __enter__(self) -> ShmBuffer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ header access
    def _get(self, key: str) -> int:
        code, index = _HEADER_INDEX[key]
        return self._typed[code][index]

    def _put(self, key: str, value: int) -> None:
        code, index = _HEADER_INDEX[key]
        self._typed[code][index] = value

    def _slot_offset(self, index: int) -> int:
        return self.layout.slots_offset + index * SLOT_SIZE

    def _slot_get(self, index: int, key: str) -> int:
        offset, code, size = _SLOT_INDEX[key]
        return self._typed[code][(self._slot_offset(index) + offset) // size]

    def _slot_put(self, index: int, key: str, value: int) -> None:
        offset, code, size = _SLOT_INDEX[key]
        self._typed[code][(self._slot_offset(index) + offset) // size] = value

    def _slot_clear(self, index: int) -> None:
        start = self._slot_offset(index)
        self._mm[start : start + SLOT_SIZE] = bytes(SLOT_SIZE)  # type: ignore[index]

    def _wake_name(self, index: int) -> str:
        return ipc_name("wake", f"{self.name}.{index}")

    def _wake_sem(self, index: int) -> posix_ipc.Semaphore:
        sem = self._wake.get(index)
        if sem is None:
            sem = posix_ipc.Semaphore(self._wake_name(index), posix_ipc.O_CREAT, 0o660, 0)
            self._wake[index] = sem
        return sem

    # ------------------------------------------------------------------ connections
    def _claim_slot(self, lock_timeout: float | None = None) -> None:
        """Take a connection slot; refuse a process beyond max_procs (NML-010)."""
        self._lock(lock_timeout)
        try:
            free, live = -1, []
            for index in range(self.config.max_procs):
                pid = self._slot_get(index, "pid")
                if pid and not is_process_alive(pid):
                    log.warning(
                        "buffer %s: freeing the slot of pid %d, which died attached", self.name, pid
                    )
                    self._slot_clear(index)
                    pid = 0
                if pid:
                    live.append(pid)
                elif free < 0:
                    free = index
            if free < 0:
                raise NmlAccessError(
                    f"buffer {self.name}: already {self.config.max_procs} connections (max_procs), "
                    f"pids {', '.join(map(str, live))}; process {self.process.name} refused"
                )
            self._slot_clear(free)
            self._slot_put(free, "pid", os.getpid())
            self._slot_put(free, "c_num", self.process.c_num)
            self._slot = free
            if self.is_broadcast and self.process.can_read:
                self._register_broadcast_reader()
        finally:
            self._unlock()
        sem = self._wake_sem(free)
        while _try_acquire(sem):  # drop wake-ups meant for a previous owner of the slot
            pass
        self._last_seen = self._get("write_count")

    def is_orphaned(self) -> bool:
        """The master that made this buffer is gone: what it holds is left over. (A
        creator pid that is no pid at all is garbage, not a verdict: the master rewrites
        it, see ``claim_as_master``.)"""
        self._require_open()
        creator = self._get("creator_pid")
        if not 0 < creator <= PID_MAX:
            return False
        return creator != os.getpid() and not is_process_alive(creator)

    def claim_as_master(self) -> bool:
        """The master's periodic check that the segment still names it as its creator
        (garbage written over the header); rewrites it if not. True if it did."""
        self._require_open()
        if self._get("creator_pid") == os.getpid():
            return False
        self._put("creator_pid", os.getpid())
        return True

    def connections(self) -> list[tuple[int, int]]:
        """(pid, c_num) of every process attached now."""
        self._require_open()
        found = []
        for index in range(self.config.max_procs):
            pid = self._slot_get(index, "pid")
            if pid:
                found.append((pid, self._slot_get(index, "c_num")))
        return found

    # ------------------------------------------------------------------ mutex
    def _lock(self, timeout: float | None = None) -> None:
        """Take the mutex within the P-line timeout (NML-031), repairing after dead holders;
        a live holder that keeps it past LOCK_HELD_REPORT_S is logged with its pid. Signals
        are held back until ``_unlock`` (see _HELD_BACK_SIGNALS)."""
        me = threading.get_ident()
        if self._is_locked and self._locking_thread == me:
            self._unlock()  # a handler raised as this thread began to let it go
        limit = self.timeout if timeout is None else timeout
        deadline = None if math.isinf(limit) else time.monotonic() + limit
        held_back = _HELD_BACK_BITS  # (if a handler raises as they are blocked: all)
        try:
            held_back = _hold_back_signals()
            self._acquire_mutex(limit, deadline, held_back)
        except BaseException:
            _let_signals_through(held_back)
            raise
        # (plain assignments from here: a handler runs at calls and jumps back, not here)
        self._held_back = held_back
        self._locking_thread = me
        self._is_locked = True

    def _acquire_mutex(self, limit: float, deadline: float | None, held_back: int) -> None:
        while True:
            wait = _LOCK_SLICE_S
            if deadline is not None:
                wait = max(0.0, min(wait, deadline - time.monotonic()))
            try:
                self._mutex.acquire(wait)
            except posix_ipc.SignalError:
                continue  # interrupted by a signal whose handler has run: wait again
            except posix_ipc.BusyError:
                # Not holding it, this thread may take its signals: Ctrl-C ends a wait
                # for a stuck holder.
                _let_signals_through(held_back)
                _hold_back_signals()
                if self._repair_after_dead_holder():
                    continue
                holder = self.lock_holder()
                if holder is not None and holder[1] >= LOCK_HELD_REPORT_S:
                    self._report_stuck_holder(*holder)
                if deadline is not None and time.monotonic() >= deadline:
                    raise NmlTimeoutError(
                        f"buffer {self.name}: busy for {describe_timeout(limit)} "
                        f"({self._describe_holder()})"
                    ) from None
                continue
            except (posix_ipc.Error, OSError):
                raise  # the wait failed (the semaphore is gone): not taken
            except BaseException:
                # Only a handler run as the wait returned raises anything else (this thread
                # cannot be interrupted by a held-back signal, but another thread of the
                # process can receive it and the main thread then runs its handler): the
                # wait had succeeded.
                self._mutex.release()
                raise
            try:
                self._put("holder_pid", _pid)
                self._put("locked_at", time.monotonic_ns())
            except BaseException:
                self._mutex.release()
                raise
            return

    def lock_holder(self) -> tuple[int, float] | None:
        """(pid, seconds held) of the process holding the mutex, or None if it is free."""
        self._require_open()
        pid = self._get("holder_pid")
        if pid <= 0:
            return None
        return pid, max(time.monotonic_ns() - self._get("locked_at"), 0) / 1e9

    def _describe_holder(self) -> str:
        holder = self.lock_holder()
        if holder is None:
            return "no holder recorded"
        pid, held = holder
        return f"held by pid {pid} ({_process_name(pid)}) for {held:.1f} s"

    def _report_stuck_holder(self, pid: int, held: float) -> None:
        if self._reported_holder != pid:
            self._reported_holder = pid
            log.warning(
                "buffer %s: pid %d (%s) has held the lock for %.1f s: a stuck process",
                self.name,
                pid,
                _process_name(pid),
                held,
            )

    def _unlock(self) -> None:
        try:
            self._put("holder_pid", 0)
        finally:
            self._is_locked = False
            self._mutex.release()
            _let_signals_through(self._held_back)

    def _repair_after_dead_holder(self) -> bool:
        """If the mutex holder died, repair the buffer and free the mutex; True if done."""
        holder = self._get("holder_pid")
        if holder <= 0 or is_process_alive(holder):
            return False
        if not _try_acquire(self._repair, 0.05):
            return False
        try:
            if self._get("holder_pid") != holder or self._mutex.value != 0:
                return False  # somebody else repaired it meanwhile
            message = f"buffer {self.name}: pid {holder} died holding the lock; recovered"
            if not self.is_queue and self._get("seq") % 2:
                self._put("latest_len", 0)
                self._put("seq", self._get("seq") + 1)
                message += " (its unfinished status write was discarded)"
            log.error(message)
            self._put("holder_pid", 0)
            self._mutex.release()
            return True
        finally:
            self._repair.release()

    # ------------------------------------------------------------------ waking
    def _wake_waiters(self) -> None:
        """Post every slot marked waiting (called with the mutex held)."""
        flags = self._waiting_flags.unpack_from(self._mm, self.layout.slots_offset)  # type: ignore[arg-type]
        if not any(flags):
            return
        for index, is_waiting in enumerate(flags):
            if is_waiting:
                self._slot_put(index, "is_waiting", 0)
                self._wake_sem(index).release()

    def _wait_for_change(self, is_ready, deadline: float | None) -> bool:  # type: ignore[no-untyped-def]
        """Sleep until ``is_ready()`` (checked under the mutex) or the deadline; True if ready."""
        if self._slot < 0:
            raise NmlAccessError(f"buffer {self.name}: an observer cannot wait for messages")
        sem = self._wake_sem(self._slot)
        while True:
            # The lock is part of this wait: it gets the caller's time, not the P line's.
            remaining = math.inf if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                self._lock(timeout=remaining)
            except NmlTimeoutError:
                return False
            try:
                if is_ready():
                    return True
                while _try_acquire(sem):
                    pass
                self._slot_put(self._slot, "is_waiting", 1)
            finally:
                self._unlock()
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                return False
            woke = _try_acquire(sem, remaining)
            if not woke:
                self._slot_put(self._slot, "is_waiting", 0)
                return is_ready()

    # ------------------------------------------------------------------ write
    def write(
        self, msg: NMLmsg, timeout: float | None = None, *, is_oldest_dropped: bool = False
    ) -> int:
        """Write a message; returns the serial number given to a command, else 0.

        Commands get the next serial number of this buffer, assigned under the mutex, so two
        writers can never produce the same number (NML-041). ``timeout`` (seconds, < 0
        forever) replaces the P line's for this write. A full queue makes the write wait for
        room, up to the timeout; with ``is_oldest_dropped`` the oldest messages make room
        instead, at once: for operator messages, which nobody may be reading (a headless
        machine), the newest are the ones to keep, and the writer must not stall.
        """
        wait_s = self.timeout if timeout is None else (math.inf if timeout < 0 else timeout)
        self._require_open()
        if not self.process.can_write:
            raise NmlAccessError(
                f"process {self.process.name} may not write buffer {self.name} "
                f"(ops {self.process.ops})"
            )
        is_command = isinstance(msg, RCS_CMD_MSG)
        data = encode(msg, self.encoding)
        limit = self.layout.capacity - (RECORD.size if self.is_queue else 0)
        if len(data) > limit:
            raise NmlFormatError(
                f"buffer {self.name}: {msg.NAME} is {len(data)} bytes encoded, more than the "
                f"{limit} the buffer holds (raise its size in the NML file)"
            )
        deadline = None if math.isinf(wait_s) else time.monotonic() + wait_s
        self._lock(wait_s)
        try:
            problem = self._repair_if_corrupt()
            if problem:
                log.error("%s", problem)  # (a writer carries on: its message goes in)
            serial = 0
            if is_command:
                serial = self._get("next_serial") + 1 & 0x7FFFFFFF or 1
                self._put("next_serial", serial)
                msg.serial_number = serial
                data = encode(msg, self.encoding)
            if self.is_queue:
                if self.is_broadcast:
                    self._trim_broadcast()
                while not self._queue_has_room(len(data)):
                    if is_oldest_dropped and self._get("count"):
                        self._drop_oldest()
                        continue
                    self._unlock()
                    if not self._wait_for_change(lambda: self._queue_has_room(len(data)), deadline):
                        raise NmlTimeoutError(
                            f"buffer {self.name}: queue full ({self._get('count')} messages) for "
                            f"{describe_timeout(wait_s)}; {msg.NAME} not written"
                        )
                    self._lock(wait_s)
                self._queue_put(data)
            else:
                self._latest_put(data)
            self._wake_waiters()
            return serial
        finally:
            if self._is_locked:
                self._unlock()

    def _latest_put(self, data: bytes) -> None:
        seq = self._get("seq") & ~1  # (even unless corrupt: a write is never in progress here)
        self._put("seq", seq + 1)  # odd: write in progress
        start = self.layout.data_offset
        self._mm[start : start + len(data)] = data  # type: ignore[index]
        self._put("latest_len", len(data))
        self._put("write_count", self._get("write_count") + 1)
        self._put("seq", seq + 2)

    def _queue_has_room(self, length: int) -> bool:
        need = RECORD.size + _align8(length)
        capacity = self.layout.capacity
        if self._get("count") == 0:
            return need <= capacity
        head, tail = self._get("head"), self._get("tail")
        if tail > head:
            return capacity - tail >= need or head >= need
        return head - tail >= need

    def _queue_put(self, data: bytes) -> None:
        need = RECORD.size + _align8(len(data))
        capacity = self.layout.capacity
        base = self.layout.data_offset
        if self._get("count") == 0:
            head = tail = used = 0
            self._put("head", 0)
        else:
            head, tail, used = self._get("head"), self._get("tail"), self._get("used")
        if tail >= head and capacity - tail < need:
            RECORD.pack_into(self._mm, base + tail, WRAP, 0, 0)
            used += capacity - tail
            tail = 0
        sequence = self._get("write_count") + 1
        RECORD.pack_into(self._mm, base + tail, len(data), 0, sequence)
        start = base + tail + RECORD.size
        self._mm[start : start + len(data)] = data  # type: ignore[index]
        self._put("used", used + need)
        self._put("count", self._get("count") + 1)
        self._put("write_count", sequence)
        self._put("tail", (tail + need) % capacity)  # last: commits the record

    # ------------------------------------------------------------------ read
    def read(self) -> NMLmsg | None:
        """A new message, or None: the oldest queued one (removed), or the status if it
        changed since this connection last read it."""
        return self._read(lock_timeout=None)

    def _read(self, lock_timeout: float | None) -> NMLmsg | None:
        self._require_readable()
        if self.is_queue:
            if self._slot < 0:
                raise NmlAccessError(f"buffer {self.name}: an observer cannot consume messages")
            return self._queue_take(is_consuming=True, lock_timeout=lock_timeout)
        data, count = self._latest_bytes()
        if data is None or count == self._last_seen:
            return None
        self._last_seen = count
        return self._decode_status(data)

    def peek(self) -> NMLmsg | None:
        """The current status (new or not) or the oldest queued message, not removed."""
        self._require_readable()
        if self.is_queue:
            return self._queue_take(is_consuming=False)
        data, _ = self._latest_bytes()
        return None if data is None else self._decode_status(data)

    def _decode_status(self, data: bytes | bytearray) -> NMLmsg:
        """A status message; one that cannot be decoded is reset (see _reset_corrupt)."""
        try:
            return decode(data, f"buffer {self.name}")
        except NmlFormatError as exc:
            raise self._reset_corrupt(str(exc)) from None

    def peek_into(self, msg: NMLmsg, target: memoryview | None = None) -> bool:
        """Copy the current status into ``msg`` in place, as LinuxCNC's stat.poll() copies
        into its struct: no allocation. ``target`` is ``msg.byte_view()``, cached by a
        caller that polls often. False if nothing was published yet; the header is checked
        as ``decode`` checks it."""
        self._require_readable()
        if self.is_queue or self.encoding is not Encoding.FIXED:
            found = self.peek()
            if found is None:
                return False
            if type(found) is not type(msg):
                raise NmlFormatError(f"buffer {self.name}: holds {found.NAME}, not {msg.NAME}")
            msg._arr[...] = found._arr
            return True
        target = msg.byte_view() if target is None else target
        mm, view, words = self._mm, self._view, self._typed["Q"]
        start = self.layout.data_offset
        expected = (msg.TYPE, msg.dtype.itemsize, msg.layout_crc, Encoding.FIXED)
        length_needed = HEADER.size + msg.dtype.itemsize
        spins = 0
        while True:
            seq, length = words[_SEQ_INDEX], words[_LATEST_LEN_INDEX]
            if not seq & 1:
                header = HEADER.unpack_from(mm, start) if length else None  # type: ignore[arg-type]
                if header == expected and length == length_needed:
                    target[:] = view[start + HEADER.size : start + length_needed]  # type: ignore[index]
                if words[_SEQ_INDEX] == seq:
                    if not length:
                        return False
                    if header != expected or length != length_needed:
                        self._decode_status(
                            bytes(view[start : start + min(length, self.layout.capacity)])  # type: ignore[index]
                        )  # raises the precise error
                        raise NmlFormatError(
                            f"buffer {self.name}: holds a {header[0]} message, not {msg.NAME}"
                        )
                    return True
            spins += 1
            if spins > 100:
                self._wait_for_status_write(spins)

    def _wait_for_status_write(self, spins: int) -> None:
        """A reader found a status write in progress for a while: sleep a little; repair
        after a writer that died mid-write; and a write "in progress" with nobody holding
        the mutex is a corrupt sequence counter, which is reset (NmlFormatError)."""
        time.sleep(0.0001)
        if spins % 100:
            return
        if self._repair_after_dead_holder():
            return
        if spins * 0.0001 >= _STUCK_WRITE_S and self._get("holder_pid") == 0:
            raise self._reset_corrupt(
                f"buffer {self.name}: a status write never finished (corrupt sequence counter)"
            )

    def _reset_corrupt(self, problem: str) -> NmlFormatError:
        """A reader found ``problem``: repair the buffer (header rewritten, content
        dropped) if it can take the mutex at once, and return the error to raise, so
        each corruption is reported once and the next read finds a sound buffer."""
        try:
            self._lock(timeout=0.05)
        except NmlTimeoutError:
            return NmlFormatError(problem)
        try:
            repaired = self._repair_if_corrupt()
            if not repaired:
                if self.is_queue:
                    repaired = self._discard_all()
                else:
                    self._put("latest_len", 0)
                    self._put("seq", (self._get("seq") | 1) + 1)
                    repaired = "its content was discarded until the next write"
            return NmlFormatError(f"{problem}; {repaired}")
        finally:
            self._unlock()

    def blocking_read(self, timeout: float) -> NMLmsg | None:
        """Wait for a new message up to ``timeout`` s (< 0: forever, 0: don't wait). The whole
        wait, taking the lock included, follows this timeout rather than the P line's."""
        deadline = None if timeout < 0 or math.isinf(timeout) else time.monotonic() + timeout
        while True:
            if not self._wait_for_change(self._has_new_data, deadline):
                return None
            remaining = math.inf if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                msg = self._read(lock_timeout=remaining)
            except NmlTimeoutError:
                return None
            if msg is not None:
                return msg

    def has_new_data(self) -> bool:
        self._require_open()
        return self._has_new_data()

    def write_count(self) -> int:
        """How many messages were ever written here: a status buffer's change counter (the
        same count, the same status), read without the lock."""
        self._require_open()
        return self._get("write_count")

    def _has_new_data(self) -> bool:
        if self.is_broadcast and self._slot >= 0:
            return self._get("write_count") > self._slot_get(self._slot, "cursor")
        if self.is_queue:
            return self._get("count") > 0
        return self._get("write_count") != self._last_seen

    def _latest_bytes(self) -> tuple[bytearray | None, int]:
        """Copy the status message out between two equal even sequence numbers (seqlock)."""
        view, words = self._view, self._typed["Q"]
        start = self.layout.data_offset
        capacity = self.layout.capacity
        spins = 0
        while True:
            seq = words[_SEQ_INDEX]
            count, length = words[_WRITE_COUNT_INDEX], words[_LATEST_LEN_INDEX]
            if not seq & 1:
                if length > capacity:
                    if words[_SEQ_INDEX] == seq:
                        raise self._reset_corrupt(
                            f"buffer {self.name}: header claims a {length}-byte message in a "
                            f"{capacity}-byte buffer (corrupt)"
                        )
                    continue
                data = bytearray(view[start : start + length]) if length else None  # type: ignore[index]
                if words[_SEQ_INDEX] == seq:
                    return data, count
            spins += 1
            if spins > 100:
                self._wait_for_status_write(spins)

    def _queue_take(self, is_consuming: bool, lock_timeout: float | None = None) -> NMLmsg | None:
        """The next message for this connection: the oldest one, or in a broadcast queue the
        oldest this reader has not read yet. Consuming removes it (or moves the cursor).
        A corrupt queue (header, record or message) is reset and reported once, by the
        NmlFormatError of the read that found it."""
        self._lock(lock_timeout)
        try:
            problem = self._repair_if_corrupt()
            if problem:
                raise NmlFormatError(problem)
            cursor = self._slot_get(self._slot, "cursor") if self.is_broadcast else -1
            try:
                found = next((r for r in self._records() if r[2] > cursor), None)
            except NmlFormatError as exc:  # the records themselves are broken
                raise NmlFormatError(f"{exc} (corrupt); {self._discard_all()}") from None
            if found is None:
                return None
            offset, length, sequence = found
            start = self.layout.data_offset + offset + RECORD.size
            data = bytes(self._mm[start : start + length])  # type: ignore[index]
            if is_consuming:
                if cursor >= 0:
                    self._slot_put(self._slot, "cursor", sequence)
                    self._trim_broadcast()
                else:
                    self._queue_pop_front()
                self._wake_waiters()
        finally:
            self._unlock()
        return decode(data, f"buffer {self.name}")  # (a bad message is consumed all the same)

    def _discard_all(self) -> str:
        """Empty a corrupt queue (mutex held); says what was lost."""
        discarded = self._get("count")
        self._reset_queue()
        self._wake_waiters()  # writers waiting for room
        return f"{discarded} queued message(s) discarded"

    def _repair_if_corrupt(self) -> str | None:
        """With the mutex held: a header that cannot be right (garbage written into the
        segment) is rewritten from this connection's configuration and the content is
        dropped; returns what was wrong, for the caller to report, or None."""
        if _IDENTITY.unpack_from(self._mm, 0) != (MAGIC, LAYOUT_VERSION) or (  # type: ignore[arg-type]
            self._layout_mismatch() is not None
        ):
            magic, version = _IDENTITY.unpack_from(self._mm, 0)  # type: ignore[arg-type]
            self._write_identity()
            if self.is_queue:
                self._reset_queue()
            else:
                self._put("latest_len", 0)
                self._put("seq", (self._get("seq") | 1) + 1)
            return (
                f"buffer {self.name}: segment header was corrupt (magic {magic:#x}, "
                f"layout {version}); rewritten, its content discarded"
            )
        if not self.is_queue:
            return None
        capacity = self.layout.capacity
        head, tail, used, count = (self._get(k) for k in ("head", "tail", "used", "count"))
        if count == 0:
            is_consistent = head == tail == used == 0
        else:
            is_consistent = (
                head < capacity
                and tail < capacity
                and not head % 8
                and not tail % 8
                and count * RECORD.size <= used <= capacity
            )
        written = self._get("write_count")
        if self.is_broadcast and self._slot >= 0 and self._slot_get(self._slot, "cursor") > written:
            self._slot_put(self._slot, "cursor", written)
        if is_consistent:
            return None
        self._reset_queue()
        return (
            f"buffer {self.name}: queue header was corrupt (head {head}, tail {tail}, "
            f"used {used}, count {count}); the queue was reset"
        )

    def _write_identity(self) -> None:
        self._put("version", LAYOUT_VERSION)
        self._put("kind", KIND_QUEUE if self.is_queue else KIND_LATEST)
        self._put("encoding", int(self.encoding))
        self._put("capacity", self.layout.capacity)
        self._put("max_procs", self.config.max_procs)
        self._put("buffer_number", self.config.buffer_number & 0xFFFFFFFF)
        self._put("magic", MAGIC)

    def take_missed(self) -> int:
        """Broadcast: how many messages were dropped before this reader read them (the
        queue was full), counted since the last call."""
        self._require_open()
        if self._slot < 0 or not self._slot_get(self._slot, "missed"):
            return 0  # (the common case: one read, no lock)
        self._lock()
        try:
            missed = self._slot_get(self._slot, "missed")
            self._slot_put(self._slot, "missed", 0)
        finally:
            self._unlock()
        return missed

    def _register_broadcast_reader(self) -> None:
        """Make this connection hold every message until it has read it, starting with what
        is still queued now (mutex held). Only connections allowed to read (R, RW) do."""
        oldest = next(self._records(), None)
        first_unread = oldest[2] - 1 if oldest else self._get("write_count")
        self._slot_put(self._slot, "cursor", first_unread)
        self._slot_put(self._slot, "is_reader", 1)

    def _records(self):  # type: ignore[no-untyped-def]
        """(offset, length, sequence) of each queued record, oldest first (mutex held).
        Raises NmlFormatError at a record whose header cannot be right."""
        base, capacity = self.layout.data_offset, self.layout.capacity
        head = self._get("head")
        for _ in range(self._get("count")):
            length, _, sequence = RECORD.unpack_from(self._mm, base + head)  # type: ignore[arg-type]
            if length == WRAP:
                head = 0
                length, _, sequence = RECORD.unpack_from(self._mm, base)  # type: ignore[arg-type]
            if head % 8 or RECORD.size + length > capacity - head:
                raise NmlFormatError(
                    f"buffer {self.name}: queue record at offset {head} claims {length} bytes"
                )
            yield head, length, sequence
            head = (head + RECORD.size + _align8(length)) % capacity

    def _drop_oldest(self) -> None:
        """Make room by dropping the oldest message (mutex held); in a broadcast queue,
        each reader that had not read it yet counts it as missed (``take_missed``)."""
        if self.is_broadcast:
            sequence = next(self._records())[2]
            for index in range(self.config.max_procs):
                if (
                    self._slot_get(index, "is_reader")
                    and self._slot_get(index, "cursor") < sequence
                ):
                    self._slot_put(index, "missed", self._slot_get(index, "missed") + 1)
        self._queue_pop_front()

    def _queue_pop_front(self) -> None:
        base, capacity = self.layout.data_offset, self.layout.capacity
        head, used = self._get("head"), self._get("used")
        length = RECORD.unpack_from(self._mm, base + head)[0]  # type: ignore[arg-type]
        if length == WRAP:
            used -= capacity - head
            head = 0
            length = RECORD.unpack_from(self._mm, base)[0]  # type: ignore[arg-type]
        need = RECORD.size + _align8(length)
        count = self._get("count") - 1
        if count == 0:
            self._reset_queue()
        else:
            self._put("head", (head + need) % capacity)
            self._put("used", used - need)
            self._put("count", count)
        self._put("read_count", self._get("read_count") + 1)

    def _trim_broadcast(self) -> None:
        """Drop the messages every live reader has read (mutex held). Without live readers
        messages stay queued, as in a plain queue, for the next reader to attach."""
        cursors = [
            self._slot_get(index, "cursor")
            for index in range(self.config.max_procs)
            if self._slot_get(index, "is_reader") and is_process_alive(self._slot_get(index, "pid"))
        ]
        if not cursors:
            return
        oldest_unread = min(cursors)
        while self._get("count"):
            first = next(self._records())
            if first[2] > oldest_unread:
                break
            self._queue_pop_front()

    def _reset_queue(self) -> None:
        for key in ("head", "tail", "used", "count"):
            self._put(key, 0)

    # ------------------------------------------------------------------ inspection
    def stats(self) -> dict[str, int]:
        """Live counters for ``cnc nml ls``."""
        self._require_open()
        keys = ("write_count", "read_count", "count", "used", "next_serial", "creator_pid")
        return {key: self._get(key) for key in keys}

    def queued(self) -> list[NMLmsg | NmlFormatError]:
        """Every queued message, oldest first, without removing them (``cnc nml dump``)."""
        self._require_readable()
        out: list[NMLmsg | NmlFormatError] = []
        self._lock()
        try:
            try:
                for offset, length, _ in self._records():
                    start = self.layout.data_offset + offset + RECORD.size
                    data = bytes(self._mm[start : start + length])  # type: ignore[index]
                    try:
                        out.append(decode(data, f"buffer {self.name}"))
                    except NmlFormatError as exc:
                        out.append(exc)
            except NmlFormatError as exc:
                out.append(exc)
        finally:
            self._unlock()
        return out

    def _require_open(self) -> None:
        if self._mm is None:
            raise NmlAccessError(f"buffer {self.name}: connection is closed")

    def _require_readable(self) -> None:
        self._require_open()
        if _IDENTITY.unpack_from(self._mm, 0) != (MAGIC, LAYOUT_VERSION):  # type: ignore[arg-type]
            magic, version = _IDENTITY.unpack_from(self._mm, 0)  # type: ignore[arg-type]
            problem = (
                f"buffer {self.name}: segment header is corrupt (magic {magic:#x}, layout "
                f"version {version}; expected {MAGIC:#x}, {LAYOUT_VERSION})"
            )
            raise self._reset_corrupt(problem)
        if not self.process.can_read:
            raise NmlAccessError(
                f"process {self.process.name} may not read buffer {self.name} "
                f"(ops {self.process.ops})"
            )


def _process_name(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/comm", encoding="utf-8", errors="replace") as handle:
            return handle.read().strip()
    except OSError:
        return "gone"


def _try_acquire(sem: posix_ipc.Semaphore, timeout: float | None = 0) -> bool:
    """Take ``sem`` within ``timeout``; False if it stayed busy or a signal interrupted the
    wait (the signal's handler has run: the caller re-checks why it was waiting)."""
    try:
        sem.acquire(timeout)
    except (posix_ipc.BusyError, posix_ipc.SignalError):
        return False
    return True
