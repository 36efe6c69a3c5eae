"""State tags through the whole machine (as LinuxCNC's tests/statbuffer-g5x-abort): while a
program runs, the status shows the modes and origin of the move motion carries out, not
of the lines the interpreter has read ahead; an abort brings the interpreter back to them,
so the next MDI move is in the coordinate system the program was in."""

from __future__ import annotations

import cnc
from tests.task.test_machine import Machine

PROGRAM = """\
%
G55
G0 X0 Y0 Z0
G1 X5 Y-5 F10 (slow: aborted here)
G56 (read ahead, never carried out)
M66 P0 L0 (a queue buster: the interpreter waits here)
%
"""


def test_an_abort_leaves_the_interpreter_in_the_running_moves_modes(machine: Machine) -> None:
    machine.ready_to_move()
    c = machine.command
    for line in ("G10 L2 P1 Z-4", "G10 L2 P2 Z-5", "G10 L2 P3 Z-6", "G54 G0 X0 Y0 Z0"):
        c.mdi(line)
        assert c.wait_complete() == cnc.RCS_DONE, line
    program = machine.folder / "g5x.ngc"
    program.write_text(PROGRAM)
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    # on the G1 (line 4), with the interpreter waiting at the M66 after G56
    machine.until(lambda s: s.motion_line == 4 and s.current_vel > 0)
    machine.until(lambda s: s.read_line == 6)
    s = machine.stat
    assert 550 in s.gcodes and 560 not in s.gcodes
    assert (s.g5x_index, s.g5x_offset[2]) == (2, -5.0)

    c.abort()
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos)
    assert 550 in machine.stat.gcodes
    machine.until(lambda s: s.g5x_index == 2)
    c.mode(cnc.MODE_MDI)
    c.wait_complete()
    c.mdi("G0 X0 Y0 Z0")
    assert c.wait_complete() == cnc.RCS_DONE
    machine.stat.poll()
    assert machine.stat.position[:3] == (0.0, 0.0, -5.0)  # G55's Z, not G56's
    assert (machine.stat.g5x_index, machine.stat.g5x_offset[2]) == (2, -5.0)
