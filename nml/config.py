"""NML configuration files in LinuxCNC's format, parsed once into records (NML-001..035).

::

    B name type host size neut RPC# buffer# max_procs key [options...]
    P name buffer type host ops server timeout master c_num [options...]

Blank lines and ``#`` comments are ignored. Every problem found is reported, each as
``file:line: cause``, in one ``NmlConfigError``; harmless oddities (network options,
``serialPortDevName``, obsolete mutex modes) become warnings. Buffer objects receive these
records and never look at the text again (NML-035).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from nml.errors import NmlConfigError

BUFFER_TYPES = {"SHMEM", "LOCMEM", "FILEMEM", "PHANTOM", "GLOBMEM"}
SUPPORTED_BUFFER_TYPES = {"SHMEM"}
PROCESS_TYPES = {"LOCAL", "REMOTE", "AUTO"}
OPS = {"R", "W", "RW"}
# A P line naming this buffer gives a process's defaults for every buffer (LinuxCNC's emcsvr).
DEFAULT_BUFFER = "default"

_NETWORK_OPTIONS = ("TCP=", "UDP=", "STCP=")
_FLAG_OPTIONS = {
    "broadcast",
    "queue",
    "confirm_write",
    "xdr",
    "ascii",
    "disp",
    "diag",
    "serial",
    "packed",
}
_OBSOLETE_MUTEX = {"none", "no_interrupts", "no_switching"}


class NmlConfigWarning(UserWarning):
    """A configuration option that is accepted but has no effect here."""


@dataclass(frozen=True)
class BufferConfig:
    name: str
    type: str
    host: str
    size: int
    is_neutral: bool
    buffer_number: int
    max_procs: int
    key: int
    is_queue: bool = False
    is_broadcast: bool = False
    mutex: str = "os_sem"
    options: tuple[str, ...] = ()
    file: str = "<string>"
    line: int = 0

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"


@dataclass(frozen=True)
class ProcessConfig:
    name: str
    buffer: str
    type: str
    host: str
    ops: str
    is_server: bool
    timeout: float  # seconds; math.inf blocks forever, 0 never blocks (NML-031)
    is_master: bool
    c_num: int
    options: tuple[str, ...] = ()
    file: str = "<string>"
    line: int = 0

    @property
    def can_read(self) -> bool:
        return "R" in self.ops

    @property
    def can_write(self) -> bool:
        return "W" in self.ops


@dataclass
class NmlConfig:
    path: str
    buffers: dict[str, BufferConfig] = field(default_factory=dict)
    processes: list[ProcessConfig] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def process(self, process: str, buffer: str) -> ProcessConfig:
        """The P line that connects ``process`` to ``buffer`` (or the process's default)."""
        fallback = None
        for entry in self.processes:
            if entry.name == process and entry.buffer == buffer:
                return entry
            if entry.name == process and entry.buffer == DEFAULT_BUFFER:
                fallback = entry
        if fallback is not None and buffer in self.buffers:
            return fallback
        known = sorted({p.name for p in self.processes if p.buffer == buffer})
        raise NmlConfigError(
            [
                f"{self.path}: no P line connects process '{process}' to buffer '{buffer}'"
                + (f" (processes of that buffer: {', '.join(known)})" if known else "")
            ]
        )

    def processes_of(self, buffer: str) -> list[ProcessConfig]:
        return [p for p in self.processes if p.buffer == buffer]


class MessageRoom(NamedTuple):
    """What a buffer's messages need: the largest one encoded, and the smallest B-line
    size that holds it (``nml.channels.message_room``, from the shared-memory layout)."""

    largest: int
    needed: int


def load(
    path: str | Path, *, message_room: Callable[[BufferConfig], MessageRoom | None] | None = None
) -> NmlConfig:
    """Parse an NML file; ``message_room`` says, per buffer, the room its messages need."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise NmlConfigError([f"{path}:0: cannot read NML file: {exc.strerror}"]) from exc
    return parse(text, str(path), message_room=message_room)


def parse(
    text: str,
    path: str = "<string>",
    *,
    message_room: Callable[[BufferConfig], MessageRoom | None] | None = None,
) -> NmlConfig:
    config = NmlConfig(path)
    errors: list[str] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        where = f"{path}:{lineno}"
        kind = words[0]
        if kind == "B":
            buffer = _parse_buffer(words, path, lineno, errors, config.warnings)
            if buffer is not None:
                config.buffers.setdefault(buffer.name, buffer)
                _check_duplicate_buffer(buffer, config, errors)
        elif kind == "P":
            process = _parse_process(words, path, lineno, errors)
            if process is not None:
                config.processes.append(process)
        else:
            errors.append(f"{where}: line must start with B (buffer) or P (process), got '{kind}'")
    _check_processes(config, errors)
    if message_room is not None:
        _check_sizes(config, message_room, errors)
    for text_warning in config.warnings:
        warnings.warn(text_warning, NmlConfigWarning, stacklevel=2)
    if errors:
        raise NmlConfigError(errors)
    return config


# ----------------------------------------------------------------------------- B lines

_B_FIELDS = ("name", "type", "host", "size", "neut", "RPC#", "buffer#", "max_procs", "key")


def _parse_buffer(
    words: list[str], path: str, lineno: int, errors: list[str], notes: list[str]
) -> BufferConfig | None:
    where = f"{path}:{lineno}"
    fields = words[1:]
    if len(fields) < len(_B_FIELDS):
        missing = ", ".join(_B_FIELDS[len(fields) :])
        errors.append(f"{where}: B line has {len(fields)} fields, missing: {missing}")
        return None
    name, buf_type, host = fields[0], fields[1], fields[2]
    numbers = {}
    for label, text in zip(_B_FIELDS[3:], fields[3:9], strict=True):
        value = _to_int(text)
        if value is None:
            errors.append(f"{where}: buffer {name}: {label} '{text}' is not a number")
            return None
        numbers[label] = value
    is_valid = True
    if buf_type not in BUFFER_TYPES:
        errors.append(
            f"{where}: buffer {name}: unknown buffer type '{buf_type}' "
            f"(one of {', '.join(sorted(BUFFER_TYPES))})"
        )
        is_valid = False
    elif buf_type not in SUPPORTED_BUFFER_TYPES:
        errors.append(f"{where}: buffer {name}: type {buf_type} is not supported (use SHMEM)")
        is_valid = False
    for label in ("size", "max_procs"):
        if numbers[label] <= 0:
            errors.append(f"{where}: buffer {name}: {label} must be positive")
            is_valid = False
    if numbers["neut"] not in (0, 1):
        errors.append(f"{where}: buffer {name}: neut must be 0 or 1")
        is_valid = False
    options = tuple(fields[9:])
    is_queue, mutex = _buffer_options(name, options, where, errors, notes)
    is_broadcast = "broadcast" in options
    if is_broadcast and not is_queue:
        errors.append(f"{where}: buffer {name}: broadcast needs the queue option")
        is_valid = False
    if not is_valid:
        return None
    return BufferConfig(
        name=name,
        type=buf_type,
        host=host,
        size=numbers["size"],
        is_neutral=bool(numbers["neut"]),
        buffer_number=numbers["buffer#"],
        max_procs=numbers["max_procs"],
        key=numbers["key"],
        is_queue=is_queue,
        is_broadcast=is_broadcast,
        mutex=mutex,
        options=options,
        file=path,
        line=lineno,
    )


def _buffer_options(
    name: str, options: tuple[str, ...], where: str, errors: list[str], notes: list[str]
) -> tuple[bool, str]:
    is_queue = False
    mutex = "os_sem"
    words = list(options)
    index = 0
    while index < len(words):
        option = words[index]
        index += 1
        if option == "queue":
            is_queue = True
        elif option.startswith("mutex="):
            mode = option.split("=", 1)[1]
            if mode == "mao" and index < len(words) and words[index] == "split":
                mode, index = "mao_split", index + 1
            if mode in ("os_sem", "mao_split"):
                mutex = mode
            elif mode in _OBSOLETE_MUTEX:
                notes.append(f"{where}: buffer {name}: mutex={mode} is not usable; using os_sem")
            else:
                errors.append(f"{where}: buffer {name}: unknown mutex mode '{mode}'")
        elif option.startswith(_NETWORK_OPTIONS):
            port = option.split("=", 1)[1]
            if _to_int(port) is None:
                errors.append(f"{where}: buffer {name}: {option}: port is not a number")
            else:
                notes.append(
                    f"{where}: buffer {name}: {option} ignored (no remote access; local only)"
                )
        elif option.startswith("serialPortDevName="):
            notes.append(f"{where}: buffer {name}: {option} ignored (undocumented option)")
        elif option.startswith(("bsem=", "passwd=", "vme_addr=", "bufline=", "procline=")):
            continue
        elif option in _FLAG_OPTIONS or "=" in option:
            continue  # encodings and diagnostics: only meaningful for remote transports
        else:
            errors.append(f"{where}: buffer {name}: unknown option '{option}'")
    return is_queue, mutex


def _check_duplicate_buffer(buffer: BufferConfig, config: NmlConfig, errors: list[str]) -> None:
    for other in config.buffers.values():
        if other is buffer:
            continue
        clash = None
        if other.name == buffer.name:
            clash = f"name '{buffer.name}'"
        elif other.key == buffer.key:
            clash = f"key {buffer.key}"
        elif other.buffer_number == buffer.buffer_number:
            clash = f"buffer# {buffer.buffer_number}"
        if clash:
            errors.append(
                f"{buffer.where}: buffer {buffer.name}: duplicate {clash} "
                f"(already used at line {other.line} by {other.name})"
            )
            return


# ----------------------------------------------------------------------------- P lines

_P_FIELDS = ("name", "buffer", "type", "host", "ops", "server", "timeout", "master", "c_num")


def _parse_process(
    words: list[str], path: str, lineno: int, errors: list[str]
) -> ProcessConfig | None:
    where = f"{path}:{lineno}"
    fields = words[1:]
    if len(fields) < len(_P_FIELDS):
        missing = ", ".join(_P_FIELDS[len(fields) :])
        errors.append(f"{where}: P line has {len(fields)} fields, missing: {missing}")
        return None
    name, buffer, proc_type, host, ops = fields[:5]
    who = f"process {name} on {buffer}"
    is_valid = True
    if proc_type.upper() not in PROCESS_TYPES:
        errors.append(f"{where}: {who}: type '{proc_type}' must be LOCAL or REMOTE")
        is_valid = False
    if ops.upper() not in OPS:
        errors.append(f"{where}: {who}: ops '{ops}' must be R, W or RW")
        is_valid = False
    server, master, c_num = (_to_int(fields[i]) for i in (5, 7, 8))
    timeout = _to_timeout(fields[6])
    for label, value, text in (
        ("server", server, fields[5]),
        ("timeout", timeout, fields[6]),
        ("master", master, fields[7]),
        ("c_num", c_num, fields[8]),
    ):
        if value is None:
            errors.append(f"{where}: {who}: {label} '{text}' is not a number")
            is_valid = False
    if not is_valid:
        return None
    return ProcessConfig(
        name=name,
        buffer=buffer,
        type=proc_type.upper(),
        host=host,
        ops=ops.upper(),
        is_server=bool(server),
        timeout=timeout,  # type: ignore[arg-type]
        is_master=bool(master),
        c_num=c_num,  # type: ignore[arg-type]
        options=tuple(fields[9:]),
        file=path,
        line=lineno,
    )


def _check_processes(config: NmlConfig, errors: list[str]) -> None:
    seen_c_num: dict[tuple[str, int], ProcessConfig] = {}
    for proc in config.processes:
        where = f"{proc.file}:{proc.line}"
        if proc.buffer == DEFAULT_BUFFER:
            continue
        buffer = config.buffers.get(proc.buffer)
        if buffer is None:
            errors.append(
                f"{where}: process {proc.name}: buffer '{proc.buffer}' is not defined by a B line"
            )
            continue
        if not 0 <= proc.c_num < buffer.max_procs:
            errors.append(
                f"{where}: process {proc.name} on {proc.buffer}: c_num {proc.c_num} out of range "
                f"0..{buffer.max_procs - 1} (max_procs {buffer.max_procs})"
            )
        other = seen_c_num.get((proc.buffer, proc.c_num))
        if other is not None and other.name != proc.name:
            errors.append(
                f"{where}: process {proc.name} on {proc.buffer}: c_num {proc.c_num} already used "
                f"by process {other.name} at line {other.line}"
            )
        seen_c_num.setdefault((proc.buffer, proc.c_num), proc)
        if proc.type == "REMOTE" and not any(
            p.is_server for p in config.processes if p.buffer in (proc.buffer, DEFAULT_BUFFER)
        ):
            errors.append(
                f"{where}: process {proc.name} is REMOTE on {proc.buffer}, "
                "but no process is the server of that buffer"
            )


def _check_sizes(
    config: NmlConfig, message_room: Callable[[BufferConfig], MessageRoom | None], errors: list[str]
) -> None:
    for buffer in config.buffers.values():
        room = message_room(buffer)
        if room is None:
            continue
        largest, needed = room
        if buffer.size < needed:
            errors.append(
                f"{buffer.where}: buffer {buffer.name}: size {buffer.size} is too small for its "
                f"largest message ({largest} bytes encoded; needs at least {needed})"
            )


# ----------------------------------------------------------------------------- helpers


def _to_int(text: str) -> int | None:
    try:
        return int(text, 0)
    except ValueError:
        try:
            value = float(text)
        except ValueError:
            return None
        return int(value) if value.is_integer() else None


def _to_timeout(text: str) -> float | None:
    if text.upper() in ("INF", "INFINITE", "FOREVER"):
        return math.inf
    try:
        value = float(text)
    except ValueError:
        return None
    if math.isnan(value):
        return None
    return math.inf if value < 0 else value


def describe_timeout(timeout: float) -> str:
    return "forever" if math.isinf(timeout) else f"{timeout:g} s"


__all__ = [
    "BufferConfig",
    "NmlConfig",
    "NmlConfigError",
    "ProcessConfig",
    "describe_timeout",
    "load",
    "parse",
]
