"""The controller's standard channels and a process's view of all its buffers (NML-036, 071).

``Nml(config, process)`` opens every buffer the process has a P line for: the channel object
of NML-036. ``message_room`` tells the configuration check how large the messages are that
the controller writes to each standard buffer, so an undersized B line is caught when the
file is parsed, not at the first write.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

from nml import config as nml_config
from nml.codec import Encoding, max_encoded_size
from nml.config import BufferConfig, MessageRoom, NmlConfig
from nml.errors import NmlAccessError
from nml.message import MessageKind, NMLmsg, Receiver
from nml.registry import REGISTRY
from nml.shmem import BufferLayout, ShmBuffer

# Buffer names of LinuxCNC's linuxcnc.nml (NML-071) and of our task <-> motion pair.
EMC_COMMAND = "emcCommand"
EMC_STATUS = "emcStatus"
EMC_ERROR = "emcError"
TOOL_COMMAND = "toolCmd"
TOOL_STATUS = "toolSts"
MOTION_COMMAND = "motCommand"
MOTION_STATUS = "motStatus"

DEFAULT_NML_FILE = Path(__file__).resolve().parent.parent / "configs" / "common" / "cnc.nml"


def _is_catalogue(cls: type[NMLmsg]) -> bool:
    """Only the EMC catalogue sizes the standard buffers, not messages a test declares."""
    return cls.__module__.startswith("nml.")


def is_motion_type(type_id: int) -> bool:
    """Commands motion carries out (declared ``receiver=Receiver.MOTION``)."""
    return _receiver_of(type_id) is Receiver.MOTION


def is_io_type(type_id: int) -> bool:
    """Commands iocontrol carries out (declared ``receiver=Receiver.IO``)."""
    return _receiver_of(type_id) is Receiver.IO


def _receiver_of(type_id: int) -> Receiver | None:
    cls = REGISTRY.by_type(type_id)
    return None if cls is None else cls.RECEIVER


def messages_of(buffer_name: str) -> list[type[NMLmsg]]:
    """The message classes the controller writes to a standard buffer (empty: unknown)."""
    import nml.emc  # noqa: F401  (registers the catalogue)

    commands = [c for c in REGISTRY.of_kind(MessageKind.COMMAND) if _is_catalogue(c)]
    by_name = REGISTRY.by_name
    table: dict[str, list[type[NMLmsg]]] = {
        EMC_COMMAND: commands,
        EMC_STATUS: [c for c in (by_name("EMC_STAT"),) if c],
        EMC_ERROR: [c for c in REGISTRY.of_kind(MessageKind.OPERATOR) if _is_catalogue(c)],
        TOOL_COMMAND: [c for c in commands if c.RECEIVER is Receiver.IO],
        TOOL_STATUS: [c for c in (by_name("EMC_IO_STAT"),) if c],
        MOTION_COMMAND: [c for c in commands if c.RECEIVER is Receiver.MOTION],
        MOTION_STATUS: [c for c in (by_name("EMC_MOTION_STAT"),) if c],
    }
    return table.get(buffer_name, [])


def message_room(buffer: BufferConfig) -> MessageRoom | None:
    """The largest encoded message the controller writes to ``buffer``, if it is standard,
    and the buffer size that holds it."""
    classes = messages_of(buffer.name)
    if not classes:
        return None
    encoding = Encoding.from_neut(buffer.is_neutral)
    largest = max(max_encoded_size(cls, encoding) for cls in classes)
    return MessageRoom(largest, BufferLayout.bytes_needed(buffer, largest))


def load_config(path: str | Path | None = None) -> NmlConfig:
    """Parse an NML file (default: ours) and check its sizes against our messages. A
    LinuxCNC NML file gets what only our controller uses (``with_our_lines``)."""
    config = nml_config.load(path or DEFAULT_NML_FILE, message_room=message_room)
    return with_our_lines(config)


MOTION_PAIR = (MOTION_COMMAND, MOTION_STATUS)


def with_our_lines(config: NmlConfig) -> NmlConfig:
    """``config`` with the lines of our NML file that only our controller uses, where it
    has none: the task <-> motion pair and the P lines of our ``motion`` process.

    LinuxCNC's task talks to motion through a shared-memory area motmod makes, which no NML
    file configures, and its motion reports errors through task: its NML files
    (linuxcnc.nml, a user's tcp.nml) name only the buffers and processes of task
    (``emc``), iocontrol (``tool``), the UIs (``xemc``) and the server (``emcsvr``). Such a
    file runs here unchanged: our lines are added, our master's going to the file's master
    process(es), so the launcher creates the pair with the rest; an added P line on one of
    the file's buffers takes a connection number that buffer does not use yet."""
    ours = _our_config()
    added_buffers = [name for name in MOTION_PAIR if name not in config.buffers]
    known_processes = {p.name for p in config.processes}
    added_lines = [
        line
        for line in ours.processes
        if line.buffer in added_buffers or (line.name not in known_processes and not line.is_master)
    ]
    if not added_lines:
        return config
    masters = sorted({p.name for p in config.processes if p.is_master})
    buffers = dict(config.buffers)
    processes = list(config.processes)
    for name in added_buffers:
        buffers[name] = ours.buffers[name]
    for line in added_lines:
        if line.buffer not in buffers:
            continue  # (a buffer the file lacks that is not ours to add: Nml says so)
        if line.buffer not in added_buffers:
            used = {p.c_num for p in processes if p.buffer == line.buffer}
            line = dataclasses.replace(line, c_num=min(set(range(len(used) + 1)) - used))
        if line.is_master and masters:
            processes += [dataclasses.replace(line, name=master) for master in masters]
        else:
            processes.append(line)
    return dataclasses.replace(config, buffers=buffers, processes=processes)


@functools.cache
def _our_config() -> NmlConfig:
    return nml_config.load(DEFAULT_NML_FILE, message_room=message_room)


class Nml:
    """Every buffer one process is configured to use, opened (master) or attached."""

    def __init__(self, config: NmlConfig, process: str, buffers: list[str] | None = None) -> None:
        self.config = config
        self.process = process
        wanted = buffers or [p.buffer for p in config.processes if p.name == process]
        wanted = [name for name in wanted if name != nml_config.DEFAULT_BUFFER]
        if not wanted:
            raise NmlAccessError(f"{config.path}: process '{process}' has no P lines")
        self.channels: dict[str, ShmBuffer] = {}
        try:
            for name in wanted:
                if name not in config.buffers:
                    raise NmlAccessError(f"{config.path}: no B line for buffer '{name}'")
                self.channels[name] = ShmBuffer(config.buffers[name], config.process(process, name))
        except BaseException:
            self.close()
            raise

    def __getitem__(self, buffer: str) -> ShmBuffer:
        try:
            return self.channels[buffer]
        except KeyError:
            raise NmlAccessError(
                f"process {self.process} is not connected to buffer '{buffer}'"
            ) from None

    def close(self) -> None:
        for channel in reversed(list(self.channels.values())):
            channel.close()
        self.channels.clear()

    def __enter__(self) -> Nml:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
