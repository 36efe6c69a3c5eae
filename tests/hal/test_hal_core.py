"""HAL core: names, types, links and values shared through shared memory (HAL-001..006)."""

from __future__ import annotations

import pytest

from hal.core import (
    HAL_BIT,
    HAL_FLOAT,
    HAL_IN,
    HAL_IO,
    HAL_OUT,
    HAL_RO,
    HAL_RW,
    HAL_S32,
    HAL_U32,
    Hal,
    HalError,
    format_value,
    is_compliant_name,
    parse_value,
)


@pytest.fixture
def hal():
    h = Hal()
    yield h
    h.destroy()
    h.close()


def test_name_longer_than_47_characters_is_refused(hal: Hal) -> None:
    hal.new_component("c")
    hal.new_pin("c", "a" * 47, HAL_BIT, HAL_IN)  # LinuxCNC's HAL_NAME_LEN
    with pytest.raises(HalError, match="too long"):
        hal.new_pin("c", "a" * 48, HAL_BIT, HAL_IN)
    with pytest.raises(HalError, match="too long"):
        hal.new_signal("s" * 48, HAL_BIT)


def test_names_take_any_printable_character_but_blanks(hal: Hal) -> None:
    """As LinuxCNC, which checks only the length: pyvcp panels make pins like "jog-x+"."""
    hal.new_component("c")
    hal.new_pin("c", "pyvcp.jog-x+", HAL_BIT, HAL_IN)
    hal.new_signal("x=1/2", HAL_BIT)
    for bad in ("two words", "tab\there", "é"):
        with pytest.raises(HalError, match="invalid characters"):
            hal.new_pin("c", bad, HAL_BIT, HAL_IN)


def test_naming_rules_are_checked() -> None:
    assert is_compliant_name("pid.0.p-gain")
    assert not is_compliant_name("pid.0.Pgain")
    assert not is_compliant_name("tool_changed")


def test_duplicate_names_are_refused(hal: Hal) -> None:
    hal.new_component("c")
    hal.new_pin("c", "c.x", HAL_FLOAT, HAL_IN)
    with pytest.raises(HalError, match="duplicate"):
        hal.new_pin("c", "c.x", HAL_FLOAT, HAL_OUT)
    with pytest.raises(HalError, match="duplicate component"):
        hal.new_component("c")


def test_in_pin_reads_signal_slot_after_link_and_keeps_value_after_unlink(hal: Hal) -> None:
    hal.new_component("c")
    out = hal.new_pin("c", "c.out", HAL_FLOAT, HAL_OUT)
    inp = hal.new_pin("c", "c.in", HAL_FLOAT, HAL_IN)
    hal.new_signal("s", HAL_FLOAT)
    hal.link("c.out", "s")
    hal.link("c.in", "s")
    hal.f[hal.ptr[out]] = 4.25
    assert hal.f[hal.ptr[inp]] == 4.25
    hal.unlink("c.in")
    hal.f[hal.ptr[out]] = 1.0
    assert hal.f[hal.ptr[inp]] == 4.25


def test_second_writer_and_type_mismatch_are_refused(hal: Hal) -> None:
    hal.new_component("c")
    hal.new_pin("c", "c.o1", HAL_BIT, HAL_OUT)
    hal.new_pin("c", "c.o2", HAL_BIT, HAL_OUT)
    hal.new_pin("c", "c.io", HAL_BIT, HAL_IO)
    hal.new_pin("c", "c.f", HAL_FLOAT, HAL_IN)
    hal.new_signal("s", HAL_BIT)
    hal.link("c.o1", "s")
    with pytest.raises(
        HalError, match=r"can not add OUT pin 'c.o2', it already has OUT pin 'c.o1'"
    ):
        hal.link("c.o2", "s")
    with pytest.raises(HalError, match="can not add I/O pin"):
        hal.link("c.io", "s")
    with pytest.raises(HalError, match=r"type mismatch 'c.f' <- 's'"):
        hal.link("c.f", "s")


def test_io_pins_may_share_a_signal(hal: Hal) -> None:
    hal.new_component("c")
    hal.new_pin("c", "c.a", HAL_BIT, HAL_IO)
    hal.new_pin("c", "c.b", HAL_BIT, HAL_IO)
    hal.new_signal("s", HAL_BIT)
    hal.link("c.a", "s")
    hal.link("c.b", "s")
    assert hal.meta["sigs"]["s"]["bidirs"] == 2


def test_second_process_attachment_sees_metadata_and_values(hal: Hal) -> None:
    hal.new_component("c")
    slot = hal.new_param("c", "c.gain", HAL_FLOAT, HAL_RW)
    other = Hal()
    try:
        assert other.meta["params"]["c.gain"]["slot"] == slot
        other.f[slot] = 3.5
        assert hal.f[slot] == 3.5
        other.new_signal("from-other", HAL_S32)
        assert "from-other" in hal.meta["sigs"]
    finally:
        other.close()


def test_remove_component_frees_pins_and_unlinks(hal: Hal) -> None:
    hal.new_component("c")
    hal.new_pin("c", "c.out", HAL_BIT, HAL_OUT)
    hal.new_param("c", "c.p", HAL_BIT, HAL_RO)
    hal.new_signal("s", HAL_BIT)
    hal.link("c.out", "s")
    hal.remove_component("c")
    assert hal.meta["pins"] == {} and hal.meta["params"] == {}
    assert hal.meta["sigs"]["s"]["writers"] == 0


def test_values_wrap_and_parse_like_halcmd() -> None:
    assert parse_value(HAL_BIT, "TRUE") == 1
    assert parse_value(HAL_S32, "0x10") == 16
    with pytest.raises(HalError, match="value 'xyz' invalid for bit"):
        parse_value(HAL_BIT, "xyz")
    with pytest.raises(HalError):
        parse_value(HAL_U32, "-1")
    assert format_value(HAL_U32, 50) == "0x00000032"
    assert format_value(HAL_FLOAT, 2.5) == "2.5"
    assert format_value(HAL_BIT, 0) == "FALSE"


def test_s32_pin_wraps_on_write(hal: Hal) -> None:
    from hal.api import make_accessor

    hal.new_component("c")
    slot = hal.new_pin("c", "c.n", HAL_S32, HAL_OUT)
    acc = make_accessor(hal, HAL_S32, slot, is_pin=True)
    acc.__set__(None, (1 << 31) + 5)
    assert acc.__get__(None) == -(1 << 31) + 5
    u = make_accessor(hal, HAL_U32, hal.new_pin("c", "c.u", HAL_U32, HAL_OUT), is_pin=True)
    u.__set__(None, -1)
    assert u.__get__(None) == 0xFFFFFFFF


def test_funct_added_in_position_order(hal: Hal) -> None:
    hal.new_component("c")
    for name in ("f1", "f2", "f3"):
        hal.new_funct("c", name)
    hal.new_thread("c", "t", 1000000)
    hal.add_funct("f1", "t")
    hal.add_funct("f2", "t")
    hal.add_funct("f3", "t", 1)
    assert hal.meta["threads"]["t"]["functs"] == ["f3", "f1", "f2"]
    with pytest.raises(HalError, match="may only be added to one thread"):
        hal.new_thread("c", "t2", 2000000)
        hal.add_funct("f1", "t2")
