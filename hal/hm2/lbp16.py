"""LBP16: the protocol of Mesa's Ethernet cards, one or more commands per UDP datagram.

A command is a 16-bit word, optionally a 16-bit byte address, then (writes) the data; all
little-endian. The board answers a datagram with the data of its read commands, in order,
in one datagram; writes are not answered. The command word:

====== ============================================================================
bit 15 write (1) or read (0)
bit 14 an address follows (1); else the space's current address is used
bit 13 the info area of the space (1) instead of its memory (0)
12-10  memory space: 0 HostMot2 registers, 1 Ethernet chip, 2 EEPROM, 3 FPGA flash,
       4 timers and scratch, 6 communication control/status, 7 board information
 9-8   transfer size: 0 = 8, 1 = 16, 2 = 32, 3 = 64 bits
bit 7  increment the address after each transfer
 6-0   transfer count, 1..127
====== ============================================================================

The UDP port is 27181. ``Command`` makes and reads these words; the simulator
(``hal.hm2.sim``) decodes whole datagrams with ``parse``.
"""

from __future__ import annotations

import functools
import struct
from dataclasses import dataclass

UDP_PORT = 27181

WRITE = 0x8000
HAS_ADDRESS = 0x4000
INFO_AREA = 0x2000
AUTO_INCREMENT = 0x0080
MAX_COUNT = 0x7F

SPACE_HM2 = 0
SPACE_ETH_CHIP = 1
SPACE_EEPROM = 2
SPACE_FLASH = 3
SPACE_TIMER = 4
SPACE_COMM_CTRL = 6
SPACE_BOARD_INFO = 7

SIZE_8, SIZE_16, SIZE_32, SIZE_64 = 0, 1, 2, 3
BYTES_PER_SIZE = (1, 2, 4, 8)

# Byte addresses the host uses outside the HostMot2 space.
EEPROM_MAC_ADDRESS = 0x0002  # three 16-bit words, lowest byte of the MAC first
COMM_CTRL_RX_PACKETS = 0x0008  # packets the board received (16 bits, wraps)
TIMER_READ_COUNT = 0x0010  # scratch: the host's read-packet number, echoed back
TIMER_WRITE_COUNT = 0x0014  # scratch: the host's write-packet number

_WORD = struct.Struct("<H")
_CMD_ADDR = struct.Struct("<HH")


class Lbp16Error(ValueError):
    """A malformed LBP16 datagram (the board counts it as a parse error)."""


@dataclass(frozen=True, slots=True)
class Command:
    """One LBP16 command: what to transfer where."""

    is_write: bool
    space: int
    size: int  # SIZE_8 .. SIZE_64
    count: int  # transfers, 1..127
    address: int | None  # byte address, None: continue where the space left off
    is_increment: bool = True
    is_info: bool = False

    @property
    def data_bytes(self) -> int:
        return self.count * BYTES_PER_SIZE[self.size]

    def word(self) -> int:
        if not 1 <= self.count <= MAX_COUNT:
            raise Lbp16Error(f"transfer count {self.count} outside 1..{MAX_COUNT}")
        return (
            (WRITE if self.is_write else 0)
            | (HAS_ADDRESS if self.address is not None else 0)
            | (INFO_AREA if self.is_info else 0)
            | (self.space & 7) << 10
            | (self.size & 3) << 8
            | (AUTO_INCREMENT if self.is_increment else 0)
            | self.count
        )

    def header(self) -> bytes:
        """The command word and address, as sent before any data."""
        if self.address is None:
            return _WORD.pack(self.word())
        return _CMD_ADDR.pack(self.word(), self.address & 0xFFFF)

    @classmethod
    @functools.lru_cache(maxsize=1024)  # a host repeats the same commands every period
    def from_word(cls, word: int, address: int | None) -> Command:
        return cls(
            is_write=bool(word & WRITE),
            space=(word >> 10) & 7,
            size=(word >> 8) & 3,
            count=word & MAX_COUNT,
            address=address,
            is_increment=bool(word & AUTO_INCREMENT),
            is_info=bool(word & INFO_AREA),
        )


def read_hm2(address: int, words: int) -> Command:
    """Read ``words`` 32-bit HostMot2 registers from ``address`` on."""
    return Command(False, SPACE_HM2, SIZE_32, words, address)


def write_hm2(address: int, words: int) -> Command:
    return Command(True, SPACE_HM2, SIZE_32, words, address)


def parse(datagram: bytes) -> list[tuple[Command, bytes]]:
    """Every command of a datagram with its write data (empty for reads); Lbp16Error if
    a command is cut short or has a count of 0."""
    commands = []
    view = memoryview(datagram)
    pos, end = 0, len(datagram)
    while pos < end:
        if pos + 2 > end:
            raise Lbp16Error(f"datagram ends inside a command word at byte {pos}")
        (word,) = _WORD.unpack_from(view, pos)
        pos += 2
        address = None
        if word & HAS_ADDRESS:
            if pos + 2 > end:
                raise Lbp16Error(f"datagram ends inside an address at byte {pos}")
            (address,) = _WORD.unpack_from(view, pos)
            pos += 2
        command = Command.from_word(word, address)
        if command.count == 0:
            raise Lbp16Error(f"command 0x{word:04X} has a transfer count of 0")
        data = b""
        if command.is_write:
            size = command.data_bytes
            if pos + size > end:
                raise Lbp16Error(f"command 0x{word:04X} wants {size} data bytes, has {end - pos}")
            data = bytes(view[pos : pos + size])
            pos += size
        commands.append((command, data))
    return commands
