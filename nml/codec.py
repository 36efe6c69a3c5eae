"""Encoding of messages into buffer bytes and back (NML-037, NML-038, NML-072).

Every encoded message starts with a 16-byte NML header, distinct from the buffer's own
header: type number, payload length, layout checksum of the declaring class, encoding.
The payload is either the fixed layout (``neut`` 0: the message's raw little-endian bytes)
or msgpack (``neut`` 1: the machine-independent form, LinuxCNC's XDR counterpart: a msgpack
array of every leaf value in declaration order). Field order is fixed by the declaration
and guarded by the layout checksum (NML-038); names come from the declaration when a
message is shown (``cnc nml dump``).

Decoding checks everything it reads and raises ``NmlFormatError`` naming the cause; it
never lets garbage through as a message.
"""

from __future__ import annotations

import enum
import struct

import msgpack
import numpy as np

from nml.errors import NmlFormatError
from nml.message import HEADER, NMLmsg
from nml.registry import REGISTRY


class Encoding(enum.IntEnum):
    FIXED = 0
    MSGPACK = 1

    @classmethod
    def from_neut(cls, neut: bool) -> Encoding:
        return cls.MSGPACK if neut else cls.FIXED


def encode(msg: NMLmsg, encoding: Encoding) -> bytes:
    if encoding is Encoding.FIXED:
        payload = msg._arr.tobytes()
    else:
        payload = msgpack.packb(msg.to_flat(), use_bin_type=True)
    return HEADER.pack(msg.TYPE, len(payload), msg.layout_crc, encoding) + payload


def peek_type(data: bytes | bytearray | memoryview) -> int:
    """The type number of an encoded message, without decoding it."""
    if len(data) < HEADER.size:
        raise NmlFormatError(f"message shorter than its {HEADER.size}-byte header")
    return HEADER.unpack_from(data)[0]


def decode(data: bytes | bytearray | memoryview, where: str = "buffer") -> NMLmsg:
    """The message encoded in ``data``; ``where`` names the buffer in error messages.

    A fixed-layout message decoded from a ``bytearray`` keeps using that bytearray's memory
    (no copy): pass a bytearray only if nothing else will change it.
    """
    if len(data) < HEADER.size:
        raise NmlFormatError(f"{where}: message shorter than its {HEADER.size}-byte header")
    type_id, length, crc, encoding = HEADER.unpack_from(data)
    cls = REGISTRY.by_type(type_id)
    if cls is None:
        raise NmlFormatError(f"{where}: unknown message type {type_id}")
    if HEADER.size + length > len(data):
        raise NmlFormatError(
            f"{where}: {cls.NAME} claims {length} payload bytes, only "
            f"{len(data) - HEADER.size} present"
        )
    if crc != cls.layout_crc:
        raise NmlFormatError(
            f"{where}: {cls.NAME} was written with a different field layout "
            "(the writer runs another version of the message declarations)"
        )
    if encoding == Encoding.FIXED:
        if length != cls.dtype.itemsize:
            raise NmlFormatError(
                f"{where}: {cls.NAME} payload is {length} bytes, expected {cls.dtype.itemsize}"
            )
        if isinstance(data, bytearray):  # a private copy already: decode in place
            return cls._view(np.ndarray((), cls.dtype, data, HEADER.size))  # type: ignore[return-value]
        return cls.from_bytes(memoryview(data)[HEADER.size : HEADER.size + length])  # type: ignore[return-value]
    payload = memoryview(data)[HEADER.size : HEADER.size + length]
    if encoding == Encoding.MSGPACK:
        try:
            values = msgpack.unpackb(payload, raw=True, use_list=False)
        except (ValueError, msgpack.UnpackException) as exc:
            raise NmlFormatError(f"{where}: {cls.NAME} msgpack payload is corrupt: {exc}") from None
        if not isinstance(values, tuple):
            raise NmlFormatError(f"{where}: {cls.NAME} msgpack payload is not an array")
        try:
            return cls.from_flat(values)  # type: ignore[return-value]
        except struct.error as exc:
            raise NmlFormatError(f"{where}: {cls.NAME} msgpack values do not fit: {exc}") from None
    raise NmlFormatError(f"{where}: unknown encoding {encoding}")


def max_encoded_size(cls: type[NMLmsg], encoding: Encoding) -> int:
    """An upper bound of the encoded size of any instance of ``cls`` (for buffer sizes)."""
    if encoding is Encoding.FIXED:
        return HEADER.size + cls.dtype.itemsize
    return HEADER.size + _msgpack_bound(cls)


def _msgpack_bound(cls: type[NMLmsg]) -> int:
    """Worst-case msgpack bytes of the flat value array: 9 per number, a header per text."""
    texts = [int(code[:-1]) for code in cls.flat_codes if code.endswith("s")]
    numbers = len(cls.flat_codes) - len(texts)
    return 5 + 9 * numbers + sum(length + 5 for length in texts)
