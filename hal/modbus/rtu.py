"""Modbus RTU over a serial line (pyserial): frames, CRC and the errors a master meets.

A frame is the slave address, the function code, the data and a CRC-16 (polynomial
0xA001, low byte first); frames are separated by 3.5 characters of silence. The master
knows how long each answer must be, so it reads exactly that (or the 5 bytes of an
exception answer) and tells apart what can go wrong, as libmodbus does for mb2hal:

- ``PortError``: the serial port cannot be opened or used (no adapter, no permission);
- ``NoAnswerError``: nothing (or too little) came within the response / byte timeouts;
- ``BadCrcError``: an answer came but its CRC is wrong (noise, wrong baud rate or parity);
- ``SlaveExceptionError``: the slave answered with an exception code (illegal address ...).

Huanyang VFDs use the same framing with their own function codes; ``transact`` takes any
request and the answer length expected.
"""

from __future__ import annotations

import contextlib
import struct
import time

import serial

# mb2hal's error numbers (libmodbus's): what its debug output and our messages name
COMM_TIME_OUT = -12
PORT_SOCKET_FAILURE = -13
INVALID_CRC = -16
EXCEPTION_NAMES = {
    1: "ILLEGAL_FUNCTION",
    2: "ILLEGAL_DATA_ADDRESS",
    3: "ILLEGAL_DATA_VALUE",
    4: "SLAVE_DEVICE_FAILURE",
    5: "ACKNOWLEDGE",
    6: "SLAVE_DEVICE_BUSY",
    7: "NEGATIVE_ACKNOWLEDGE",
    8: "MEMORY_PARITY_ERROR",
    10: "GATEWAY_PROBLEM_PATH",
    11: "GATEWAY_PROBLEM_TARGET",
}
PARITIES = {"none": serial.PARITY_NONE, "even": serial.PARITY_EVEN, "odd": serial.PARITY_ODD}


class ModbusError(Exception):
    """A transaction failed; ``code`` is mb2hal's number for the failure."""

    code = 0


class PortError(ModbusError):
    code = PORT_SOCKET_FAILURE


class NoAnswerError(ModbusError):
    code = COMM_TIME_OUT


class BadCrcError(ModbusError):
    code = INVALID_CRC


class SlaveExceptionError(ModbusError):
    def __init__(self, function: int, exception: int) -> None:
        name = EXCEPTION_NAMES.get(exception, f"exception {exception}")
        super().__init__(f"the slave refused function {function}: {name} ({exception})")
        self.code = -exception


def crc16(data: bytes) -> int:
    """Modbus's CRC-16 of ``data``."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def frame(slave: int, pdu: bytes) -> bytes:
    """The RTU frame of a PDU (function code and data) for ``slave``."""
    body = bytes((slave,)) + pdu
    return body + struct.pack("<H", crc16(body))


def check_frame(raw: bytes) -> bytes:
    """The slave address and PDU of a received frame; BadCrcError if its CRC is wrong."""
    if len(raw) < 4 or struct.unpack("<H", raw[-2:])[0] != crc16(raw[:-2]):
        raise BadCrcError(f"bad CRC in the answer {raw.hex(' ')}")
    return raw[:-2]


def silence_s(baud: int) -> float:
    """The 3.5 character gap between frames (1.75 ms above 19200 baud, as the spec says)."""
    return 3.5 * 11 / baud if baud <= 19200 else 0.00175


class RtuLink:
    """One serial port with its settings; opened on first use, reopened after a failure."""

    def __init__(
        self,
        port: str,
        baud: int = 19200,
        bits: int = 8,
        parity: str = "none",
        stop: int = 1,
    ) -> None:
        if parity not in PARITIES:
            raise ValueError(f"parity must be one of {', '.join(PARITIES)}, not '{parity}'")
        self.port, self.baud, self.bits, self.parity, self.stop = port, baud, bits, parity, stop
        self.serial: serial.Serial | None = None
        self.last_activity = 0.0

    def open(self) -> None:
        if self.serial is not None:
            return
        try:
            self.serial = serial.Serial(
                self.port,
                self.baud,
                bytesize=self.bits,
                parity=PARITIES[self.parity],
                stopbits=self.stop,
                timeout=0.5,
            )
        except (serial.SerialException, OSError, ValueError) as exc:
            raise PortError(f"cannot open {self.port}: {exc}") from None

    def close(self) -> None:
        if self.serial is not None:
            with contextlib.suppress(Exception):
                self.serial.close()
            self.serial = None

    def transact(
        self,
        request: bytes,
        answer_bytes: int,
        response_timeout: float = 0.5,
        byte_timeout: float = 0.5,
    ) -> bytes:
        """Send a frame (with its CRC) and return the answer's address and PDU (CRC
        checked); exception answers raise SlaveExceptionError."""
        self.open()
        assert self.serial is not None
        port = self.serial
        try:
            wait = self.last_activity + silence_s(self.baud) - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            port.reset_input_buffer()
            port.write(request)
            port.flush()
            port.timeout = response_timeout
            first = port.read(2)  # address and function: is it an exception answer?
            if len(first) < 2:
                slave = request[0]
                raise NoAnswerError(f"no answer from slave {slave} within {response_timeout:g} s")
            remaining = (5 if first[1] & 0x80 else answer_bytes) - 2
            port.timeout = byte_timeout + remaining * 11 / self.baud
            rest = port.read(remaining)
        except (serial.SerialException, OSError) as exc:
            self.close()
            raise PortError(f"{self.port}: {exc}") from None
        finally:
            self.last_activity = time.monotonic()
        raw = first + rest
        if len(rest) < remaining:
            raise NoAnswerError(f"answer of slave {request[0]} cut short ({len(raw)} bytes)")
        body = check_frame(raw)
        if body[0] != request[0]:
            raise NoAnswerError(f"answer from slave {body[0]} instead of {request[0]}")
        if body[1] & 0x80:
            raise SlaveExceptionError(request[1], body[2])
        return body


# ---------------------------------------------------------------- standard functions
def read_request(slave: int, function: int, first: int, count: int) -> tuple[bytes, int]:
    """Functions 1-4: the frame and the answer's length."""
    request = frame(slave, struct.pack(">BHH", function, first, count))
    data = (count + 7) // 8 if function in (1, 2) else 2 * count
    return request, 3 + data + 2


def parse_bits(body: bytes, count: int) -> list[bool]:
    data = body[3:]
    return [bool(data[i // 8] >> (i % 8) & 1) for i in range(count)]


def parse_registers(body: bytes, count: int) -> list[int]:
    return list(struct.unpack(f">{count}H", body[3 : 3 + 2 * count]))


def write_single_request(slave: int, function: int, address: int, value: int) -> bytes:
    """Function 5 (coil: True/False) or 6 (register)."""
    if function == 5:
        value = 0xFF00 if value else 0x0000
    return frame(slave, struct.pack(">BHH", function, address, value & 0xFFFF))


def write_multiple_request(slave: int, function: int, first: int, values: list[int]) -> bytes:
    """Function 15 (coils) or 16 (registers)."""
    count = len(values)
    if function == 15:
        data = bytearray((count + 7) // 8)
        for i, value in enumerate(values):
            if value:
                data[i // 8] |= 1 << (i % 8)
    else:
        data = bytearray(struct.pack(f">{count}H", *(v & 0xFFFF for v in values)))
    return frame(slave, struct.pack(">BHHB", function, first, count, len(data)) + bytes(data))


WRITE_ANSWER_BYTES = 8  # functions 5, 6, 15, 16 echo address and value/count
