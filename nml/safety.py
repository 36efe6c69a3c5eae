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
import time
from dataclasses import dataclass

import posix_ipc

from nml.ipcnames import ipc_name
from nml.shmem import is_process_alive

MAGIC = 0x46415331  # "1SAF"
# A braking E-stop that has not brought motion to rest by then turns motion off anyway.
BRAKE_TIMEOUT_S = 5.0
VERSION = 1
NUM_SLOTS = 32
REASON_BYTES = 112
NAME_BYTES = 32

# Byte offsets. Every field is read and written whole through a typed view of the segment
# (one aligned load or store): struct.pack_into first zeroes what it writes, and a reader
# without a lock would see the zeros (a beat of 0: a process taken for dead).
# header: magic u32, version u32, creator pid i64, is_shutting_down u32
_MAGIC_AT, _VERSION_AT, _CREATOR_AT, _SHUTDOWN_AT = 0, 4, 8, 16
HEADER_SIZE = 64
# a request: stamp u64 (ns, written last), pid i32, is_braking u32, reason (UTF-8, NUL padded)
_STAMP_AT, _PID_AT, _BRAKING_AT, _REASON_AT = 0, 8, 12, 16
REQUEST_SIZE = 128
ESTOP_AT = HEADER_SIZE
ABORT_AT = ESTOP_AT + REQUEST_SIZE
# a slot: pid i32, state u32 (written last), timeout u64 (ns), beat u64 (ns),
# is_supervised u32, is_reported u32 (a loss told to the operator), name, then the reason
# of a loss (UTF-8, NUL padded)
_SLOT_PID_AT, _STATE_AT, _TIMEOUT_AT, _BEAT_AT = 0, 4, 8, 16
_SUPERVISED_AT, _REPORTED_AT, _NAME_AT, _LOSS_AT = 24, 28, 32, 64
LOSS_BYTES = 64
SLOT_SIZE = 128
SLOTS_AT = ABORT_AT + REQUEST_SIZE
SEGMENT_SIZE = SLOTS_AT + NUM_SLOTS * SLOT_SIZE

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


@dataclass(frozen=True)
class _SlotView:
    pid: int
    state: int
    timeout: int
    beat: int
    is_supervised: bool
    name: str


class SafetyBoard:
    """One process's view of the machine's safety board."""

    def __init__(self, mm: mmap.mmap, is_owner: bool) -> None:
        self._mm = mm
        self.is_owner = is_owner
        view = memoryview(mm)
        self._u64, self._i32, self._u32 = view.cast("Q"), view.cast("i"), view.cast("I")
        view.release()

    # ------------------------------------------------------------------ typed fields
    def _get_u64(self, at: int) -> int:
        return self._u64[at >> 3]

    def _put_u64(self, at: int, value: int) -> None:
        self._u64[at >> 3] = value

    def _get_u32(self, at: int) -> int:
        return self._u32[at >> 2]

    def _put_u32(self, at: int, value: int) -> None:
        self._u32[at >> 2] = value

    def _get_i32(self, at: int) -> int:
        return self._i32[at >> 2]

    def _put_i32(self, at: int, value: int) -> None:
        self._i32[at >> 2] = value

    def _put_text(self, at: int, size: int, text: str) -> None:
        raw = text.encode("utf-8")[:size]
        self._mm[at : at + size] = raw + bytes(size - len(raw))

    def _get_text(self, at: int, size: int) -> str:
        return self._mm[at : at + size].rstrip(b"\0").decode("utf-8", errors="replace")

    def _slot(self, index: int) -> _SlotView:
        at = _slot_at(index)
        return _SlotView(
            self._get_i32(at + _SLOT_PID_AT),
            self._get_u32(at + _STATE_AT),
            self._get_u64(at + _TIMEOUT_AT),
            self._get_u64(at + _BEAT_AT),
            bool(self._get_u32(at + _SUPERVISED_AT)),
            self._get_text(at + _NAME_AT, NAME_BYTES),
        )

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
        board = cls(mm, is_owner=True)
        board._put_u32(_VERSION_AT, VERSION)
        board._put_u64(_CREATOR_AT, os.getpid())
        board._put_u32(_MAGIC_AT, MAGIC)  # last: attachers check it
        return board

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
        board = cls(mm, is_owner=False)
        if (board._get_u32(_MAGIC_AT), board._get_u32(_VERSION_AT)) != (MAGIC, VERSION):
            board.close()
            return None
        return board

    def close(self) -> None:
        if self._mm.closed:
            return
        for view in (self._u64, self._i32, self._u32):
            view.release()
        self._mm.close()

    @property
    def is_closed(self) -> bool:
        return self._mm.closed

    def unlink(self, instance: str | None = None) -> None:
        self.close()
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(ipc_name("shm", "safety", instance))

    @property
    def is_shutting_down(self) -> bool:
        """The launcher is stopping the machine: processes leaving are not lost."""
        return bool(self._get_u32(_SHUTDOWN_AT))

    def begin_shutdown(self) -> None:
        self._put_u32(_SHUTDOWN_AT, 1)

    # ------------------------------------------------------------------ requests
    def request_estop(self, reason: str, *, is_braking: bool = False) -> int:
        """Ask every process for E-stop; returns the request's stamp."""
        return self._request(ESTOP_AT, reason, is_braking)

    def request_abort(self, reason: str) -> int:
        """Ask motion, task and iocontrol to abort; returns the request's stamp."""
        return self._request(ABORT_AT, reason, False)

    def _request(self, at: int, reason: str, is_braking: bool) -> int:
        stamp = now_ns()
        self._put_text(at + _REASON_AT, REASON_BYTES, reason)
        self._put_i32(at + _PID_AT, os.getpid())
        self._put_u32(at + _BRAKING_AT, int(is_braking))
        self._put_u64(at + _STAMP_AT, stamp)  # last: the request counts from now
        return stamp

    def estop_stamp(self) -> int:
        """The last E-stop request's stamp: cheap enough for every servo period."""
        return self._u64[(ESTOP_AT + _STAMP_AT) >> 3]

    def abort_stamp(self) -> int:
        return self._u64[(ABORT_AT + _STAMP_AT) >> 3]

    def estop_request(self) -> Request:
        return self._read_request(ESTOP_AT)

    def abort_request(self) -> Request:
        return self._read_request(ABORT_AT)

    def _read_request(self, at: int) -> Request:
        return Request(
            self._get_u64(at + _STAMP_AT),
            self._get_i32(at + _PID_AT),
            self._get_text(at + _REASON_AT, REASON_BYTES),
            bool(self._get_u32(at + _BRAKING_AT)),
        )

    def watcher(self) -> RequestWatcher:
        """Something that reports each new request once, starting from now."""
        return RequestWatcher(self)

    # ------------------------------------------------------------------ heartbeats
    def register(self, name: str, timeout_s: float, *, is_supervised: bool) -> Heartbeat:
        """Claim a slot for this process (the lost slot of the same name, if any: the
        process is back) and beat it once. Raises RuntimeError when all are taken."""
        chosen = None
        for index in range(NUM_SLOTS):
            slot = self._slot(index)
            if slot.name == name and slot.state in (LOST, EXITED):
                chosen = index  # back after being lost: take its place, E-stop may be reset
                break
            # (a supervised slot of a dead process stays until someone finds it lost)
            is_reusable = slot.state == FREE or (
                not slot.is_supervised and not is_process_alive(slot.pid)
            )
            if chosen is None and is_reusable:
                chosen = index
        if chosen is None:
            raise RuntimeError(f"safety board: all {NUM_SLOTS} heartbeat slots are taken")
        at, pid = _slot_at(chosen), os.getpid()
        self._put_text(at + _NAME_AT, NAME_BYTES, name)
        self._put_u32(at + _REPORTED_AT, 0)
        self._put_u64(at + _TIMEOUT_AT, max(int(timeout_s * 1e9), 1))
        self._put_u32(at + _SUPERVISED_AT, int(is_supervised))
        self._put_u64(at + _BEAT_AT, now_ns())
        self._put_i32(at + _SLOT_PID_AT, pid)
        self._put_u32(at + _STATE_AT, ALIVE)  # last: from now on it is looked at
        return Heartbeat(self, chosen, pid, name)

    def slot_is_alive(self, slot: int, pid: int, now: int | None = None) -> bool:
        """A lease: slot ``slot`` still belongs to ``pid``, which beat it in time."""
        if not 0 <= slot < NUM_SLOTS:
            return False
        at = _slot_at(slot)
        if self._get_i32(at + _SLOT_PID_AT) != pid or self._get_u32(at + _STATE_AT) != ALIVE:
            return False
        age = (now_ns() if now is None else now) - self._get_u64(at + _BEAT_AT)
        return age <= self._get_u64(at + _TIMEOUT_AT)

    def find_lost(self, now: int | None = None) -> list[LostProcess]:
        """Mark supervised processes that stopped beating or left as lost, and return
        the ones this call marked (each is found once, by whoever looks first)."""
        if self.is_shutting_down:
            return []
        now = now_ns() if now is None else now
        found = []
        for index in range(NUM_SLOTS):
            at = _slot_at(index)
            state = self._get_u32(at + _STATE_AT)
            if state not in (ALIVE, EXITED) or not self._get_u32(at + _SUPERVISED_AT):
                continue
            slot = self._slot(index)
            label = f"{slot.name} (pid {slot.pid})"
            if state == EXITED:
                reason = f"{label} has exited"
            elif now - slot.beat > slot.timeout:
                seconds = (now - slot.beat) / 1e9
                reason = (
                    f"{label} is gone"
                    if not is_process_alive(slot.pid)
                    else f"{label} stopped answering"
                ) + f" (no heartbeat for {seconds:.2f} s)"
            else:
                continue
            self._lose(index, reason)
            found.append(LostProcess(index, slot.name, slot.pid, reason))
        return found

    def _lose(self, index: int, reason: str) -> None:
        at = _slot_at(index)
        self._put_text(at + _LOSS_AT, LOSS_BYTES, reason)
        self._put_u32(at + _REPORTED_AT, 0)
        self._put_u32(at + _STATE_AT, LOST)

    def take_unreported(self) -> list[LostProcess]:
        """Losses nobody has told the operator about yet, now marked told: each is told
        once, by a process that can write to the error channel (halui, which finds
        losses too, cannot)."""
        found = []
        for index in range(NUM_SLOTS):
            at = _slot_at(index)
            if self._get_u32(at + _STATE_AT) != LOST or self._get_u32(at + _REPORTED_AT):
                continue
            self._put_u32(at + _REPORTED_AT, 1)
            slot = self._slot(index)
            reason = self._get_text(at + _LOSS_AT, LOSS_BYTES)
            found.append(LostProcess(index, slot.name, slot.pid, reason))
        return found

    def mark_lost(self, pid: int, reason: str) -> LostProcess | None:
        """The launcher saw process ``pid`` end: mark its supervised slot lost now,
        rather than after its heartbeat timeout. None if it had none or was marked."""
        if self.is_shutting_down:
            return None
        for index in range(NUM_SLOTS):
            slot = self._slot(index)
            if slot.pid == pid and slot.is_supervised and slot.state in (ALIVE, EXITED):
                self._lose(index, reason)
                return LostProcess(index, slot.name, pid, reason)
        return None

    def lost(self) -> list[LostProcess]:
        """Supervised processes lost and not back: E-stop may not be reset meanwhile."""
        found = []
        for index in range(NUM_SLOTS):
            slot = self._slot(index)
            if slot.is_supervised and slot.state == LOST:
                reason = self._get_text(_slot_at(index) + _LOSS_AT, LOSS_BYTES)
                found.append(LostProcess(index, slot.name, slot.pid, reason))
        return found

    def lost_names(self) -> list[str]:
        return [f"{process.name} (pid {process.pid})" for process in self.lost()]


class Heartbeat:
    """This process's slot on the board."""

    __slots__ = ("_beat_index", "board", "name", "pid", "slot")

    def __init__(self, board: SafetyBoard, slot: int, pid: int, name: str) -> None:
        self.board = board
        self.slot = slot
        self.pid = pid
        self.name = name
        self._beat_index = (_slot_at(slot) + _BEAT_AT) >> 3

    def beat(self) -> None:
        """Raises ValueError once the board is closed (the machine stopped)."""
        self.board._u64[self._beat_index] = time.monotonic_ns()

    def leave(self) -> None:
        """A clean exit: a supervised process that leaves while the machine runs is lost
        all the same (its inputs are no longer read), but it says so at once."""
        board = self.board
        if board.is_closed:
            return
        at = _slot_at(self.slot)
        if board._get_i32(at + _SLOT_PID_AT) == self.pid:
            board._put_u32(at + _STATE_AT, EXITED)


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


@dataclass(frozen=True)
class Tick:
    """What one look at the board found: new requests, and the lost processes this
    process is to tell the operator about (their braking E-stop is requested already)."""

    estop: Request | None
    abort: Request | None
    lost: list[LostProcess]


LOST_SCAN_NS = 20_000_000  # how often a process looks for lost ones (20 ms)
_NOTHING_LOST: list[LostProcess] = []
_QUIET = Tick(None, None, _NOTHING_LOST)


class SafetyLink:
    """A process's part in the safety board, done once a cycle by ``tick()``: beat its
    heartbeat, take new requests, look for lost processes (and, for a process that can
    write to the error channel, ``is_reporter``, take the losses nobody reported yet)."""

    def __init__(self, board: SafetyBoard, heartbeat: Heartbeat, is_reporter: bool) -> None:
        self.board = board
        self.heartbeat = heartbeat
        self.is_reporter = is_reporter
        self.watcher = board.watcher()
        self._next_scan = 0

    @classmethod
    def open(
        cls, name: str, timeout_s: float, *, is_supervised: bool = True, is_reporter: bool = True
    ) -> SafetyLink | None:
        """Register on the running machine's board; None without one."""
        board = SafetyBoard.attach()
        if board is None:
            return None
        try:
            heartbeat = board.register(name, timeout_s, is_supervised=is_supervised)
        except RuntimeError:
            board.close()
            raise
        return cls(board, heartbeat, is_reporter)

    def tick(self) -> Tick:
        """Cheap when nothing happened (motion calls it every servo period)."""
        self.heartbeat.beat()
        lost = _NOTHING_LOST
        now = now_ns()
        if now >= self._next_scan:
            self._next_scan = now + LOST_SCAN_NS
            for process in self.board.find_lost(now):
                self.board.request_estop(process.reason, is_braking=True)
            if self.is_reporter:
                lost = self.board.take_unreported()
        estop, abort = self.watcher.take_estop(), self.watcher.take_abort()
        if estop is None and abort is None and not lost:
            return _QUIET
        return Tick(estop, abort, lost)

    def close(self) -> None:
        self.heartbeat.leave()
        self.board.close()
