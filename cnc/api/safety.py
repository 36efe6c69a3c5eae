"""The user interfaces' side of the safety board (nml/safety.py).

- ``request_estop()`` / ``request_abort()``: put the request on the board, which motion,
  iocontrol and task look at every cycle: no process holding the command buffer's lock,
  stuck or dead, can delay it. ``command.state(STATE_ESTOP)`` and ``command.abort()`` do
  this first, then send the command as LinuxCNC does (for the RCS answer).
- ``jog_lease()``: the (slot, pid) a continuous jog carries. Motion stops the jog when
  that heartbeat slot goes quiet, so a UI killed or frozen mid-jog stops its jog. The first
  continuous jog registers an unsupervised slot and starts a daemon thread that beats it
  while the process lives; a process that beats a slot of its own (halui, from its main
  loop) gives it with ``use_heartbeat()`` instead.
"""

from __future__ import annotations

import os
import sys
import threading

from nml.ipcnames import SHM_DIR, ipc_name
from nml.safety import Heartbeat, SafetyBoard

LEASE_TIMEOUT_S = 0.5  # a UI's jog stops this long after its process stopped beating
_BEATS_PER_TIMEOUT = 5

_lock = threading.Lock()
_board: SafetyBoard | None = None
_board_id: tuple[int, int] | None = None  # (device, inode) of the segment attached
_lease: Heartbeat | None = None
_own_heartbeat: Heartbeat | None = None


def _segment_id() -> tuple[int, int] | None:
    try:
        found = (SHM_DIR / ipc_name("shm", "safety")[1:]).stat()
    except OSError:
        return None
    return found.st_dev, found.st_ino


def board() -> SafetyBoard | None:
    """The running machine's board (attached again when a new machine made a new one);
    None when no machine runs."""
    global _board, _board_id
    with _lock:
        current = _segment_id()
        if current != _board_id:
            if _board is not None:
                _board.close()
            _board = SafetyBoard.attach() if current is not None else None
            _board_id = current if _board is not None else None
        return _board


def _who() -> str:
    return f"{os.path.basename(sys.argv[0]) or 'python'} (pid {os.getpid()})"


def request_estop() -> int:
    """E-stop through the board; its stamp, 0 without a running machine."""
    found = board()
    return found.request_estop(f"E-stop from {_who()}") if found is not None else 0


def request_abort() -> int:
    found = board()
    return found.request_abort(f"abort from {_who()}") if found is not None else 0


def use_heartbeat(heartbeat: Heartbeat | None) -> None:
    """This process beats ``heartbeat`` itself (halui): its jogs are leased to it."""
    global _own_heartbeat
    _own_heartbeat = heartbeat


def keep_alive() -> None:
    """Beat this process's own heartbeat, if it has one, while it waits for the controller
    (a command method waits up to seconds: the process is alive all the same)."""
    if _own_heartbeat is not None:
        _own_heartbeat.beat()


def jog_lease() -> tuple[int, int]:
    """(slot, pid) for a continuous jog; (0, 0) without a board (nothing supervised)."""
    global _lease
    if _own_heartbeat is not None:
        return _own_heartbeat.slot, _own_heartbeat.pid
    found = board()
    if found is None:
        return 0, 0
    with _lock:
        if _lease is None or _lease.board is not found or _lease.pid != os.getpid():
            _lease = found.register(f"ui {_who()}", LEASE_TIMEOUT_S, is_supervised=False)
            threading.Thread(target=_beat, args=(_lease,), name="jog-lease", daemon=True).start()
        _lease.beat()
        return _lease.slot, _lease.pid


def _beat(lease: Heartbeat) -> None:
    """Beat the lease while this process lives and the lease is the current one."""
    pause = threading.Event()  # (never set: a sleep that a signal does not cut short)
    while _lease is lease:
        try:
            lease.beat()
        except ValueError:  # the machine stopped: its board was closed
            return
        pause.wait(LEASE_TIMEOUT_S / _BEATS_PER_TIMEOUT)
