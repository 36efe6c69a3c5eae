"""A move motion refuses ends the program (LinuxCNC's task aborts it): nothing queued after
the refused move runs, though task had already sent it to motion."""

from __future__ import annotations

import cnc


def test_a_move_beyond_a_soft_limit_ends_the_program_there(start_machine) -> None:
    machine = start_machine()
    c, s = machine.command, machine.stat
    program = machine.folder / "limits.ngc"
    short_moves = [f"G1 X{0.01 * i:.2f}" for i in range(1, 40)]  # (queued ahead)
    tail = ["G1 X500", "M3 S1000", "G1 X30 Y30", "G1 X40", "M2"]
    program.write_text("\n".join(["G21 G90 G64 F3000", *short_moves, *tail]) + "\n")
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE, timeout=20)
    texts = [text for _, text in machine.messages()]
    s.poll()
    assert s.position[0] <= 0.39 and s.position[1] == 0.0  # stopped before the hole
    assert s.spindle[0]["speed"] == 0.0  # the M3 after it never ran
    assert "Linear move on line 41 would exceed X's positive limit" in texts
    # a new MDI move runs: the abort ended motion's refusals
    c.mode(cnc.MODE_MDI)
    c.wait_complete()
    c.mdi("G1 X5 F3000")
    machine.until(lambda s: s.position[0] == 5.0, timeout=10)
