"""The safety board: E-stop and abort requests that no lock can block, and heartbeats.

One small shared-memory segment per machine (``/cnc.<instance>.shm.safety``), created by
the launcher before anything else starts and removed last. It holds no lock and no
semaphore, so no process, stuck or dead, can keep another from using it:

- **Requests** (E-stop, abort): a single slot each, latest value wins. A request writes its
  reason and pid, then its stamp (``CLOCK_MONOTONIC`` nanoseconds, the same clock in every
  process). Motion (every servo period), iocontrol and task (every cycle) each remember the
  last stamp they acted on and act on any change, so a request reaches each of them even
  when the others are stuck; two requests in the same instant both count as one. An
  E-stop is *immediate* (the operator's: motion off at once) or *braking* (a lost process:
  motion brakes along its path, then goes off, then asks for the immediate one).
- **Heartbeats**: every process that carries a safety input or output (task, iocontrol,
  halui, motion itself) claims a slot, writes its timeout there and beats it from its main
  loop. A *supervised* slot whose beat is older than its timeout, or whose process left
  without the launcher shutting the machine down, is **lost**: whoever notices first
  (motion, iocontrol, task or the launcher) marks it, asks for a braking E-stop naming the
  process, and tells the operator. A lost slot stays lost, and E-stop cannot be reset,
  until a process of that name registers again.
- **Leases**: a user interface that starts a continuous jog beats an unsupervised slot of
  its own while the jog runs; motion stops a continuous jog whose requester's slot has gone
  quiet (a UI killed or stopped mid-jog).

Writes of 8-byte fields are not guaranteed atomic from Python, but nothing here depends on
it: a reader acts on any *change* of a stamp, and a torn stamp is a change too.
"""

from __future__ import annotations

import contextlib
import mmap
import os
import struct
import time
from dataclasses import dataclass

import posix_ipc

from nml.ipcnames import ipc_name

MAGIC = 0x46415331  # "1SAF"
VERSION = 1
NUM_SLOTS = 32
REASON_BYTES = 112
NAME_BYTES = 32

# header: magic, version, creator pid, is_shutting_down
_HEADER = struct.Struct("<IIqI")
HEADER_SIZE = 64
# a request: stamp (ns), pid, is_braking, reason (UTF-8, NUL padded)
_REQUEST = struct.Struct(f"<QiI{REASON_BYTES}s")
REQUEST_SIZE = 128
ESTOP_AT = HEADER_SIZE
ABORT_AT = ESTOP_AT + REQUEST_SIZE
# a slot: pid, state, timeout (ns), beat (ns), is_supervised, name
_SLOT = struct.Struct(f"<iIQQI4x{NAME_BYTES}s")
SLOT_SIZE = 64
SLOTS_AT = ABORT_AT + REQUEST_SIZE
SEGMENT_SIZE = SLOTS_AT + NUM_SLOTS * SLOT_SIZE
_U64 = struct.Struct("<Q")
_STAMP_AT = 0  # offset of a request's stamp, and of a slot's beat
_BEAT_AT = 16
_STATE_AT = 4

FREE, ALIVE, EXITED, LOST = 0, 1, 2, 3


def now_ns() -> int:
    return time.monotonic_ns()


@dataclass(frozen=True)
class Request:
    """An E-stop or abort request: when (monotonic ns), who, why."""

    stamp: int
    pid: int
    reason: str
    is_braking: bool = False


@dataclass(frozen=True)
class LostProcess:
    """A supervised process that died or stopped beating; ``reason`` says which and how."""

    slot: int
    name: str
    pid: int
    reason: str


class SafetyBoard:
    """One process's view of the machine's safety board."""

    def __init__(self, mm: mmap.mmap, is_owner: bool) -> None:
        self._mm = mm
        self.is_owner = is_owner

    # ------------------------------------------------------------------ lifecycle
    @classmethod
    def create(cls, instance: str | None = None) -> SafetyBoard:
        """Make a new, empty board (the launcher, before it starts anything)."""
        name = ipc_name("shm", "safety", instance)
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(name)
        shm = posix_ipc.SharedMemory(name, posix_ipc.O_CREX, mode=0o660, size=SEGMENT_SIZE)
        try:
            mm = mmap.mmap(shm.fd, SEGMENT_SIZE)
        finally:
            shm.close_fd()
        _HEADER.pack_into(mm, 0, 0, VERSION, os.getpid(), 0)
        struct.pack_into("<I", mm, 0, MAGIC)  # last: attachers check it
        return cls(mm, is_owner=True)

    @classmethod
    def attach(cls, instance: str | None = None) -> SafetyBoard | None:
        """The running machine's board; None if there is none (a HAL session or test
        without the launcher: nothing is supervised then)."""
        try:
            shm = posix_ipc.SharedMemory(ipc_name("shm", "safety", instance))
        except posix_ipc.ExistentialError:
            return None
        try:
            if shm.size < SEGMENT_SIZE:
                return None
            mm = mmap.mmap(shm.fd, SEGMENT_SIZE)
        finally:
            shm.close_fd()
        if _HEADER.unpack_from(mm, 0)[:2] != (MAGIC, VERSION):
            mm.close()
            return None
        return cls(mm, is_owner=False)

    def close(self) -> None:
        if self._mm is not None and not self._mm.closed:
            self._mm.close()

    def unlink(self, instance: str | None = None) -> None:
        self.close()
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(ipc_name("shm", "safety", instance))

    @property
    def is_shutting_down(self) -> bool:
        """The launcher is stopping the machine: processes leaving are not lost."""
        return bool(_HEADER.unpack_from(self._mm, 0)[3])

    def begin_shutdown(self) -> None:
        magic, version, creator, _ = _HEADER.unpack_from(self._mm, 0)
        _HEADER.pack_into(self._mm, 0, magic, version, creator, 1)

    # ------------------------------------------------------------------ requests
    def request_estop(self, reason: str, *, is_braking: bool = False) -> int:
        """Ask every process for E-stop; returns the request's stamp."""
        return self._request(ESTOP_AT, reason, is_braking)

    def request_abort(self, reason: str) -> int:
        """Ask motion, task and iocontrol to abort; returns the request's stamp."""
        return self._request(ABORT_AT, reason, False)

    def _request(self, at: int, reason: str, is_braking: bool) -> int:
        stamp = now_ns()
        text = reason.encode("utf-8")[:REASON_BYTES]
        _REQUEST.pack_into(self._mm, at, 0, os.getpid(), int(is_braking), text)
        _U64.pack_into(self._mm, at + _STAMP_AT, stamp)  # last: the request counts from now
        return stamp

    def estop_stamp(self) -> int:
        """The last E-stop request's stamp: cheap enough for every servo period."""
        return _U64.unpack_from(self._mm, ESTOP_AT)[0]

    def abort_stamp(self) -> int:
        return _U64.unpack_from(self._mm, ABORT_AT)[0]

    def estop_request(self) -> Request:
        return self._read_request(ESTOP_AT)

    def abort_request(self) -> Request:
        return self._read_request(ABORT_AT)

    def _read_request(self, at: int) -> Request:
        stamp, pid, is_braking, text = _REQUEST.unpack_from(self._mm, at)
        return Request(stamp, pid, _text(text), bool(is_braking))

    def watcher(self) -> RequestWatcher:
        """Something that reports each new request once, starting from now."""
        return RequestWatcher(self)

    # ------------------------------------------------------------------ heartbeats
    def register(self, name: str, timeout_s: float, *, is_supervised: bool) -> Heartbeat:
        """Claim a slot for this process (the lost slot of the same name, if any: the
        process is back) and beat it once. Raises RuntimeError when all are taken."""
        pid = os.getpid()
        wanted = name.encode("utf-8")[:NAME_BYTES]
        free = None
        for index in range(NUM_SLOTS):
            at = _slot_at(index)
            slot_pid, state, _, _, is_supervised, slot_name = _SLOT.unpack_from(self._mm, at)
            if slot_name.rstrip(b"\0") == wanted and state in (LOST, EXITED):
                free = index  # back after being lost: take its place, E-stop may be reset
                break
            # (a supervised slot of a dead process stays until someone finds it lost)
            is_reusable = state == FREE or (not is_supervised and not _is_alive(slot_pid))
            if free is None and is_reusable:
                free = index
        if free is None:
            raise RuntimeError(f"safety board: all {NUM_SLOTS} heartbeat slots are taken")
        timeout_ns = max(int(timeout_s * 1e9), 1)
        _SLOT.pack_into(
            self._mm, _slot_at(free), pid, ALIVE, timeout_ns, now_ns(), int(is_supervised), wanted
        )
        return Heartbeat(self, free, pid, name)

    def slot_is_alive(self, slot: int, pid: int, now: int | None = None) -> bool:
        """A lease: slot ``slot`` still belongs to ``pid``, which beat it in time."""
        if not 0 <= slot < NUM_SLOTS:
            return False
        slot_pid, state, timeout, beat, _, _ = _SLOT.unpack_from(self._mm, _slot_at(slot))
        age = (now_ns() if now is None else now) - beat
        return slot_pid == pid and state == ALIVE and age <= timeout

    def find_lost(self, now: int | None = None) -> list[LostProcess]:
        """Mark supervised processes that stopped beating or left as lost, and return
        the ones this call marked (each is found once, by whoever looks first)."""
        now = now_ns() if now is None else now
        is_shutting_down = self.is_shutting_down
        found = []
        for index in range(NUM_SLOTS):
            at = _slot_at(index)
            pid, state, timeout, beat, is_supervised, name = _SLOT.unpack_from(self._mm, at)
            if not is_supervised or state not in (ALIVE, EXITED) or is_shutting_down:
                continue
            label = f"{_text(name)} (pid {pid})"
            if state == EXITED:
                reason = f"{label} has exited"
            elif now - beat > timeout:
                seconds = (now - beat) / 1e9
                reason = (
                    f"{label} is gone" if not _is_alive(pid) else f"{label} stopped answering"
                ) + f" (no heartbeat for {seconds:.2f} s)"
            else:
                continue
            struct.pack_into("<I", self._mm, at + _STATE_AT, LOST)
            found.append(LostProcess(index, _text(name), pid, reason))
        return found

    def mark_lost(self, pid: int, reason: str) -> LostProcess | None:
        """The launcher saw process ``pid`` end: mark its supervised slot lost now,
        rather than after its heartbeat timeout. None if it had none or was marked."""
        for index in range(NUM_SLOTS):
            at = _slot_at(index)
            slot_pid, state, _, _, is_supervised, name = _SLOT.unpack_from(self._mm, at)
            if slot_pid == pid and is_supervised and state in (ALIVE, EXITED):
                if self.is_shutting_down:
                    return None
                struct.pack_into("<I", self._mm, at + _STATE_AT, LOST)
                return LostProcess(index, _text(name), pid, reason)
        return None

    def lost_names(self) -> list[str]:
        """Supervised processes lost and not back: E-stop may not be reset meanwhile."""
        names = []
        for index in range(NUM_SLOTS):
            pid, state, _, _, is_supervised, name = _SLOT.unpack_from(self._mm, _slot_at(index))
            if is_supervised and state == LOST:
                names.append(f"{_text(name)} (pid {pid})")
        return names


class Heartbeat:
    """This process's slot on the board."""

    __slots__ = ("_at", "_mm", "board", "name", "pid", "slot")

    def __init__(self, board: SafetyBoard, slot: int, pid: int, name: str) -> None:
        self.board = board
        self.slot = slot
        self.pid = pid
        self.name = name
        self._mm = board._mm
        self._at = _slot_at(slot) + _BEAT_AT

    def beat(self) -> None:
        _U64.pack_into(self._mm, self._at, time.monotonic_ns())

    def leave(self) -> None:
        """A clean exit: a supervised process that leaves while the machine runs is lost
        all the same (its inputs are no longer read), but it says so at once."""
        if self._mm.closed:
            return
        at = _slot_at(self.slot)
        if struct.unpack_from("<i", self._mm, at)[0] == self.pid:
            struct.pack_into("<I", self._mm, at + _STATE_AT, EXITED)


class RequestWatcher:
    """Reports each new E-stop or abort request once (the ones before it was made, never)."""

    __slots__ = ("abort_seen", "board", "estop_seen")

    def __init__(self, board: SafetyBoard) -> None:
        self.board = board
        self.estop_seen = board.estop_stamp()
        self.abort_seen = board.abort_stamp()

    def take_estop(self) -> Request | None:
        if self.board.estop_stamp() == self.estop_seen:
            return None
        request = self.board.estop_request()
        self.estop_seen = request.stamp
        return request

    def take_abort(self) -> Request | None:
        if self.board.abort_stamp() == self.abort_seen:
            return None
        request = self.board.abort_request()
        self.abort_seen = request.stamp
        return request


def _slot_at(index: int) -> int:
    return SLOTS_AT + index * SLOT_SIZE


def _text(raw: bytes) -> str:
    return raw.rstrip(b"\0").decode("utf-8", errors="replace")


def _is_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@dataclass(frozen=True)
class Tick:
    """What one look at the board found: new requests, and processes this look found lost
    (their braking E-stop is already requested; the caller tells the operator)."""

    estop: Request | None
    abort: Request | None
    lost: list[LostProcess]


LOST_SCAN_NS = 20_000_000  # how often a process looks for lost ones (20 ms)


class SafetyLink:
    """A process's part in the safety board, done once a cycle by ``tick()``: beat its
    heartbeat, take new requests, look for lost processes."""

    def __init__(self, board: SafetyBoard, heartbeat: Heartbeat) -> None:
        self.board = board
        self.heartbeat = heartbeat
        self.watcher = board.watcher()
        self._next_scan = 0

    @classmethod
    def open(cls, name: str, timeout_s: float, *, is_supervised: bool = True) -> SafetyLink | None:
        """Register on the running machine's board; None without one."""
        board = SafetyBoard.attach()
        if board is None:
            return None
        try:
            heartbeat = board.register(name, timeout_s, is_supervised=is_supervised)
        except RuntimeError:
            board.close()
            raise
        return cls(board, heartbeat)

    def tick(self) -> Tick:
        self.heartbeat.beat()
        lost: list[LostProcess] = []
        now = now_ns()
        if now >= self._next_scan:
            self._next_scan = now + LOST_SCAN_NS
            lost = self.board.find_lost(now)
            for process in lost:
                self.board.request_estop(process.reason, is_braking=True)
        return Tick(self.watcher.take_estop(), self.watcher.take_abort(), lost)

    def close(self) -> None:
        self.heartbeat.leave()
        self.board.close()
