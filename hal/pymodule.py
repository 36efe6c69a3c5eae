"""LinuxCNC's Python ``hal`` module, as ``import hal`` gives it to a user's script.

Our package is itself named ``hal``: its top level lends every name below (``hal.component``,
``hal.HAL_FLOAT``, ``hal.connect``...) from this module on first use, while our own modules
live under it (``hal.core``, ``hal.api``...) with no name in common. So a script written for
LinuxCNC, or a Python program started by ``loadusr`` (which runs it with this controller's
Python), imports ours and talks to this controller's HAL (the instance of
``$CNC_INSTANCE``).

Behaviour follows LinuxCNC 2.9's ``halmodule.cc`` and ``hal.py``, quirks included:
``new_sig``, ``connect``, ``disconnect`` and ``set_p`` return True when they *failed*;
``getpins()`` maps names to values; a component's pins are also its attributes and items;
values out of a pin type's range raise ``OverflowError``; SIGTERM (``halcmd unload``)
raises ``KeyboardInterrupt`` in a program that made a component and handles no SIGTERM.
"""

from __future__ import annotations

import atexit
import contextlib
import mmap
import os
import signal
import threading
from pathlib import Path
from typing import Any

import posix_ipc

from cnc.stdio import keep_lines_whole
from hal import LINUXCNC_NAMES, show
from hal.api import shared_hal
from hal.core import (
    HAL_BIT,
    HAL_FLOAT,
    HAL_IN,
    HAL_IO,
    HAL_NAME_LEN,
    HAL_OUT,
    HAL_RO,
    HAL_RW,
    HAL_S32,
    HAL_S64,
    HAL_U32,
    HAL_U64,
    Hal,
    HalError,
    parse_value,
)
from hal.fifo import (
    CFG_LETTERS,
    SAMPLER_BASE,
    STREAMER_BASE,
    Fifo,
    channel_of_key,
    decode,
    parse_cfg,
)
from hal.fifo import encode as encode_row
from nml.ipcnames import ipc_name

__all__ = list(LINUXCNC_NAMES)  # (listed in hal/__init__.py, which lends them out)


class error(HalError):  # noqa: N818 - LinuxCNC's name
    """``hal.error``: a HAL operation was refused."""


MSG_NONE, MSG_ERR, MSG_WARN, MSG_INFO, MSG_DBG, MSG_ALL = range(6)
is_kernelspace, is_userspace = 0, 1
kernel_version = "Not Available"
sampler_base, streamer_base = SAMPLER_BASE, STREAMER_BASE


def _is_realtime_kernel() -> bool:
    with contextlib.suppress(OSError):
        return Path("/sys/kernel/realtime").read_text().strip() == "1"
    return False


is_rt = int(_is_realtime_kernel())
is_sim = 1 - is_rt

_msg_level = MSG_ERR
_INT_RANGES = {
    HAL_S32: (-(1 << 31), (1 << 31) - 1),
    HAL_U32: (0, (1 << 32) - 1),
    HAL_S64: (-(1 << 63), (1 << 63) - 1),
    HAL_U64: (0, (1 << 64) - 1),
}
_TYPE_WORDS = {HAL_BIT: "BIT", HAL_FLOAT: "FLOAT", HAL_S32: "S32", HAL_U32: "U32"}
_DIR_WORDS = {HAL_IN: "IN", HAL_OUT: "OUT", HAL_IO: "IO", HAL_RO: "RO", HAL_RW: "RW"}


def _hal() -> Hal:
    return shared_hal()


def _to_hal(hal_type: int, value: Any) -> int | float:
    """A Python value for a pin or parameter, with LinuxCNC's conversions and errors."""
    if hal_type == HAL_BIT:
        return 1 if value else 0
    if hal_type == HAL_FLOAT:
        try:
            return float(value)
        except OverflowError:
            raise
        except (TypeError, ValueError):
            raise TypeError(f"Number expected, not {type(value).__name__}") from None
    number = value if isinstance(value, int) else int(value)
    low, high = _INT_RANGES[hal_type]
    if not low <= number <= high:
        raise OverflowError(f"Value {number} out of range")
    return number


def _from_slot(hal: Hal, hal_type: int, slot: int) -> bool | int | float:
    value = hal.read_slot(hal_type, slot)
    return bool(value) if hal_type == HAL_BIT else value


class item:
    """A pin or parameter of a component (``hal.item``): get, set and what it is."""

    def __init__(self, hal: Hal, short_name: str, hal_type: int, direction: int, slot: int) -> None:
        self._hal, self._name, self._type, self._dir, self._slot = (
            hal,
            short_name,
            hal_type,
            direction,
            slot,
        )
        self._is_pin = direction in (HAL_IN, HAL_OUT, HAL_IO)

    def _current_slot(self) -> int:
        return self._hal.ptr[self._slot] if self._is_pin else self._slot

    def get(self) -> bool | int | float:
        return _from_slot(self._hal, self._type, self._current_slot())

    def set(self, value: Any) -> None:
        self._hal.write_slot(self._type, self._current_slot(), _to_hal(self._type, value))

    def get_name(self) -> str:
        return self._name

    def get_type(self) -> int:
        return self._type

    def get_dir(self) -> int:
        return self._dir

    def is_pin(self) -> bool:
        return self._is_pin

    def __repr__(self) -> str:
        kind = "pin" if self._is_pin else "param"
        type_word = _TYPE_WORDS.get(self._type, "unknown")
        return f'<hal {kind} "{self._name}" {type_word}-{_DIR_WORDS.get(self._dir, "unknown")}>'


class _Wrapped(item):
    """hal.py's item wrappers: ``.value``, ``.name``, ``.type``, ``.dir``."""

    name = property(lambda self: self.get_name())
    type = property(lambda self: self.get_type())
    dir = property(lambda self: self.get_dir())
    value = property(lambda self: self.get(), lambda self, value: self.set(value))


class Pin(_Wrapped):
    """What ``component.newpin`` returns."""


class Param(_Wrapped):
    """What ``component.newparam`` returns."""


class component:
    """A userspace HAL component (``hal.component(name, prefix=name)``).

    Pins and parameters are made with ``newpin``/``newparam`` and read or written as items
    (``c["out"] = 1``) or attributes (``c.out``); ``ready()`` tells ``loadusr -W`` the
    component is ready; ``exit()`` (or the end of the program) removes it.
    """

    def __init__(self, name: str, prefix: str | None = None) -> None:
        hal = _hal()
        object.__setattr__(self, "_hal", hal)
        object.__setattr__(self, "_name", name)
        object.__setattr__(self, "_prefix", name if prefix is None else prefix)
        object.__setattr__(self, "_items", {})
        try:
            comp_id = hal.new_component(name, "user", os.getpid())
        except HalError as exc:
            raise error(str(exc)) from None
        object.__setattr__(self, "_id", comp_id)
        atexit.register(self.exit)
        _interrupt_on_sigterm()
        keep_lines_whole()  # (a component program shares halcmd's terminal)

    # ------------------------------------------------------------ pins and params
    def _check_live(self) -> None:
        if not self._id:
            raise RuntimeError("Invalid operation on closed HAL component")

    def _new_item(self, name: str, hal_type: int, direction: int, kind: type[item]) -> item:
        self._check_live()
        label = "pin" if kind is Pin else "parameter"
        if name in self._items:
            raise ValueError(f"Duplicate {label} name '{name}'")
        if hal_type not in (HAL_BIT, HAL_FLOAT, HAL_S32, HAL_U32, HAL_S64, HAL_U64):
            raise error(f"Invalid {'pin' if kind is Pin else 'param'} type {hal_type}")
        full = f"{self._prefix}.{name}"
        if len(full) > HAL_NAME_LEN:
            raise error(f'Invalid pin name length "{full}": max = {HAL_NAME_LEN} characters')
        try:
            if kind is Pin:
                slot = self._hal.new_pin(self._name, full, hal_type, direction)
            else:
                slot = self._hal.new_param(self._name, full, hal_type, direction)
        except HalError as exc:
            raise error(str(exc)) from None
        made = kind(self._hal, name, hal_type, direction, slot)
        self._items[name] = made
        return made

    def newpin(self, name: str, hal_type: int, direction: int) -> Pin:
        return self._new_item(name, hal_type, direction, Pin)  # type: ignore[return-value]

    def newparam(self, name: str, hal_type: int, direction: int) -> Param:
        return self._new_item(name, hal_type, direction, Param)  # type: ignore[return-value]

    def _find(self, name: str) -> item:
        found = self._items.get(name)
        if found is None:
            raise AttributeError(f"Pin '{name}' does not exist")
        return found

    def getitem(self, name: str) -> item:
        self._check_live()
        found = self._find(name)
        return item(found._hal, found._name, found._type, found._dir, found._slot)

    def getpin(self, name: str) -> Pin:
        found = self._find(name)
        if not found.is_pin():
            raise TypeError("Must be constructed from pin object")
        return Pin(found._hal, found._name, found._type, found._dir, found._slot)

    def getparam(self, name: str) -> Param:
        found = self._find(name)
        if found.is_pin():
            raise TypeError("Must be constructed from param object")
        return Param(found._hal, found._name, found._type, found._dir, found._slot)

    def getpins(self) -> dict[str, Any]:
        """Every pin's and parameter's value by (short) name."""
        self._check_live()
        return {name: found.get() for name, found in sorted(self._items.items())}

    # ------------------------------------------------------------ life
    def ready(self) -> None:
        self._check_live()
        self._hal.ready(self._name)

    def unready(self) -> None:
        self._check_live()
        with self._hal.edit() as meta:
            meta["comps"][self._name]["is_ready"] = False

    def exit(self) -> None:
        if self._id:
            object.__setattr__(self, "_id", 0)
            # at interpreter exit the HAL may already be gone: nothing left to remove then
            with contextlib.suppress(HalError, ValueError, OSError, KeyError):
                self._hal.remove_component(self._name)

    def getprefix(self) -> str:
        return self._prefix

    def setprefix(self, prefix: str) -> None:
        object.__setattr__(self, "_prefix", prefix)

    # ------------------------------------------------------------ item access
    def __getitem__(self, name: str) -> Any:
        self._check_live()
        return self._find(name).get()

    def __setitem__(self, name: str, value: Any) -> None:
        self._check_live()
        self._find(name).set(value)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        self._check_live()
        return self._find(name).get()

    def __setattr__(self, name: str, value: Any) -> None:
        self._check_live()
        self._find(name).set(value)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"<hal component {self._name}({self._id}) with {len(self._items)} pins and params>"

    def __enter__(self) -> component:
        return self

    def __exit__(self, *exc: object) -> None:
        self.exit()


def _interrupt_on_sigterm() -> None:
    """As LinuxCNC's module: SIGTERM (``halcmd unload``) raises KeyboardInterrupt, unless
    the program handles SIGTERM itself."""
    is_main = threading.current_thread() is threading.main_thread()
    if is_main and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, signal.default_int_handler)


# ---------------------------------------------------------------- module functions
def pin_has_writer(name: str) -> bool:
    hal = _hal()
    found = hal.find_pin(name)
    if found is None:
        raise NameError(f"Pin `{name}' does not exist")
    sig = found[1]["sig"]
    return bool(sig and hal.meta["sigs"][sig]["writers"])


def component_exists(name: str) -> bool:
    return name in _hal().meta["comps"]


def component_is_ready(name: str) -> bool:
    comp = _hal().meta["comps"].get(name)
    return bool(comp and comp["is_ready"])


def set_msg_level(level: int) -> None:
    global _msg_level
    _msg_level = int(level)


def get_msg_level() -> int:
    return _msg_level


def new_sig(name: str, hal_type: int) -> bool:
    """Make a signal; True when that failed (LinuxCNC returns the failure)."""
    if hal_type not in (HAL_BIT, HAL_FLOAT, HAL_S32, HAL_U32, HAL_S64, HAL_U64):
        raise RuntimeError("not a valid HAL signal type")
    try:
        _hal().new_signal(name, hal_type)
    except HalError:
        return True
    return False


def connect(pin_name: str, sig_name: str) -> bool:
    """Link a pin to a signal; True when that failed."""
    try:
        _hal().link(pin_name, sig_name)
    except HalError:
        return True
    return False


def disconnect(pin_name: str) -> bool:
    """Unlink a pin; True when that failed."""
    try:
        _hal().unlink(pin_name)
    except HalError:
        return True
    return False


def set_p(name: str, value: str) -> bool:
    """Set a parameter or an unlinked input pin from text, as ``halcmd setp``; True when
    the text is not a value of its type."""
    hal = _hal()
    param = hal.find_param(name)
    if param is not None:
        info = param[1]
        if info["dir"] == HAL_RO:
            raise RuntimeError("param not writable")
        slot = info["slot"]
    else:
        pin = hal.find_pin(name)
        if pin is None:
            raise RuntimeError("pin not found")
        info = pin[1]
        if info["dir"] == HAL_OUT:
            raise RuntimeError("pin not writable")
        if info["sig"] is not None:
            raise RuntimeError("pin connected to signal")
        slot = info["slot"]
    try:
        hal.write_slot(info["type"], slot, parse_value(info["type"], value))
    except HalError:
        return True
    return False


def get_value(name: str) -> bool | int | float:
    """The value of a parameter, pin or signal, by name."""
    hal = _hal()
    param = hal.find_param(name)
    if param is not None:
        return _from_slot(hal, param[1]["type"], param[1]["slot"])
    pin = hal.find_pin(name)
    if pin is not None:
        return _from_slot(hal, pin[1]["type"], hal.ptr[pin[1]["slot"]])
    sig = hal.meta["sigs"].get(name)
    if sig is not None:
        return _from_slot(hal, sig["type"], sig["slot"])
    raise RuntimeError(f"Can't set value: pin / param {name} not found")


def get_info_pins() -> list[dict[str, Any]]:
    """Every pin: ``{"NAME", "VALUE", "DIRECTION", "TYPE"}``, sorted by name."""
    hal = _hal()
    return [
        {
            "NAME": shown,
            "VALUE": _from_slot(hal, pin["type"], hal.ptr[pin["slot"]]),
            "DIRECTION": pin["dir"],
            "TYPE": pin["type"],
        }
        for shown, _real, pin in show.pins_in_order(hal.meta)
    ]


def get_info_signals() -> list[dict[str, Any]]:
    """Every signal: ``{"NAME", "VALUE", "DRIVER" (its output pin or None), "TYPE"}``."""
    hal = _hal()
    meta = hal.meta
    linked = show.pins_of_signals(meta)
    rows = []
    for name, sig in sorted(meta["sigs"].items()):
        driver = next((pin for pin, d in linked.get(name, []) if d == HAL_OUT), None)
        rows.append(
            {
                "NAME": name,
                "VALUE": _from_slot(hal, sig["type"], sig["slot"]),
                "DRIVER": driver,
                "TYPE": sig["type"],
            }
        )
    return rows


def get_info_params() -> list[dict[str, Any]]:
    """Every parameter: ``{"NAME", "DIRECTION", "VALUE"}``, sorted by name."""
    hal = _hal()
    return [
        {
            "NAME": shown,
            "DIRECTION": param["dir"],
            "VALUE": _from_slot(hal, param["type"], param["slot"]),
        }
        for shown, _real, param in show.params_in_order(hal.meta)
    ]


# ---------------------------------------------------------------- streams and shared memory
class stream:
    """A sampler/streamer FIFO (LinuxCNC's ``hal.stream``).

    ``stream(comp, key, depth, types)`` creates one (``types``: letters f b s u);
    ``stream(comp, key[, types])`` attaches to an existing one, checking its types.
    ``hal.streamer_base + N`` is the FIFO of ``streamer.N``, ``hal.sampler_base + N`` that
    of ``sampler.N``.
    """

    def __init__(self, comp: component, key: int, *args: Any) -> None:
        if not isinstance(comp, component):
            raise TypeError("hal.stream: the first argument must be a hal.component")
        self._key = int(key)
        self._is_creator = len(args) == 2
        self.sampleno = 0
        channel = channel_of_key(self._key)
        try:
            if self._is_creator:
                depth, types = int(args[0]), str(args[1])
                self._fifo = Fifo.create(channel, depth, parse_cfg(types))
            else:
                if len(args) > 1:
                    raise TypeError("hal.stream takes (comp, key, depth, types) or (comp, key)")
                self._fifo = Fifo.open(channel)
                if args and args[0] is not None and parse_cfg(str(args[0])) != self._fifo.types:
                    self._fifo.close()
                    raise HalError(f"Type mismatch: stream {channel} holds {self.element_types!r}")
        except HalError as exc:
            raise OSError(22, f"Invalid argument ({exc})") from None

    @property
    def element_types(self) -> bytes:
        return "".join(CFG_LETTERS[t] for t in self._fifo.types).encode()

    @property
    def readable(self) -> bool:
        return self._fifo.count() > 0

    @property
    def writable(self) -> bool:
        return self._fifo.is_writable()

    @property
    def depth(self) -> int:
        return self._fifo.count()

    @property
    def maxdepth(self) -> int:
        return self._fifo.depth

    @property
    def num_underruns(self) -> int:
        return self._fifo.underruns

    @property
    def num_overruns(self) -> int:
        return self._fifo.overruns

    def read(self) -> tuple[Any, ...] | None:
        """The oldest row as a tuple, or None when empty (counted as an underrun)."""
        row = self._fifo.get()
        if row is None:
            return None
        self.sampleno = int(row[0])
        types = self._fifo.types
        values = decode(row[1:], types)
        return tuple(bool(v) if t == HAL_BIT else v for v, t in zip(values, types, strict=True))

    def write(self, values: tuple[Any, ...]) -> None:
        """Append one row; OSError (and an overrun counted) when the FIFO is full."""
        if not isinstance(values, tuple):
            raise TypeError("hal.stream.write: the argument must be a tuple")
        types = self._fifo.types
        if len(values) < len(types):
            raise ValueError("Too few elements to unpack")
        if len(values) > len(types):
            raise ValueError("Too many elements to unpack")
        checked = [_to_hal(t, v) for v, t in zip(values, types, strict=True)]
        if not self._fifo.put(encode_row(checked, types)):
            raise OSError(28, "No space left on device")

    def __del__(self) -> None:
        fifo = getattr(self, "_fifo", None)
        if fifo is not None:
            if self._is_creator:
                fifo.unlink()
            fifo.close()

    def __repr__(self) -> str:
        return f"<stream 0x{self._key:x}{' creator' if self._is_creator else ''}>"


class shm:
    """A block of shared memory by key (LinuxCNC's ``hal.shm(comp, key, size)``)."""

    def __init__(self, comp: component, key: int, size: int) -> None:
        self._key, self._size = int(key), int(size)
        self._name = ipc_name("hal", f"shm.{self._key:x}")
        memory = posix_ipc.SharedMemory(self._name, posix_ipc.O_CREAT, size=self._size)
        self._map = mmap.mmap(memory.fd, self._size)
        memory.close_fd()

    def getbuffer(self) -> memoryview:
        return memoryview(self._map)

    def setsize(self, size: int) -> None:
        if size > self._size:
            raise ValueError("the shared memory block cannot grow")
        self._size = int(size)

    def __repr__(self) -> str:
        return f"<shm key=0x{self._key:x} size={self._size}>"
