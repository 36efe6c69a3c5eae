"""A shared-memory FIFO of HAL samples between a realtime component and a user program.

One writer and one reader. The segment holds a header of four int64 (rows written, rows
read, depth, columns) and ``depth`` rows of ``1 + columns`` int64: the sample number, then
each value as the raw 8 bytes of its HAL slot (floats are reinterpreted by the reader).
"""

from __future__ import annotations

import contextlib
import mmap

import numpy as np
import posix_ipc

from hal.core import HAL_BIT, HAL_FLOAT, HAL_S32, HAL_S64, HAL_U32, HAL_U64, HalError
from nml.ipcnames import ipc_name

HEADER = 4
#: sampler/streamer config letters (LinuxCNC's) -> HAL types
CFG_TYPES = {
    "f": HAL_FLOAT,
    "b": HAL_BIT,
    "s": HAL_S32,
    "u": HAL_U32,
    "l": HAL_S64,
    "k": HAL_U64,
}


def fifo_name(channel: str) -> str:
    return ipc_name("hal", f"fifo.{channel}")


class Fifo:
    """A FIFO segment: ``Fifo.create`` in the component, ``Fifo.open`` in the program."""

    def __init__(self, shm: posix_ipc.SharedMemory, name: str) -> None:
        self.name = name
        self._map = mmap.mmap(shm.fd, shm.size)
        shm.close_fd()
        whole = np.frombuffer(self._map, dtype=np.int64)
        self.header = whole[:HEADER]
        depth, width = int(self.header[2]), int(self.header[3])
        self.depth, self.width = depth, width
        self.rows = whole[HEADER : HEADER + depth * (width + 1)].reshape(depth, width + 1)

    @classmethod
    def create(cls, channel: str, depth: int, width: int) -> Fifo:
        name = fifo_name(channel)
        size = 8 * (HEADER + depth * (width + 1))
        shm = posix_ipc.SharedMemory(name, posix_ipc.O_CREAT, size=size)
        header = mmap.mmap(shm.fd, 8 * HEADER)
        header[:] = np.array([0, 0, depth, width], dtype=np.int64).tobytes()
        header.close()
        return cls(shm, name)

    @classmethod
    def open(cls, channel: str) -> Fifo:
        try:
            shm = posix_ipc.SharedMemory(fifo_name(channel))
        except posix_ipc.ExistentialError:
            raise HalError(f"no FIFO '{channel}' (is the component loaded?)") from None
        return cls(shm, fifo_name(channel))

    def close(self) -> None:
        self.rows = self.header = None  # type: ignore[assignment]
        with contextlib.suppress(BufferError):
            self._map.close()

    def unlink(self) -> None:
        with contextlib.suppress(posix_ipc.ExistentialError):
            posix_ipc.unlink_shared_memory(self.name)

    # ------------------------------------------------------------ both ends
    def count(self) -> int:
        return int(self.header[0] - self.header[1])

    def put(self, row: list[int]) -> bool:
        """Append one row (sample number first); False when the FIFO is full."""
        written = int(self.header[0])
        if written - int(self.header[1]) >= self.depth:
            return False
        self.rows[written % self.depth] = row
        self.header[0] = written + 1
        return True

    def get(self) -> np.ndarray | None:
        """The oldest row (a copy), or None when empty."""
        read = int(self.header[1])
        if read >= int(self.header[0]):
            return None
        row = self.rows[read % self.depth].copy()
        self.header[1] = read + 1
        return row


def decode(raw: np.ndarray, types: list[int]) -> list[int | float]:
    """Raw slot bytes of one row's values -> Python values by HAL type."""
    values: list[int | float] = []
    for word, hal_type in zip(raw, types, strict=True):
        if hal_type == HAL_FLOAT:
            values.append(float(np.int64(word).view(np.float64)))
        elif hal_type in (HAL_U32, HAL_U64):
            values.append(int(np.int64(word).view(np.uint64)))
        else:
            values.append(int(word))
    return values


def encode(values: list[float | int], types: list[int]) -> list[int]:
    """Python values -> raw slot words (the inverse of ``decode``)."""
    words = []
    for value, hal_type in zip(values, types, strict=True):
        if hal_type == HAL_FLOAT:
            words.append(int(np.float64(value).view(np.int64)))
        elif hal_type == HAL_BIT:
            words.append(1 if value else 0)
        else:
            words.append(int(np.uint64(int(value) % (1 << 64)).view(np.int64)))
    return words


def parse_cfg(cfg: str) -> list[int]:
    try:
        return [CFG_TYPES[letter] for letter in cfg.lower()]
    except KeyError as exc:
        raise HalError(f"bad cfg letter {exc} (want f, b, s, u, l or k)") from None
