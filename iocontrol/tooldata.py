"""The shared tool data store: iocontrol's tool table, readable by every process (ARCH-015).

EMC_IO_STAT carries only the spindle record (``tool.toolTableCurrent``); the whole table
lives here, in one shared-memory segment per instance (``/cnc.<instance>.tooldata.table``),
like LinuxCNC 2.9's tool mmap. iocontrol is the only writer (``ToolDataWriter``, created at
start-up, removed at exit); task, the interpreter and UIs read it (``ToolDataReader``, or
``read_tool_data()`` once).

Layout: a header (magic, layout version, sequence counter, changer kind, record count), then
one CANON_TOOL_TABLE record per tooldata index 0..count-1 (toolno -1: empty). The writer
makes the counter odd while it writes and even when done, so a reader retries instead of
ever using a half-written table; the counter also tells a reader whether anything changed.
"""

from __future__ import annotations

import contextlib
import mmap
import struct
import time

import numpy as np
import posix_ipc

from iocontrol.tooltable import CANON_POCKETS_MAX, ToolEntry, ToolTable
from nml.emc import CANON_TOOL_TABLE
from nml.ipcnames import ipc_name

MAGIC = 0x544F4F4C  # "TOOL"
LAYOUT_VERSION = 1
HEADER = struct.Struct("<IIQii")  # magic, version, sequence, is_random, count
RECORDS_OFFSET = 32
RECORD = CANON_TOOL_TABLE.dtype
SEGMENT_BYTES = RECORDS_OFFSET + CANON_POCKETS_MAX * RECORD.itemsize
_SEQ = struct.Struct("<Q")
_SEQ_OFFSET = 8


class ToolDataError(Exception):
    """No tool data store (iocontrol not running) or a corrupt one."""


def segment_name() -> str:
    return ipc_name("tooldata", "table")


def _record(entry: ToolEntry) -> tuple:
    o = entry.offset
    return (
        entry.toolno,
        entry.pocketno,
        ((o[0], o[1], o[2]), o[3], o[4], o[5], o[6], o[7], o[8]),
        entry.diameter,
        entry.frontangle,
        entry.backangle,
        entry.orientation,
    )


def _entry(rec: tuple) -> ToolEntry:
    """The inverse of ``_record`` (records come back as nested tuples from ``tolist``)."""
    toolno, pocketno, (tran, *rest), diameter, frontangle, backangle, orientation = rec
    return ToolEntry(toolno, pocketno, [*tran, *rest], diameter, frontangle, backangle, orientation)


class ToolDataWriter:
    """iocontrol's side: creates the segment and publishes the table after every change."""

    def __init__(self) -> None:
        shm = posix_ipc.SharedMemory(segment_name(), posix_ipc.O_CREAT, size=SEGMENT_BYTES)
        self._mm = mmap.mmap(shm.fd, SEGMENT_BYTES)
        shm.close_fd()
        # a store left by a killed iocontrol keeps counting, so its readers see a change
        self._sequence = (_SEQ.unpack_from(self._mm, _SEQ_OFFSET)[0] | 1) + 1
        HEADER.pack_into(self._mm, 0, MAGIC, LAYOUT_VERSION, self._sequence, 0, 0)

    def publish(self, table: ToolTable) -> None:
        """Write every record of ``table`` (indices 0..last_index)."""
        count = table.last_index + 1
        empty = ToolEntry()
        records = np.array(
            [_record(table.entries.get(index, empty)) for index in range(count)], RECORD
        )
        self._sequence += 1  # odd: writing
        _SEQ.pack_into(self._mm, _SEQ_OFFSET, self._sequence)
        self._mm[RECORDS_OFFSET : RECORDS_OFFSET + records.nbytes] = records.tobytes()
        self._sequence += 1
        HEADER.pack_into(
            self._mm, 0, MAGIC, LAYOUT_VERSION, self._sequence, table.random_toolchanger, count
        )

    def close(self) -> None:
        """Mark the store closed (readers re-attach to a new one), unmap and remove it."""
        HEADER.pack_into(self._mm, 0, 0, 0, self._sequence, 0, 0)
        self._mm.close()
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(segment_name())


class ToolDataReader:
    """A reader's side (task, interpreter, UIs): a read-only mapping kept open between reads.

    If iocontrol restarts, the reader notices the closed store and maps the new one.
    """

    def __init__(self) -> None:
        self._mm: mmap.mmap | None = None
        self._attach()

    def _attach(self) -> None:
        self.close()
        try:
            shm = posix_ipc.SharedMemory(segment_name())
        except posix_ipc.ExistentialError:
            raise ToolDataError(
                f"no tool data store {segment_name()} (is iocontrol running?)"
            ) from None
        try:
            self._mm = mmap.mmap(shm.fd, SEGMENT_BYTES, prot=mmap.PROT_READ)
        finally:
            shm.close_fd()

    def _map(self) -> mmap.mmap:
        if self._mm is None or HEADER.unpack_from(self._mm, 0)[0] != MAGIC:
            self._attach()  # closed by its writer: a new iocontrol may have made a new one
        assert self._mm is not None
        return self._mm

    @property
    def sequence(self) -> int:
        """The change counter; read the table again only when it changed."""
        return _SEQ.unpack_from(self._map(), _SEQ_OFFSET)[0]

    def read(self, timeout_s: float = 1.0) -> ToolTable:
        """A consistent copy of iocontrol's tool table; raises ToolDataError."""
        mm = self._map()
        deadline = time.monotonic() + timeout_s
        while True:
            magic, version, seq, is_random, count = HEADER.unpack_from(mm, 0)
            if (magic, version) != (MAGIC, LAYOUT_VERSION) or not 0 <= count <= CANON_POCKETS_MAX:
                raise ToolDataError(f"tool data store {segment_name()} is closed or corrupt")
            data = mm[RECORDS_OFFSET : RECORDS_OFFSET + count * RECORD.itemsize]
            if seq % 2 == 0 and _SEQ.unpack_from(mm, _SEQ_OFFSET)[0] == seq:
                break
            if time.monotonic() > deadline:
                raise ToolDataError("tool data store is being written for too long")
            time.sleep(0.0001)
        table = ToolTable(random_toolchanger=bool(is_random))
        for index, rec in enumerate(np.frombuffer(data, RECORD, count).tolist()):
            if index == 0 or rec[0] != -1:
                table.put(index, _entry(rec))
        return table

    def close(self) -> None:
        if self._mm is not None:
            self._mm.close()
            self._mm = None

    def __enter__(self) -> ToolDataReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read_tool_data() -> ToolTable:
    """One-shot read of iocontrol's tool table (attach, read, detach)."""
    with ToolDataReader() as reader:
        return reader.read()
