"""Tool changes through the whole machine: [EMCIO] tool-change keys, the interpreter's view
of the tool table after edits, and the spindle around M6 (TOOL-017..027, IO-006..010).

Each test starts tests/task/machine/mill.ini with extra [EMCIO] keys (``start_machine``).
"""

from __future__ import annotations

import time

import pytest

import cnc
from tests.task.test_machine import Machine


def mdi(machine: Machine, *lines: str) -> None:
    for line in lines:
        machine.command.mdi(line)
        assert machine.command.wait_complete(20) == cnc.RCS_DONE, line
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos)


def test_m6_goes_to_the_tool_change_position_in_machine_coordinates(start_machine) -> None:
    machine = start_machine(EMCIO=["TOOL_CHANGE_POSITION = 50 40 30"])
    mdi(machine, "G10 L2 P1 X5 Y5 Z-5", "G54 G0 X1 Y2 Z3", "T2 M6")
    s = machine.stat
    assert s.position[:3] == pytest.approx((50.0, 40.0, 30.0), abs=1e-6)
    assert s.tool_in_spindle == 2
    mdi(machine, "G43 G0 X0 Y0")  # the program continues from there, offsets applied
    assert s.tool_offset[2] == pytest.approx(20.0)
    assert s.position[:3] == pytest.approx((5.0, 5.0, 30.0), abs=1e-6)


def test_quill_up_lifts_z_to_machine_zero_before_the_change(start_machine) -> None:
    machine = start_machine(EMCIO=["TOOL_CHANGE_QUILL_UP = 1"])
    mdi(machine, "G0 X12 Y-7 Z-20", "T1 M6")
    s = machine.stat
    assert s.position[:3] == pytest.approx((12.0, -7.0, 0.0), abs=1e-6)
    assert s.tool_in_spindle == 1


def test_the_spindle_stops_for_a_change_unless_configured_otherwise(start_machine) -> None:
    machine = start_machine()
    mdi(machine, "M3 S1000")
    assert machine.stat.spindle[0]["enabled"]
    mdi(machine, "T1 M6")
    assert not machine.stat.spindle[0]["enabled"]


def test_with_spindle_on_the_spindle_keeps_turning(start_machine) -> None:
    machine = start_machine(EMCIO=["TOOL_CHANGE_WITH_SPINDLE_ON = 1"])
    mdi(machine, "M3 S1000", "T1 M6")
    assert machine.stat.spindle[0]["enabled"] and machine.stat.spindle[0]["speed"] == 1000


def test_the_interpreter_sees_tool_table_edits_from_g10_and_from_the_file(start_machine) -> None:
    """G10 L1 changes iocontrol's table (and its file, atomically); a table file edited by
    hand and reloaded through the API reaches the interpreter before the next G43."""
    machine = start_machine()
    s = machine.stat
    mdi(machine, "G10 L1 P1 Z7.5 R2", "T1 M6", "G43")
    assert s.tool_offset[2] == pytest.approx(7.5)
    assert s.tool_table[1].zoffset == pytest.approx(7.5)
    first = (machine.folder / "test.tbl").read_text().splitlines()[0].split()
    assert first[:4] == ["T1", "P1", "D+4.000000", "Z+7.500000"]
    (machine.folder / "test.tbl").write_text("T1 P1 Z3.25 D6 ;edited\nT2 P2 Z20 D3\n")
    machine.command.load_tool_table()
    assert machine.command.wait_complete(10) == cnc.RCS_DONE
    machine.until(lambda s: s.tool_table[1].zoffset == pytest.approx(3.25))
    mdi(machine, "G43 H1")
    assert s.tool_offset[2] == pytest.approx(3.25)


def test_tool_offset_shows_the_applied_offset_g43_h_and_g49(start_machine) -> None:
    """stat.tool_offset is the offset in effect (G43 Hn with any tool, G49), not the
    table entry of the tool in the spindle."""
    machine = start_machine()
    s = machine.stat
    mdi(machine, "G43 H2 G0 X1")
    assert s.tool_in_spindle == 0 and s.tool_offset[2] == pytest.approx(20.0)
    mdi(machine, "G43 H1")
    assert s.tool_offset[2] == pytest.approx(10.0)
    mdi(machine, "G49")
    assert s.tool_offset[2] == 0.0


def test_spindle_commands_wait_for_the_moves_before_them(start_machine) -> None:
    """M5 after a cut stops the spindle once the cut is done, never during it (LinuxCNC's
    task preconditions: spindle commands wait for motion)."""
    machine = start_machine()
    c, s = machine.command, machine.stat
    program = machine.folder / "cut.ngc"
    program.write_text("G21 G90\nM3 S1000\nG1 X30 F1200\nM5\nG0 X0\nM2\n")
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    seen_during_cut = []
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE, timeout=5)
    while s.interp_state != cnc.INTERP_IDLE:
        s.poll()
        if 2.0 < s.position[0] < 28.0 and s.motion_line == 3:
            seen_during_cut.append(s.spindle[0]["enabled"])
        time.sleep(0.002)  # (a spinning test takes the machine's CPU)
    assert seen_during_cut and all(seen_during_cut)
    # (if the run ended early, the error channel says why)
    assert s.position[0] == pytest.approx(0.0), machine.messages()
    assert not s.spindle[0]["enabled"]
