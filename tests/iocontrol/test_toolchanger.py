"""Tool changer rules in-process: handshakes, T0, random swaps, M61, G10 (IO-006..015)."""

from __future__ import annotations

import pytest

from iocontrol.toolchanger import NO_POCKET, ToolChangeError, ToolChanger
from iocontrol.tooltable import ToolTable

NONRANDOM = ["T1 P1 Z0.5 ;one\n", "T2 P7 Z1.0 D3 ;two\n", "T3 P4 Z2.0 ;three\n"]
RANDOM = ["T5 P0 Z5.0 ;five\n", "T1 P1 Z0.5 ;one\n", "T2 P2 Z1.0 ;two\n"]


def changer(lines: list[str], *, is_random: bool = False) -> ToolChanger:
    table = ToolTable(random_toolchanger=is_random)
    table.load_lines(lines, "tool.tbl")
    return ToolChanger(table)


def change_to(tc: ToolChanger, toolno: int) -> None:
    """T<toolno> M6 with a changer that acknowledges at once."""
    tc.prepare(toolno)
    tc.poll(is_prepared=True, is_changed=False)
    tc.start_change()
    tc.poll(is_prepared=False, is_changed=True)


def test_nonrandom_starts_with_an_empty_spindle() -> None:
    tc = changer(NONRANDOM)
    assert (tc.tool_in_spindle, tc.pocket_prepped, tc.spindle().toolno) == (0, NO_POCKET, -1)
    # the cleared record LinuxCNC's table load leaves: #<_current_pocket> reads -1
    assert tc.spindle().pocketno == -1


def test_prepare_sets_pins_and_waits_for_prepared() -> None:
    tc = changer(NONRANDOM)
    tc.prepare(2)
    assert tc.is_preparing and tc.is_pending
    assert (tc.prep_number, tc.prep_pocket, tc.prep_index) == (2, 7, 2)
    assert not tc.poll(is_prepared=False, is_changed=False)
    assert tc.pocket_prepped == NO_POCKET
    assert tc.poll(is_prepared=True, is_changed=False)
    assert not tc.is_pending and tc.pocket_prepped == 2


def test_nonrandom_change_copies_the_record_into_the_spindle() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 2)
    assert (tc.tool_in_spindle, tc.tool_from_pocket, tc.pocket_prepped) == (2, 7, NO_POCKET)
    assert (tc.prep_number, tc.prep_pocket, tc.prep_index) == (0, 0, 0)
    spindle = tc.spindle()
    assert (spindle.toolno, spindle.offset[2], spindle.diameter) == (2, 1.0, 3.0)
    assert tc.table.get(2).toolno == 2  # the home pocket keeps its tool (TOOL-002)


def test_nonrandom_t0_empties_the_spindle() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 1)
    tc.prepare(0)
    assert (tc.prep_number, tc.prep_pocket, tc.pocket_prepped) == (0, 0, 0)
    assert tc.is_preparing  # the changer still gets the handshake
    tc.poll(is_prepared=True, is_changed=False)
    tc.start_change()
    tc.poll(is_prepared=False, is_changed=True)
    assert (tc.tool_in_spindle, tc.tool_from_pocket, tc.spindle().toolno) == (0, 0, 0)


def test_changing_to_the_loaded_tool_needs_no_handshake() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 3)
    tc.prepare(3)
    tc.poll(is_prepared=True, is_changed=False)
    tc.start_change()
    assert not tc.is_changing


def test_random_change_swaps_spindle_and_pocket() -> None:
    tc = changer(RANDOM, is_random=True)
    assert tc.tool_in_spindle == 5
    change_to(tc, 2)
    assert (tc.tool_in_spindle, tc.tool_from_pocket) == (2, 2)
    assert (tc.table.get(0).toolno, tc.table.get(2).toolno) == (2, 5)
    assert tc.table.get(2).offset[2] == 5.0 and tc.table.get(2).comment == "five"
    assert tc.table.format().splitlines()[0].startswith("T2   P0")


def test_random_prepare_of_the_spindle_tool_completes_at_once() -> None:
    tc = changer(RANDOM, is_random=True)
    tc.prepare(5)
    assert not tc.is_pending and tc.pocket_prepped == 0 and tc.prep_number == 5
    tc.start_change()
    assert not tc.is_changing


def test_random_change_into_an_empty_spindle() -> None:
    tc = changer(RANDOM[1:], is_random=True)
    assert tc.tool_in_spindle == -1  # no tool in pocket 0, as LinuxCNC reports it
    change_to(tc, 1)
    assert tc.tool_in_spindle == 1
    assert [line.split()[:2] for line in tc.table.format().splitlines()] == [
        ["T1", "P0"],
        ["T2", "P2"],
    ]


def test_unknown_tool_and_change_without_prepare_are_errors() -> None:
    tc = changer(NONRANDOM)
    with pytest.raises(ToolChangeError, match="tool 9"):
        tc.prepare(9)
    with pytest.raises(ToolChangeError, match="no tool is prepared"):
        tc.start_change()
    assert not tc.is_pending


def test_cancel_drops_a_pending_handshake() -> None:
    tc = changer(NONRANDOM)
    tc.prepare(1)
    tc.cancel()
    assert not tc.is_pending
    assert not tc.poll(is_prepared=True, is_changed=True)
    assert tc.pocket_prepped == NO_POCKET


def test_set_number_loads_without_handshake() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 1)
    assert tc.tool_from_pocket == 1
    tc.set_number(3)  # M61 Q3: the interpreter sends the tooldata index
    # tool-from-pocket is the last handshake change's, as in LinuxCNC (test toolchanger/m61)
    assert (tc.tool_in_spindle, tc.tool_from_pocket, tc.spindle().toolno) == (3, 1, 3)
    assert not tc.is_pending
    tc.set_number(0)
    assert (tc.tool_in_spindle, tc.tool_from_pocket) == (0, 0)
    with pytest.raises(ToolChangeError):
        tc.set_number(5000)


def test_set_offset_updates_the_spindle_copy_on_nonrandom() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 2)
    tc.set_offset(2, 2, [0, 0, 9.5, 0, 0, 0, 0, 0, 0], 4.0, 0, 0, 0)
    assert tc.table.get(2).offset[2] == 9.5 and tc.table.get(2).pocketno == 7
    assert tc.spindle().offset[2] == 9.5 and tc.spindle().diameter == 4.0
    assert "T2   P7   D+4.000000 Z+9.500000" in tc.table.format()


def test_reload_keeps_the_spindle_tool_with_its_new_data() -> None:
    tc = changer(NONRANDOM)
    change_to(tc, 1)
    fresh = ToolTable()
    fresh.load_lines(["T1 P1 Z0.75\n", "T4 P2\n"], "tool.tbl")
    tc.replace_table(fresh)
    assert tc.tool_in_spindle == 1 and tc.spindle().offset[2] == 0.75
    assert tc.table.find_index_for_tool(4) == 2
