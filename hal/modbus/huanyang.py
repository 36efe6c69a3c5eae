"""The Huanyang VFD protocol: Modbus RTU framing with Huanyang's own function codes.

==== ======================= ============================ =========================
code what                    request data                 answer data
==== ======================= ============================ =========================
0x01 read a PD register      3, register, value (2 bytes) 3, register, value
0x02 write a PD register     3, register, value           3, register, value
0x03 write the control word  1, control                   1, status (CNST)
0x04 read a status value     1, which (0 SetF ... 7 Tmp)  3, which, value
0x05 write the frequency     2, frequency x 100           2, frequency x 100
==== ======================= ============================ =========================

Control words: 0x01 run forward, 0x11 run reverse, 0x08 stop. Status bits (CNST): run,
jog, command reverse, running, jogging, running reverse, braking, track start.
"""

from __future__ import annotations

import struct

from hal.modbus import rtu

READ_REGISTER = 0x01
WRITE_REGISTER = 0x02
WRITE_CONTROL = 0x03
READ_STATUS = 0x04
WRITE_FREQUENCY = 0x05

RUN_FORWARD = 0x01
RUN_REVERSE = 0x11
STOP = 0x08

STATUS_SETF, STATUS_OUTF, STATUS_OUTA, STATUS_ROTT = 0, 1, 2, 3
STATUS_DCV, STATUS_ACV, STATUS_CONT, STATUS_TMP = 4, 5, 6, 7
STATUS_NAMES = ("SetF", "OutF", "OutA", "Rott", "DCV", "ACV", "Cont", "Tmp")
CNST_BITS = (
    "run", "jog", "command-rf", "running", "jogging", "running-rf", "bracking", "track-start",
)  # fmt: skip

ANSWER_BYTES = {READ_REGISTER: 8, WRITE_REGISTER: 8, WRITE_CONTROL: 6, READ_STATUS: 8,
                WRITE_FREQUENCY: 7}  # fmt: skip


def request(slave: int, function: int, *, register: int = 0, value: int = 0) -> bytes:
    """The frame of a Huanyang request."""
    if function in (READ_REGISTER, WRITE_REGISTER):
        data = struct.pack(">BBH", 3, register, value & 0xFFFF)
    elif function in (WRITE_CONTROL, READ_STATUS):
        data = struct.pack(">BB", 1, value & 0xFF)
    elif function == WRITE_FREQUENCY:
        data = struct.pack(">BH", 2, value & 0xFFFF)
    else:
        raise ValueError(f"unknown Huanyang function 0x{function:02X}")
    return rtu.frame(slave, bytes((function,)) + data)


def answer_value(function: int, body: bytes) -> int:
    """The value an answer carries (its address and PDU, CRC already checked)."""
    if body[1] != function:
        raise rtu.NoAnswerError(f"answer to function 0x{body[1]:02X} instead of 0x{function:02X}")
    if function in (READ_REGISTER, WRITE_REGISTER, READ_STATUS):
        return struct.unpack(">H", body[4:6])[0]
    if function == WRITE_CONTROL:
        return body[3]
    return struct.unpack(">H", body[3:5])[0]


def answer(slave: int, function: int, first: int, value: int) -> bytes:
    """The VFD's side: the frame answering ``function`` (``first``: the register or status
    number the request named)."""
    if function in (READ_REGISTER, WRITE_REGISTER, READ_STATUS):
        data = struct.pack(">BBH", 3, first, value & 0xFFFF)
    elif function == WRITE_CONTROL:
        data = struct.pack(">BB", 1, value & 0xFF)
    else:
        data = struct.pack(">BH", 2, value & 0xFFFF)
    return rtu.frame(slave, bytes((function,)) + data)
