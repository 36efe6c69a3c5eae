"""The host's end of an Ethernet HostMot2 link, as LinuxCNC's hm2_eth runs it.

Start-up uses plain reads and writes (a datagram each, answers waited for up to
``INIT_TIMEOUT_S``). Each servo period then costs two datagrams:

- the read request: one read command per register region the functions asked for, then
  a read of the board's received-packet counter, a write of this request's number into
  the board's scratch registers and a read back of that number and of the last write
  packet's number. The answer must carry both numbers, or it is stale or lost;
- the write packet: the regions to write, then this packet's number into the scratch.

An answer that does not come before the read deadline, or carries the wrong numbers, is
a packet error: ``PacketErrors`` keeps LinuxCNC's error level (up by ``increment`` per
error, down by ``decrement`` per good period) and reports when it reaches ``limit``.
Nothing here blocks longer than until the period's read deadline.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import time
from dataclasses import dataclass

from hal.hm2 import lbp16
from hal.hm2.lbp16 import Command

INIT_TIMEOUT_S = 0.2  # LinuxCNC waits 200 ms for an answer while loading
MAX_WORDS = lbp16.MAX_COUNT  # registers per command
MAX_DATAGRAM = 1400
_TAIL_BYTES = 2 + 8  # received-packet counter, then the two packet numbers


class LinkError(OSError):
    """The board does not answer, or answers nonsense."""


@dataclass
class PacketErrors:
    """LinuxCNC's packet error level: the pins and parameters of ``hm2_eth``."""

    limit: int = 10
    increment: int = 2
    decrement: int = 1
    level: int = 0
    total: int = 0
    is_error: bool = False  # this period
    is_exceeded: bool = False

    def record_error(self) -> bool:
        """One more error; False once the level reaches the limit (a permanent error)."""
        self.is_error = True
        self.total += 1
        self.level += max(self.increment, 1)
        if self.level < 0 or self.level > self.limit:
            self.level = self.limit
        self.is_exceeded = self.level >= self.limit
        return not self.is_exceeded

    def record_success(self) -> None:
        self.level = max(self.level - max(self.decrement, 1), 0)
        self.is_error = False
        self.is_exceeded = False


class EthLink:
    """LBP16 over a connected UDP socket to one board."""

    def __init__(self, ip: str, port: int = lbp16.UDP_PORT) -> None:
        self.ip = ip
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.connect((ip, port))
        except OSError as exc:
            self.sock.close()
            raise LinkError(f"cannot reach the board: {exc.strerror}") from None
        self.buffer = bytearray(MAX_DATAGRAM)
        self.read_count = 0
        self.write_count = 0
        self.read_template = b""
        self.read_tail = b""
        self.read_struct = struct.Struct("<")
        self.answer_bytes = _TAIL_BYTES
        self.is_read_requested = False
        self.request_time_ns = 0

    def close(self) -> None:
        self.sock.close()

    # ------------------------------------------------------------ start-up
    def transact(
        self, request: bytes, answer_bytes: int, timeout_s: float = INIT_TIMEOUT_S
    ) -> bytes:
        """Send one datagram and wait for its answer of ``answer_bytes``."""
        self._drain()
        self.sock.send(request)
        deadline = time.monotonic() + timeout_s
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise LinkError(f"the board did not answer within {timeout_s:g} s")
            self.sock.settimeout(remaining)
            try:
                size = self.sock.recv_into(self.buffer)
            except TimeoutError:
                continue
            except OSError as exc:
                raise LinkError(f"no answer: {exc.strerror}") from None
            if size == answer_bytes:
                return bytes(self.buffer[:size])

    def _drain(self) -> None:
        """Throw away answers left over from timed-out requests."""
        self.sock.setblocking(False)
        try:
            while True:
                self.sock.recv_into(self.buffer)
        except (BlockingIOError, OSError):
            pass

    def read(self, address: int, words: int) -> tuple[int, ...]:
        """HostMot2 registers ``address`` on, waiting for the answer (start-up only)."""
        values: list[int] = []
        while words > 0:
            count = min(words, MAX_WORDS)
            answer = self.transact(lbp16.read_hm2(address, count).header(), 4 * count)
            values += struct.unpack(f"<{count}I", answer)
            address += 4 * count
            words -= count
        return tuple(values)

    def write(self, address: int, values: list[int] | tuple[int, ...]) -> None:
        """Write registers now (start-up and reconfiguration, outside the periodic packets)."""
        self.write_count += 1
        packet = lbp16.write_hm2(address, len(values)).header() + struct.pack(
            f"<{len(values)}I", *values
        )
        packet += self._write_count_command()
        self.sock.send(packet)

    def read_space(self, space: int, address: int, words16: int) -> bytes:
        command = Command(False, space, lbp16.SIZE_16, words16, address)
        return self.transact(command.header(), 2 * words16)

    def board_name(self) -> str:
        """The board's name from its information space ("7I96S")."""
        raw = self.read_space(lbp16.SPACE_BOARD_INFO, 0, 8)
        return raw.split(b"\0", 1)[0].decode("ascii", errors="replace").strip()

    def mac_address(self) -> str:
        raw = self.read_space(lbp16.SPACE_EEPROM, lbp16.EEPROM_MAC_ADDRESS, 3)
        return ":".join(f"{b:02x}" for b in reversed(raw))

    def _write_count_command(self) -> bytes:
        command = Command(True, lbp16.SPACE_TIMER, lbp16.SIZE_16, 2, lbp16.TIMER_WRITE_COUNT)
        return command.header() + struct.pack("<I", self.write_count & 0xFFFFFFFF)

    # ------------------------------------------------------------ each period
    def set_read_regions(self, regions: list[tuple[int, int]]) -> None:
        """The (address, words) regions every read request asks for, in this order."""
        parts = []
        total = 0
        for address, words in regions:
            while words > 0:
                count = min(words, MAX_WORDS)
                parts.append(lbp16.read_hm2(address, count).header())
                address += 4 * count
                words -= count
                total += count
        parts.append(
            Command(False, lbp16.SPACE_COMM_CTRL, lbp16.SIZE_16, 1, 0x0008).header()
        )  # the board's received-packet counter (kept for diagnosis, as LinuxCNC does)
        parts.append(
            Command(True, lbp16.SPACE_TIMER, lbp16.SIZE_16, 2, lbp16.TIMER_READ_COUNT).header()
        )
        self.read_template = b"".join(parts)
        self.read_tail = Command(
            False, lbp16.SPACE_TIMER, lbp16.SIZE_16, 4, lbp16.TIMER_READ_COUNT
        ).header()
        self.read_struct = struct.Struct(f"<{total}IHII")
        self.answer_bytes = self.read_struct.size
        if len(self.read_template) + 4 + len(self.read_tail) > MAX_DATAGRAM:
            raise LinkError("too many registers to read in one datagram")

    def send_read_request(self, now_ns: int) -> None:
        self.read_count = (self.read_count + 1) & 0xFFFFFFFF
        self.sock.send(self.read_template + struct.pack("<I", self.read_count) + self.read_tail)
        self.is_read_requested = True
        self.request_time_ns = now_ns

    def receive(self, deadline_ns: int) -> tuple[int, ...] | None:
        """The answer to the last read request: the register values, or None when it did
        not come by ``deadline_ns`` (monotonic ns) or is not the answer to that request
        or came before the last write packet was taken in."""
        self.is_read_requested = False
        buffer, sock, wanted = self.buffer, self.sock, self.answer_bytes
        while True:
            remaining = (deadline_ns - time.monotonic_ns()) / 1e9
            try:
                if remaining > 0:
                    sock.settimeout(remaining)
                    size = sock.recv_into(buffer)
                else:  # late: take what is there, never wait
                    sock.setblocking(False)
                    size = sock.recv_into(buffer)
            except (TimeoutError, BlockingIOError):
                return None
            except OSError:
                return None
            if size != wanted:
                continue
            values = self.read_struct.unpack_from(buffer)
            if values[-2] != self.read_count:
                continue  # a stale answer to an earlier request: look for ours
            if self.write_count and values[-1] != self.write_count:
                return None  # the last write packet was lost
            return values

    def send_writes(self, packet: bytearray | bytes) -> None:
        """One write datagram: ``packet`` holds the write commands; the packet number is
        appended here."""
        self.write_count = (self.write_count + 1) & 0xFFFFFFFF
        self.sock.send(bytes(packet) + self._write_count_command())

    def bite_watchdog(self, watchdog_address: int) -> None:
        """Make the board's watchdog bite at once (outputs off), as at unload."""
        packet = lbp16.write_hm2(watchdog_address, 1).header() + struct.pack("<I", 1)
        with contextlib.suppress(OSError):
            self.sock.send(packet)
