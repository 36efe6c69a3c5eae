"""stat.current_line, motion_line and read_line while a program runs (TASK-*): current_line is
the line of the command task last took from its queue (a dwell shows its own line), motion_line
the line of the move motion executes, read_line the interpreter's."""

from __future__ import annotations

import cnc


def test_lines_follow_the_program(start_machine) -> None:
    machine = start_machine()
    c, s = machine.command, machine.stat
    program = machine.folder / "lines.ngc"
    program.write_text("G21 G90\nG1 X20 F1200\nG4 P0.6\nG0 X0\nM2\n")
    machine.open_program(program)
    s.poll()
    assert s.current_line == 0 and s.motion_line == 0
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.motion_line == 2 and s.position[0] > 1.0, timeout=10)
    assert s.current_line >= 2 and s.read_line >= 2
    machine.until(lambda s: s.position[0] == 20.0 and s.current_line == 3, timeout=10)
    assert s.motion_line == 2  # dwelling: no move of line 3 or later has started
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE, timeout=10)
