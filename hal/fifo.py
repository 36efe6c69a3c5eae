"""A shared-memory FIFO of HAL samples between a realtime component and a user program
(LinuxCNC's ``hal_stream``): one writer and one reader.

The segment holds int64 words: a header (rows written, rows read, depth, columns, underruns,
overruns, the last sample number, a magic number), one word per column with its HAL type,
then ``depth`` rows of ``1 + columns`` words: the sample number, then each value as the raw
8 bytes of its HAL slot (floats are reinterpreted by the reader). As in LinuxCNC a FIFO of
depth D holds at most D - 1 rows.
"""

from __future__ import annotations

import contextlib
import mmap
import struct

import posix_ipc

from hal.core import HAL_BIT, HAL_FLOAT, HAL_S32, HAL_S64, HAL_U32, HAL_U64, HalError
from nml.ipcnames import ipc_name

WRITTEN, READ, DEPTH, WIDTH, UNDERRUNS, OVERRUNS, LAST_SAMPLE, MAGIC = range(8)
HEADER = 8
MAGIC_NUMBER = 0x48535452  # "HSTR"
MAX_COLUMNS = 20  # LinuxCNC's HAL_STREAM_MAX_PINS
WORD = struct.Struct("<q")  # (no numpy here: halsampler/halstreamer start in a blink)
FLOAT = struct.Struct("<d")
U64 = 1 << 64
#: sampler/streamer config letters (LinuxCNC's, either case) -> HAL types
CFG_TYPES = {
    "f": HAL_FLOAT,
    "b": HAL_BIT,
    "s": HAL_S32,
    "u": HAL_U32,
    "l": HAL_S64,
    "k": HAL_U64,
}
CFG_LETTERS = {hal_type: letter for letter, hal_type in CFG_TYPES.items()}
# LinuxCNC's keys of sampler and streamer channels (hal.sampler_base / hal.streamer_base)
SAMPLER_BASE = 0x48534130
STREAMER_BASE = 0x48535430


def fifo_name(channel: str) -> str:
    return ipc_name("hal", f"fifo.{channel}")


def channel_of_key(key: int) -> str:
    """The channel a LinuxCNC stream key names: sampler_base + N is ``sampler.N``."""
    for base, module in ((SAMPLER_BASE, "sampler"), (STREAMER_BASE, "streamer")):
        if 0 <= key - base < 256:
            return f"{module}.{key - base}"
    return f"stream.{key:x}"


class Fifo:
    """A FIFO segment: ``Fifo.create`` by the side that owns it, ``Fifo.open`` by the other."""

    def __init__(self, shm: posix_ipc.SharedMemory, name: str) -> None:
        self.name = name
        self._map = mmap.mmap(shm.fd, shm.size)
        shm.close_fd()
        self.words = memoryview(self._map).cast("q")
        self.header = self.words[:HEADER]
        if self.header[MAGIC] != MAGIC_NUMBER:
            self.close()
            raise HalError(f"'{name}' is not a HAL stream")
        depth, width = self.header[DEPTH], self.header[WIDTH]
        self.depth, self.width = depth, width
        self.types = list(self.words[HEADER : HEADER + width])
        self._rows_start = HEADER + width  # row i: words[start + i * (width + 1)...]

    @classmethod
    def create(cls, channel: str, depth: int, types: list[int]) -> Fifo:
        if depth < 2:
            raise HalError(f"{channel}: depth must be at least 2")
        if not 0 < len(types) <= MAX_COLUMNS:
            raise HalError(f"{channel}: 1 to {MAX_COLUMNS} values per row")
        name = fifo_name(channel)
        width = len(types)
        size = 8 * (HEADER + width + depth * (width + 1))
        shm = posix_ipc.SharedMemory(name, posix_ipc.O_CREAT, size=size)
        head = mmap.mmap(shm.fd, 8 * (HEADER + width))
        header = [0] * HEADER
        header[DEPTH], header[WIDTH], header[MAGIC] = depth, width, MAGIC_NUMBER
        head[:] = struct.pack(f"<{HEADER + width}q", *header, *types)
        head.close()
        return cls(shm, name)

    @classmethod
    def open(cls, channel: str) -> Fifo:
        try:
            shm = posix_ipc.SharedMemory(fifo_name(channel))
        except posix_ipc.ExistentialError:
            raise HalError(f"no FIFO '{channel}' (is the component loaded?)") from None
        return cls(shm, fifo_name(channel))

    def close(self) -> None:
        if self.header is None:
            return
        self.header.release()
        self.words.release()
        self.header = self.words = None  # type: ignore[assignment]
        with contextlib.suppress(BufferError):
            self._map.close()

    def unlink(self) -> None:
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(self.name)

    # ------------------------------------------------------------ both ends
    def count(self) -> int:
        """Rows waiting to be read."""
        return self.header[WRITTEN] - self.header[READ]

    @property
    def capacity(self) -> int:
        return self.depth - 1

    def is_writable(self) -> bool:
        return self.count() < self.capacity

    def put(self, values: list[int]) -> bool:
        """Append one row of raw value words, numbering it; False (and an overrun counted)
        when the FIFO is full."""
        header = self.header
        written = header[WRITTEN]
        if written - header[READ] >= self.depth - 1:
            header[OVERRUNS] += 1
            return False
        number = header[LAST_SAMPLE] + 1
        start = self._rows_start + (written % self.depth) * (self.width + 1)
        words = self.words
        words[start] = number
        for offset, value in enumerate(values, start + 1):
            words[offset] = value
        header[LAST_SAMPLE] = number
        header[WRITTEN] = written + 1
        return True

    def get(self) -> list[int] | None:
        """The oldest row (a copy: sample number, then the raw value words), or None (and
        an underrun counted) when empty."""
        header = self.header
        read = header[READ]
        if read >= header[WRITTEN]:
            header[UNDERRUNS] += 1
            return None
        start = self._rows_start + (read % self.depth) * (self.width + 1)
        row = self.words[start : start + self.width + 1].tolist()
        header[READ] = read + 1
        return row

    @property
    def underruns(self) -> int:
        return self.header[UNDERRUNS]

    @property
    def overruns(self) -> int:
        return self.header[OVERRUNS]


def decode(raw: list[int], types: list[int]) -> list[int | float]:
    """Raw slot words of one row's values -> Python values by HAL type."""
    values: list[int | float] = []
    for word, hal_type in zip(raw, types, strict=True):
        if hal_type == HAL_FLOAT:
            values.append(FLOAT.unpack(WORD.pack(word))[0])
        elif hal_type in (HAL_U32, HAL_U64):
            values.append(word % U64)
        else:
            values.append(int(word))
    return values


def encode(values: list[float | int], types: list[int]) -> list[int]:
    """Python values -> raw slot words (the inverse of ``decode``)."""
    words = []
    for value, hal_type in zip(values, types, strict=True):
        if hal_type == HAL_FLOAT:
            words.append(WORD.unpack(FLOAT.pack(float(value)))[0])
        elif hal_type == HAL_BIT:
            words.append(1 if value else 0)
        else:
            word = int(value) % U64
            words.append(word - U64 if word >= U64 // 2 else word)
    return words


def parse_cfg(cfg: str) -> list[int]:
    """A sampler/streamer ``cfg=`` string (``ffb``...) -> HAL types."""
    try:
        types = [CFG_TYPES[letter] for letter in cfg.lower()]
    except KeyError as exc:
        raise HalError(f"bad cfg letter {exc} (want f, b, s, u, l or k)") from None
    if not 0 < len(types) <= MAX_COLUMNS:
        raise HalError(f"cfg '{cfg}': 1 to {MAX_COLUMNS} letters")
    return types
