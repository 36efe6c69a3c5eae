"""What task stops, steps and skips, as LinuxCNC does (issue 14 items 1, 4, 5, 6).

LinuxCNC's behaviour here was checked on its headless sim (../shared/reference), not taken
from memory: abort, E-stop and machine off stop every spindle and turn the coolant off;
a step while paused runs exactly the next line and pauses again; run from line starts from
where the machine stands, with the modal state of the lines it skipped.
"""

from __future__ import annotations

import pytest

import cnc
from tests.task.test_machine import Machine


def spindle_and_coolant_on(machine: Machine) -> None:
    c = machine.command
    for line in ("M3 S1000", "M7", "M8"):
        c.mdi(line)
        assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.spindle[0]["speed"] == 1000 and s.flood and s.mist)


def is_all_off(s) -> bool:
    spindle = s.spindle[0]
    return (
        spindle["speed"] == 0
        and spindle["direction"] == 0
        and s.flood == cnc.FLOOD_OFF
        and s.mist == cnc.MIST_OFF
    )


@pytest.mark.parametrize("how", ["abort", "estop", "off"])
def test_abort_estop_and_machine_off_stop_the_spindle_and_coolant(machine: Machine, how) -> None:
    machine.ready_to_move()
    spindle_and_coolant_on(machine)
    c = machine.command
    if how == "abort":
        c.abort()
    else:
        c.state(cnc.STATE_ESTOP if how == "estop" else cnc.STATE_OFF)
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(is_all_off)


def test_an_unknown_subroutine_in_mdi_is_an_error_not_a_hang(machine: Machine) -> None:
    machine.ready_to_move()
    c = machine.command
    c.mdi("o<nosuchsub> call")
    assert c.wait_complete() == cnc.RCS_ERROR
    assert "File not open" in [text for _, text in machine.messages()]
    c.mdi("G0 X1")
    assert c.wait_complete() == cnc.RCS_DONE


def test_step_while_paused_runs_exactly_the_next_line(machine: Machine) -> None:
    program = machine.folder / "square.ngc"
    program.write_text("G21 G90\nG1 F600 X20\nG1 Y20\nG1 X0\nG1 Y0\nM2\n")
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.position[0] > 2.0)  # in the middle of line 2
    c.auto(cnc.AUTO_PAUSE)
    machine.until(lambda s: s.paused and s.current_vel == 0)
    ends = []
    for _ in range(3):
        c.auto(cnc.AUTO_STEP)
        c.wait_complete()
        machine.until(lambda s: s.current_vel > 0, timeout=10)
        machine.until(lambda s: s.interp_state == cnc.INTERP_PAUSED and s.current_vel == 0)
        ends.append(tuple(round(v) for v in machine.stat.position[:2]))
    assert ends == [(20, 0), (20, 20), (0, 20)]  # one line a step, paused after each
    c.auto(cnc.AUTO_RESUME)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
    assert tuple(round(v) for v in machine.stat.position[:2]) == (0, 0)


def test_run_from_inside_a_loop_or_subroutine_is_refused(machine: Machine) -> None:
    program = machine.folder / "loop.ngc"
    program.write_text(
        "G21 G90\n#1 = 0\no100 while [#1 LT 3]\nG1 F600 X[#1]\n#1 = [#1 + 1]\n"
        "o100 endwhile\nG0 X0\nM2\n"
    )
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 4)
    assert c.wait_complete() == cnc.RCS_ERROR
    texts = [text for _, text in machine.messages()]
    assert any("cannot run from line 4" in t and "o100 while (lines 3-6)" in t for t in texts)
    c.auto(cnc.AUTO_RUN, 7)  # after the loop: allowed
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)


def test_run_from_line_keeps_the_tool_offset_motion_and_interpreter_agree(
    machine: Machine,
) -> None:
    machine.ready_to_move()
    c = machine.command
    c.mdi("T1 M6")
    assert c.wait_complete(10) == cnc.RCS_DONE
    program = machine.folder / "offset.ngc"
    program.write_text("G21 G90\nG43 H1\nG0 Z5\nG0 X3\nM2\n")
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 4)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos)
    s = machine.stat
    offset = s.tool_table[0].zoffset  # the tool in the spindle's length
    assert offset != 0 and s.tool_offset[2] == pytest.approx(offset)  # the skipped G43 holds
    c.mode(cnc.MODE_MDI)
    c.wait_complete()
    c.mdi("G0 Z0")  # the interpreter applies the same offset
    assert c.wait_complete(10) == cnc.RCS_DONE
    machine.until(lambda s: s.inpos)
    assert machine.stat.position[2] == pytest.approx(offset)


def test_run_from_line_after_a_skipped_tool_change_is_refused(machine: Machine) -> None:
    machine.ready_to_move()
    c = machine.command
    program = machine.folder / "change.ngc"
    program.write_text("G21 G90\nT2 M6\nG43 H2\nG0 Z5\nG0 X3\nM2\n")
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 5)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
    texts = [text for _, text in machine.messages()]
    assert any("changes to tool 2" in t and "load tool 2 first" in t for t in texts), texts
    assert machine.stat.position[0] == pytest.approx(0.0)  # nothing moved


def test_optional_stop_starts_on_so_m1_pauses_until_it_is_switched_off(machine: Machine) -> None:
    """LinuxCNC starts with the optional stop on (its startup-state test): M1 pauses like
    M0, motion paused too (stat.paused, checked on LinuxCNC's sim); switched off, M1 is
    passed over."""
    program = machine.folder / "m1.ngc"
    program.write_text("G21 G90\nG0 X5\nM1\nG0 X10\nM1\nG0 X15\nM2\n")
    machine.stat.poll()
    assert machine.stat.optional_stop is True and machine.stat.block_delete is True
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.interp_state == cnc.INTERP_PAUSED and s.current_vel == 0)
    assert round(machine.stat.position[0]) == 5
    machine.until(lambda s: s.paused and s.task_paused)
    c.set_optional_stop(0)
    assert c.wait_complete() == cnc.RCS_DONE
    c.auto(cnc.AUTO_RESUME)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
    assert round(machine.stat.position[0]) == 15 and machine.stat.optional_stop is False
