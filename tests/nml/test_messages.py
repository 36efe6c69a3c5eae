"""The declaration mechanism: one class gives both encodings, defaults, registry (NML-037..052)."""

from __future__ import annotations

import msgpack
import pytest

from nml import emc
from nml.codec import HEADER, Encoding, decode, encode, max_encoded_size, peek_type
from nml.errors import NmlFormatError, NmlRegistryError
from nml.message import RCS_CMD_MSG, RCS_STAT_MSG, RCS_STATUS, Struct, array, f64, i32, string
from nml.registry import REGISTRY


class Point(Struct):
    x: f64
    y: f64 = 2.5


class DEMO_MOVE(RCS_CMD_MSG, type_id=90101):
    target: Point
    path: array(Point, 3)
    speeds: array(f64, 4)
    label: string(8)
    count: i32 = 7


def test_one_declaration_gives_fields_defaults_and_nested_access() -> None:
    move = DEMO_MOVE(serial_number=4, label="abc")
    assert (move.count, move.target.y, move.path[2].y, move.label) == (7, 2.5, 2.5, "abc")
    move.target.x = 1.0
    move.path[1].x = -3.0
    move.speeds[3] = 9.0
    assert move.to_python() == {
        "serial_number": 4,
        "target": {"x": 1.0, "y": 2.5},
        "path": [{"x": 0.0, "y": 2.5}, {"x": -3.0, "y": 2.5}, {"x": 0.0, "y": 2.5}],
        "speeds": [0.0, 0.0, 0.0, 9.0],
        "label": "abc",
        "count": 7,
    }
    assert DEMO_MOVE.fixed_size() == 8 * 2 + 16 * 3 + 8 * 4 + 8 + 4 + 4
    assert move.size == HEADER.size + DEMO_MOVE.fixed_size()


def test_status_starts_uninitialized() -> None:
    assert RCS_STAT_MSG().status == RCS_STATUS.UNINITIALIZED == -1


@pytest.mark.parametrize("encoding", list(Encoding))
def test_both_encodings_round_trip(encoding: Encoding) -> None:
    move = DEMO_MOVE(serial_number=11, label="ü8")
    move.path[0].x = 1e300
    data = encode(move, encoding)
    assert peek_type(data) == 90101
    assert decode(data) == move
    assert len(data) <= max_encoded_size(DEMO_MOVE, encoding)


def test_msgpack_is_the_leaf_values_in_declaration_order() -> None:
    move = DEMO_MOVE(serial_number=3, label="x")
    move.path[1].x = -1.0
    data = encode(move, Encoding.MSGPACK)
    assert msgpack.unpackb(data[HEADER.size :]) == [
        3,
        0.0,
        2.5,
        0.0,
        2.5,
        -1.0,
        2.5,
        0.0,
        2.5,
        0.0,
        0.0,
        0.0,
        0.0,
        b"x",
        7,
    ]


def test_text_that_does_not_fit_is_refused() -> None:
    with pytest.raises(ValueError, match=r"DEMO_MOVE\.label: 9 bytes do not fit in 8"):
        DEMO_MOVE(label="123456789")


def test_fit_text_cuts_a_long_text_at_a_character_boundary() -> None:
    """Operator messages, file names and MDI texts are cut to their field, never refused;
    cutting by characters (text[:255]) gave non-ASCII texts too many bytes, and task
    crashed on such an error message."""
    text = "fichero ñandú " * 40  # 2 bytes per ñ and ú
    fitted = emc.fit_text(text)
    assert len(fitted.encode("utf-8")) <= emc.LINELEN - 1
    assert text.startswith(fitted) and len(fitted) > 200
    assert emc.EMC_OPERATOR_ERROR(error=fitted).error == fitted
    assert emc.fit_text("short") == "short"
    assert emc.fit_text("ñ" * 10, size=6) == "ññ"  # 5 bytes: the third ñ would be cut in two


def test_unknown_field_is_refused() -> None:
    with pytest.raises(TypeError, match="DEMO_MOVE has no field 'speed'"):
        DEMO_MOVE(speed=1)


def test_field_without_nml_type_is_refused() -> None:
    with pytest.raises(TypeError, match=r"BadStruct.n: not an NML field type"):

        class BadStruct(Struct):
            n: int


def test_registry_rejects_duplicate_numbers_and_names() -> None:
    with pytest.raises(NmlRegistryError, match="type 90101 of OTHER_MOVE is already used by DEMO"):

        class OTHER_MOVE(RCS_CMD_MSG, type_id=90101):
            pass

    with pytest.raises(NmlRegistryError, match="name DEMO_MOVE is already registered"):

        def declare_again():  # a second class of the same name, another number
            class DEMO_MOVE(RCS_CMD_MSG, type_id=90102):
                pass

        declare_again()


def test_symbol_lookup() -> None:
    assert REGISTRY.symbol(90101) == "DEMO_MOVE"
    assert REGISTRY.by_name("DEMO_MOVE") is DEMO_MOVE
    assert REGISTRY.symbol(424242) == "UNKNOWN_TYPE_424242"


@pytest.mark.parametrize(
    ("mangle", "cause"),
    [
        (lambda d: d[:10], "shorter than its 16-byte header"),
        (lambda d: HEADER.pack(424242, 0, 0, 0), "unknown message type 424242"),
        (lambda d: d[:-4], "claims .* payload bytes, only"),
        (lambda d: d[:8] + b"\0\0\0\0" + d[12:], "different field layout"),
        (lambda d: d[:12] + b"\x07\0\0\0" + d[16:], "unknown encoding 7"),
    ],
)
def test_corrupt_bytes_are_clear_errors(mangle, cause: str) -> None:
    data = encode(DEMO_MOVE(), Encoding.FIXED)
    with pytest.raises(NmlFormatError, match=f"^where: .*{cause}|^where: {cause}"):
        decode(mangle(data), "where")


def test_corrupt_msgpack_payload_is_a_clear_error() -> None:
    data = bytearray(encode(DEMO_MOVE(), Encoding.MSGPACK))
    data[HEADER.size] = 0xC1  # never used by msgpack
    with pytest.raises(NmlFormatError, match="msgpack payload is corrupt"):
        decode(bytes(data), "where")
    wrong = HEADER.pack(90101, 1, DEMO_MOVE.layout_crc, 1) + msgpack.packb(5)
    with pytest.raises(NmlFormatError, match="not an array"):
        decode(wrong, "where")
    short = msgpack.packb([1, 2.0])
    wrong = HEADER.pack(90101, len(short), DEMO_MOVE.layout_crc, 1) + short
    with pytest.raises(NmlFormatError, match="msgpack values do not fit"):
        decode(wrong, "where")
