"""The HAL shared space: components, pins, parameters, signals, functions and threads.

Two POSIX shared-memory segments per instance hold everything, so every process (the
realtime host, userspace components, halcmd, UIs, tests) sees the same HAL:

- the *data* segment: a header (metadata generation counter), a pointer table and value
  slots of 8 bytes each. Every pin, parameter and signal owns one value slot. A pin also owns
  one pointer entry, ``ptr[pin_slot]``, naming the slot it currently reads and writes: its
  own slot while unlinked, the signal's slot after ``net``. So a linked in pin sees the
  writer's value immediately, like LinuxCNC's pin pointers.
- the *metadata* segment: names, types, directions, links, functions and threads, as one
  msgpack document rewritten under the HAL mutex (a POSIX named semaphore), alternately in
  each half of the segment so that a writer dying mid-way leaves the last document intact.
  Readers cache the document and reload it only when the generation counter changes.

All values are stored in 8-byte slots: floats as doubles, every integer type and bits as
64-bit integers (bits 0/1, s32/u32 wrapped to their width on write).
"""

from __future__ import annotations

import contextlib
import mmap
import os
import re
import sys
import threading
from collections.abc import Iterator
from typing import Any

import msgpack
import posix_ipc

from nml.ipcnames import instance_objects, ipc_name

# Types and directions with LinuxCNC's numeric values (hal.h).
HAL_BIT, HAL_FLOAT, HAL_S32, HAL_U32, HAL_S64, HAL_U64 = 1, 2, 3, 4, 6, 7
HAL_IN, HAL_OUT, HAL_IO = 16, 32, 48
HAL_RO, HAL_RW = 64, 192

TYPE_NAMES = {
    HAL_BIT: "bit",
    HAL_FLOAT: "float",
    HAL_S32: "s32",
    HAL_U32: "u32",
    HAL_S64: "s64",
    HAL_U64: "u64",
}
TYPES_BY_NAME = {name: code for code, name in TYPE_NAMES.items()}
DIR_NAMES = {HAL_IN: "IN", HAL_OUT: "OUT", HAL_IO: "I/O", HAL_RO: "RO", HAL_RW: "RW"}
DIRS_BY_NAME = {"in": HAL_IN, "out": HAL_OUT, "io": HAL_IO, "ro": HAL_RO, "rw": HAL_RW}

HAL_NAME_LEN = 47  # LinuxCNC 2.9 hal.h
NSLOTS = 1 << 17
HEADER_BYTES = 64
DATA_BYTES = HEADER_BYTES + NSLOTS * 4 + NSLOTS * 8
META_BYTES = 16 << 20
LOCK_TIMEOUT_S = 5.0

_COMPLIANT = re.compile(r"^[a-z0-9.-]+$")
# Any printable character but blanks, as LinuxCNC (which checks only the length): pyvcp
# panels name pins "jog-x+", and halcmd splits words at blanks
_ALLOWED = re.compile(r"^[!-~]+$")


class HalError(Exception):
    """A refused HAL operation; the message reads like LinuxCNC's."""


def check_name(kind: str, name: str) -> None:
    """Refuse names that are too long or contain characters HAL cannot store (HAL-002)."""
    if not name:
        raise HalError(f"{kind} name is empty")
    if len(name) > HAL_NAME_LEN:
        raise HalError(f"{kind} name '{name}' is too long (more than {HAL_NAME_LEN} characters)")
    if not _ALLOWED.match(name):
        raise HalError(f"{kind} name '{name}' contains invalid characters")


def is_compliant_name(name: str) -> bool:
    """True when a name follows HAL-005: lowercase letters, digits, '.' and '-' only."""
    return bool(_COMPLIANT.match(name))


def wrap_value(hal_type: int, value: Any) -> int | float:
    """A Python value converted to what a slot of ``hal_type`` stores."""
    if hal_type == HAL_FLOAT:
        return float(value)
    if hal_type == HAL_BIT:
        return 1 if value else 0
    number = int(value)
    if hal_type == HAL_S32:
        return (number + (1 << 31)) % (1 << 32) - (1 << 31)
    if hal_type == HAL_U32:
        return number % (1 << 32)
    if hal_type == HAL_S64:
        return (number + (1 << 63)) % (1 << 64) - (1 << 63)
    return number % (1 << 64)


def parse_value(hal_type: int, text: str) -> int | float:
    """A value typed in a HAL file; raises HalError like halcmd's ``value 'x' invalid``."""
    word = text.strip()
    try:
        if hal_type == HAL_BIT:
            lowered = word.lower()
            if lowered in ("1", "true", "on"):
                return 1
            if lowered in ("0", "false", "off"):
                return 0
            raise ValueError(word)
        if hal_type == HAL_FLOAT:
            return float(word)
        number = int(word, 0)
    except ValueError:
        raise HalError(f"value '{text}' invalid for {TYPE_NAMES[hal_type]}") from None
    limits = {
        HAL_S32: (-(1 << 31), (1 << 31) - 1),
        HAL_U32: (0, (1 << 32) - 1),
        HAL_S64: (-(1 << 63), (1 << 63) - 1),
        HAL_U64: (0, (1 << 64) - 1),
    }[hal_type]
    if not limits[0] <= number <= limits[1]:
        raise HalError(f"value '{text}' invalid for {TYPE_NAMES[hal_type]}")
    return number


def format_value(hal_type: int, value: int | float, *, is_show: bool = True) -> str:
    """A value as halcmd prints it (``TRUE``, ``0x00000032`` in show, ``2.5``)."""
    if hal_type == HAL_BIT:
        return "TRUE" if value else "FALSE"
    if hal_type == HAL_FLOAT:
        return f"{value:.7g}"
    if hal_type == HAL_U32 and is_show:
        return f"0x{int(value):08X}"
    if hal_type == HAL_U64 and is_show:
        return f"0x{int(value):016X}"
    return str(int(value))


def remove_hal_objects() -> list[str]:
    """Unlink this instance's HAL shared memory and semaphores; returns their names."""
    prefix = ipc_name("hal", "")
    removed = []
    for name in instance_objects():
        if not name.startswith(prefix):
            continue
        for unlink in (posix_ipc.unlink_shared_memory, posix_ipc.unlink_semaphore):
            with contextlib.suppress(posix_ipc.ExistentialError):
                unlink(name)
                removed.append(name)
    return removed


def release_hal_mutex(instance: str | None = None) -> bool | None:
    """Release the HAL mutex of an instance if a crashed program left it held (halcmd -R).

    True when it was held and is now free, False when it was free, None when the instance
    has no HAL mutex.
    """
    try:
        mutex = posix_ipc.Semaphore(ipc_name("hal", "mutex", instance))
    except posix_ipc.ExistentialError:
        return None
    try:
        is_held = mutex.value == 0
        if is_held:
            mutex.release()
        return is_held
    finally:
        mutex.close()


def _empty_meta() -> dict[str, Any]:
    return {
        "next_id": 1,
        "next_slot": 1,
        "free": [],
        "comps": {},
        "pins": {},
        "params": {},
        "sigs": {},
        "functs": {},
        "threads": {},
        "is_running": False,
        "pin_alias": {},
        "param_alias": {},
        "lock": 0,
    }


class Hal:
    """One process's attachment to the HAL shared space of the current instance.

    ``meta`` is a cached read-only view of the metadata; change it only inside
    ``with hal.edit() as meta:``. Values are read and written straight in shared memory.
    """

    def __init__(self, instance: str | None = None, *, is_creating: bool = True) -> None:
        self.data_name = ipc_name("hal", "data", instance)
        self.meta_name = ipc_name("hal", "meta", instance)
        self.mutex_name = ipc_name("hal", "mutex", instance)
        if not is_creating:
            try:
                posix_ipc.SharedMemory(self.meta_name).close_fd()
            except posix_ipc.ExistentialError:
                raise HalError("HAL is not running (no HAL shared memory)") from None
        self._mutex = posix_ipc.Semaphore(self.mutex_name, posix_ipc.O_CREAT, initial_value=1)
        self._local = threading.RLock()
        self._depth = 0
        data_shm = posix_ipc.SharedMemory(self.data_name, posix_ipc.O_CREAT, size=DATA_BYTES)
        meta_shm = posix_ipc.SharedMemory(self.meta_name, posix_ipc.O_CREAT, size=META_BYTES)
        self._data_map = mmap.mmap(data_shm.fd, DATA_BYTES)
        self._meta_map = mmap.mmap(meta_shm.fd, META_BYTES)
        data_shm.close_fd()
        meta_shm.close_fd()
        whole = memoryview(self._data_map)
        self._header = whole[:HEADER_BYTES].cast("q")
        self.ptr = whole[HEADER_BYTES : HEADER_BYTES + NSLOTS * 4].cast("i")
        values = whole[HEADER_BYTES + NSLOTS * 4 :]
        self.f = values.cast("d")
        self.q = values.cast("q")
        self.u = values.cast("Q")
        self._views = [whole, values, self._header, self.ptr, self.f, self.q, self.u]
        self._cached_gen = -1
        self._meta: dict[str, Any] = {}
        with self._locked():
            if self._header[1] == 0:
                with self.edit():
                    pass  # the first process publishes an empty HAL

    # ------------------------------------------------------------ metadata
    @property
    def generation(self) -> int:
        return self._header[0]

    @property
    def meta(self) -> dict[str, Any]:
        return self.snapshot()

    def _load(self) -> None:
        gen = self._header[0]
        # header[1] = 2 * length + (1 when the document is in the second half): one
        # 8-byte store publishes both
        length, start = self._header[1] // 2, (self._header[1] % 2) * (META_BYTES // 2)
        if length == 0:
            self._meta = _empty_meta()
        else:
            try:
                self._meta = msgpack.unpackb(
                    self._meta_map[start : start + length], strict_map_key=False
                )
            except (ValueError, msgpack.UnpackException) as exc:
                raise HalError(f"HAL metadata is damaged ({exc})") from None
        self._cached_gen = gen

    @contextlib.contextmanager
    def _locked(self) -> Iterator[None]:
        with self._local:
            if self._depth == 0 and not self._mutex_acquire():
                print("HAL: mutex held too long by a dead process; taking it over", file=sys.stderr)
            self._depth += 1
            try:
                yield
            finally:
                self._depth -= 1
                if self._depth == 0:
                    self._mutex.release()

    def _mutex_acquire(self) -> bool:
        try:
            self._mutex.acquire(LOCK_TIMEOUT_S)
            return True
        except posix_ipc.BusyError:
            return False

    @contextlib.contextmanager
    def edit(self) -> Iterator[dict[str, Any]]:
        """Lock the HAL, yield the metadata to change, then publish it.

        Nested calls join the outermost one, which publishes once: wrap many changes in one
        ``edit`` to make them fast and atomic. An exception discards every change.
        """
        with self._locked():
            outermost = self._depth == 1
            if outermost:
                self._load()
            try:
                yield self._meta
            except BaseException:
                if outermost:
                    self._cached_gen = -1  # drop the half-made changes: reload next time
                raise
            if outermost:
                blob = msgpack.packb(self._meta)
                half = META_BYTES // 2
                if len(blob) > half:
                    self._cached_gen = -1
                    raise HalError("HAL metadata area is full")
                # write the half not in use, then switch: a writer dying half-way through
                # leaves the previous document intact
                is_second = self._header[1] % 2 == 0
                start = half if is_second else 0
                self._meta_map[start : start + len(blob)] = blob
                self._header[1] = 2 * len(blob) + (1 if is_second else 0)
                self._header[0] = self._cached_gen + 1
                self._cached_gen += 1

    def close(self) -> None:
        for view in reversed(self._views):
            view.release()
        self._data_map.close()
        self._meta_map.close()
        self._mutex.close()

    def destroy(self) -> None:
        """Remove the shared segments and the mutex (the HAL owner does this at exit)."""
        for remove, name in (
            (posix_ipc.unlink_shared_memory, self.data_name),
            (posix_ipc.unlink_shared_memory, self.meta_name),
            (posix_ipc.unlink_semaphore, self.mutex_name),
        ):
            with contextlib.suppress(posix_ipc.ExistentialError):
                remove(name)

    # ------------------------------------------------------------ slots
    def _alloc_slot(self, meta: dict[str, Any]) -> int:
        if meta["free"]:
            slot = meta["free"].pop()
        else:
            slot = meta["next_slot"]
            if slot >= NSLOTS:
                raise HalError("HAL out of value slots")
            meta["next_slot"] = slot + 1
        self.ptr[slot] = slot
        self.q[slot] = 0
        return slot

    def read_slot(self, hal_type: int, slot: int) -> int | float:
        if hal_type == HAL_FLOAT:
            return self.f[slot]
        if hal_type in (HAL_U32, HAL_U64):
            return self.u[slot]
        return self.q[slot]

    def write_slot(self, hal_type: int, slot: int, value: Any) -> None:
        stored = wrap_value(hal_type, value)
        if hal_type == HAL_FLOAT:
            self.f[slot] = stored
        elif hal_type in (HAL_U32, HAL_U64):
            self.u[slot] = stored
        else:
            self.q[slot] = stored

    # ------------------------------------------------------------ components
    def new_component(
        self, name: str, kind: str = "user", pid: int | None = None, args: str = ""
    ) -> int:
        check_name("component", name)
        with self.edit() as meta:
            if name in meta["comps"]:
                raise HalError(f"duplicate component name '{name}'")
            comp_id = meta["next_id"]
            meta["next_id"] += 1
            meta["comps"][name] = {
                "id": comp_id,
                "kind": kind,
                "pid": os.getpid() if pid is None else pid,
                "is_ready": False,
                "args": args,
            }
        return comp_id

    def ready(self, comp: str) -> None:
        with self.edit() as meta:
            meta["comps"][comp]["is_ready"] = True

    def remove_component(self, comp: str) -> None:
        """Delete a component with its pins, parameters, functions and threads."""
        with self.edit() as meta:
            if comp not in meta["comps"]:
                raise HalError(f"component '{comp}' not found")
            for name in [n for n, p in meta["pins"].items() if p["owner"] == comp]:
                self._unlink(meta, name)
                meta["free"].append(meta["pins"].pop(name)["slot"])
            for name in [n for n, p in meta["params"].items() if p["owner"] == comp]:
                meta["free"].append(meta["params"].pop(name)["slot"])
            for name in [n for n, f in meta["functs"].items() if f["owner"] == comp]:
                for thread in meta["threads"].values():
                    if name in thread["functs"]:
                        thread["functs"].remove(name)
                del meta["functs"][name]
            for name in [n for n, t in meta["threads"].items() if t["owner"] == comp]:
                for funct in meta["threads"][name]["functs"]:
                    meta["functs"][funct]["users"] -= 1
                meta["free"].append(meta["threads"].pop(name)["overruns_slot"])
            for table in ("pin_alias", "param_alias"):
                owned = meta["pins"] if table == "pin_alias" else meta["params"]
                meta[table] = {k: v for k, v in meta[table].items() if v in owned}
            del meta["comps"][comp]

    # ------------------------------------------------------------ pins and params
    def new_pin(self, comp: str, name: str, hal_type: int, direction: int) -> int:
        """Create a pin owned by ``comp``; returns its slot (its pointer index)."""
        check_name("pin", name)
        if hal_type not in TYPE_NAMES or direction not in (HAL_IN, HAL_OUT, HAL_IO):
            raise HalError(f"pin '{name}': bad type or direction")
        with self.edit() as meta:
            self._check_new_object(meta, name, "pin")
            slot = self._alloc_slot(meta)
            meta["pins"][name] = {
                "owner": comp,
                "type": hal_type,
                "dir": direction,
                "slot": slot,
                "sig": None,
            }
        return slot

    def new_param(self, comp: str, name: str, hal_type: int, direction: int) -> int:
        check_name("parameter", name)
        if hal_type not in TYPE_NAMES or direction not in (HAL_RO, HAL_RW):
            raise HalError(f"parameter '{name}': bad type or direction")
        with self.edit() as meta:
            self._check_new_object(meta, name, "parameter")
            slot = self._alloc_slot(meta)
            meta["params"][name] = {"owner": comp, "type": hal_type, "dir": direction, "slot": slot}
        return slot

    @staticmethod
    def _check_new_object(meta: dict[str, Any], name: str, kind: str) -> None:
        if name in meta["pins"] or name in meta["params"] or name in meta["pin_alias"]:
            raise HalError(f"duplicate {kind} name '{name}'")

    def find_pin(self, name: str) -> tuple[str, dict[str, Any]] | None:
        meta = self.meta
        real = meta["pin_alias"].get(name, name)
        pin = meta["pins"].get(real)
        return (real, pin) if pin is not None else None

    def find_param(self, name: str) -> tuple[str, dict[str, Any]] | None:
        meta = self.meta
        real = meta["param_alias"].get(name, name)
        param = meta["params"].get(real)
        return (real, param) if param is not None else None

    def snapshot(self) -> dict[str, Any]:
        """The current metadata, safe to read from any thread of this process."""
        with self._locked():
            if self._header[0] != self._cached_gen:
                self._load()
            return self._meta

    def versioned_snapshot(self) -> tuple[int, dict[str, Any]]:
        """(generation, metadata) read together."""
        with self._locked():
            return self._header[0], self.snapshot()

    def pin_value(self, pin: dict[str, Any]) -> int | float:
        return self.read_slot(pin["type"], self.ptr[pin["slot"]])

    # ------------------------------------------------------------ signals
    def new_signal(self, name: str, hal_type: int) -> None:
        check_name("signal", name)
        with self.edit() as meta:
            if name in meta["sigs"]:
                raise HalError(f"duplicate signal '{name}'")
            slot = self._alloc_slot(meta)
            meta["sigs"][name] = {
                "type": hal_type,
                "slot": slot,
                "writers": 0,
                "bidirs": 0,
                "readers": 0,
            }

    def delete_signal(self, name: str) -> None:
        with self.edit() as meta:
            if name not in meta["sigs"]:
                raise HalError(f"signal '{name}' not found")
            for pin_name, pin in meta["pins"].items():
                if pin["sig"] == name:
                    self._unlink(meta, pin_name)
            meta["free"].append(meta["sigs"].pop(name)["slot"])

    def link(self, pin_name: str, sig_name: str) -> None:
        """Connect a pin to a signal with LinuxCNC's rules (one writer, same type)."""
        with self.edit() as meta:
            real = meta["pin_alias"].get(pin_name, pin_name)
            pin = meta["pins"].get(real)
            if pin is None:
                raise HalError(f"pin '{pin_name}' not found")
            sig = meta["sigs"].get(sig_name)
            if sig is None:
                raise HalError(f"signal '{sig_name}' not found")
            if pin["sig"] == sig_name:
                return
            if pin["sig"] is not None:
                raise HalError(f"pin '{pin_name}' was already linked to signal '{pin['sig']}'")
            if pin["type"] != sig["type"]:
                raise HalError(f"type mismatch '{pin_name}' <- '{sig_name}'")
            if pin["dir"] == HAL_OUT:
                if sig["writers"] or sig["bidirs"]:
                    writer = self._writer_of(meta, sig_name)
                    raise HalError(
                        f"Signal '{sig_name}' can not add OUT pin '{pin_name}', "
                        f"it already has {'OUT' if sig['writers'] else 'I/O'} pin '{writer}'"
                    )
                sig["writers"] = 1
            elif pin["dir"] == HAL_IO:
                if sig["writers"]:
                    writer = self._writer_of(meta, sig_name)
                    raise HalError(
                        f"Signal '{sig_name}' can not add I/O pin '{pin_name}', "
                        f"it already has OUT pin '{writer}'"
                    )
                sig["bidirs"] += 1
            else:
                sig["readers"] += 1
            if sig["writers"] + sig["bidirs"] + sig["readers"] == 1:
                # the first pin of a signal gives it its value, as LinuxCNC does
                self.q[sig["slot"]] = self.q[self.ptr[pin["slot"]]]
            pin["sig"] = sig_name
            self.ptr[pin["slot"]] = sig["slot"]

    @staticmethod
    def _writer_of(meta: dict[str, Any], sig_name: str) -> str:
        for name, pin in sorted(meta["pins"].items()):
            if pin["sig"] == sig_name and pin["dir"] != HAL_IN:
                return name
        return "?"

    def unlink(self, pin_name: str) -> None:
        with self.edit() as meta:
            real = meta["pin_alias"].get(pin_name, pin_name)
            if real not in meta["pins"]:
                raise HalError(f"pin '{pin_name}' not found")
            self._unlink(meta, real)

    def _unlink(self, meta: dict[str, Any], pin_name: str) -> None:
        pin = meta["pins"][pin_name]
        sig_name = pin["sig"]
        if sig_name is None:
            return
        sig = meta["sigs"][sig_name]
        if pin["dir"] == HAL_OUT:
            sig["writers"] = 0
        elif pin["dir"] == HAL_IO:
            sig["bidirs"] -= 1
        else:
            sig["readers"] -= 1
        # the pin keeps the signal's last value, as LinuxCNC copies it to the dummy
        self.q[pin["slot"]] = self.q[sig["slot"]]
        self.ptr[pin["slot"]] = pin["slot"]
        pin["sig"] = None

    # ------------------------------------------------------------ functions and threads
    def new_funct(self, comp: str, name: str, *, has_fp: bool = True) -> None:
        check_name("function", name)
        with self.edit() as meta:
            if name in meta["functs"]:
                raise HalError(f"duplicate function '{name}'")
            meta["functs"][name] = {"owner": comp, "fp": has_fp, "users": 0}

    def new_thread(self, comp: str, name: str, period_ns: int, *, has_fp: bool = True) -> int:
        """Declare a thread; returns the slot of its overrun counter (``thread_overruns``)."""
        check_name("thread", name)
        with self.edit() as meta:
            if name in meta["threads"]:
                raise HalError(f"duplicate thread name '{name}'")
            slot = self._alloc_slot(meta)
            meta["threads"][name] = {
                "owner": comp,
                "period": int(period_ns),
                "fp": has_fp,
                "functs": [],
                "overruns_slot": slot,
            }
        return slot

    def thread_overruns(self, name: str) -> int:
        """Periods of a thread whose functions ran past the next deadline (our addition to
        LinuxCNC's HAL, kept out of its pin and parameter lists)."""
        thread = self.meta["threads"].get(name)
        if thread is None:
            raise HalError(f"thread '{name}' not found")
        return int(self.q[thread["overruns_slot"]])

    def add_funct(self, funct: str, thread: str, position: int = -1) -> None:
        with self.edit() as meta:
            if funct not in meta["functs"]:
                raise HalError(f"function '{funct}' not found")
            if thread not in meta["threads"]:
                raise HalError(f"thread '{thread}' not found")
            info, chain = meta["functs"][funct], meta["threads"][thread]["functs"]
            if funct in chain:
                raise HalError(f"function '{funct}' already added to thread '{thread}'")
            if info["users"] and not info.get("reentrant", False):
                raise HalError(f"function '{funct}' may only be added to one thread")
            if position > 0:
                chain.insert(position - 1, funct)
            elif position < -1:
                chain.insert(len(chain) + position + 1, funct)
            else:
                chain.append(funct)
            info["users"] += 1

    def del_funct(self, funct: str, thread: str) -> None:
        with self.edit() as meta:
            if funct not in meta["functs"]:
                raise HalError(f"function '{funct}' not found")
            if thread not in meta["threads"]:
                raise HalError(f"thread '{thread}' not found")
            chain = meta["threads"][thread]["functs"]
            if funct not in chain:
                raise HalError(f"function '{funct}' not linked to '{thread}'")
            chain.remove(funct)
            meta["functs"][funct]["users"] -= 1

    def set_running(self, is_running: bool) -> None:
        with self.edit() as meta:
            meta["is_running"] = is_running
