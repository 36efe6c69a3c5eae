"""LBP16 command words and datagrams."""

from __future__ import annotations

import pytest

from hal.hm2 import lbp16
from hal.hm2.lbp16 import Command, Lbp16Error


def test_a_hostmot2_read_command_is_laid_out_as_mesa_documents() -> None:
    # read, address follows, HostMot2 space, 32 bits, increment, 1 transfer: 0x4281
    assert lbp16.read_hm2(0x0100, 1).header() == bytes((0x81, 0x42, 0x00, 0x01))
    assert lbp16.write_hm2(0x0C00, 2).word() == 0xC282


def test_command_words_round_trip() -> None:
    command = Command(False, lbp16.SPACE_TIMER, lbp16.SIZE_16, 4, 0x10)
    assert Command.from_word(command.word(), 0x10) == command
    assert command.data_bytes == 8


def test_a_datagram_parses_into_its_commands_with_their_data() -> None:
    datagram = (
        lbp16.read_hm2(0x1000, 3).header()
        + lbp16.write_hm2(0x2000, 2).header()
        + bytes(range(8))
        + Command(False, lbp16.SPACE_BOARD_INFO, lbp16.SIZE_16, 8, None).header()
    )
    commands = lbp16.parse(datagram)
    assert [(c.is_write, c.address, c.count) for c, _ in commands] == [
        (False, 0x1000, 3),
        (True, 0x2000, 2),
        (False, None, 8),
    ]
    assert commands[1][1] == bytes(range(8))


@pytest.mark.parametrize(
    "datagram, cause",
    [
        (b"\x81", "inside a command word"),
        (b"\x81\x42\x00", "inside an address"),
        (lbp16.write_hm2(0x2000, 2).header() + b"\0" * 5, "wants 8 data bytes, has 5"),
        (b"\x00\x42\x00\x01", "transfer count of 0"),
    ],
)
def test_a_malformed_datagram_is_refused_with_its_cause(datagram: bytes, cause: str) -> None:
    with pytest.raises(Lbp16Error, match=cause):
        lbp16.parse(datagram)
