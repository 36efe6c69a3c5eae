"""A program of many short moves fills motion's planner queue: task must wait for room, never
overflow it (LinuxCNC's queueFull margin); nothing is refused and the run goes on."""

from __future__ import annotations

import time

import cnc


def test_a_program_longer_than_the_planner_queue_waits_for_room(start_machine) -> None:
    machine = start_machine()
    c, s = machine.command, machine.stat
    program = machine.folder / "dense.ngc"
    moves = "".join(f"G1 X{(i % 2) * 0.002:.3f} Y{i * 0.001:.3f}\n" for i in range(1, 2601))
    program.write_text("G21 G90 G64\nF6\n" + moves + "M2\n")
    machine.messages(0.1)
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    deadline = time.monotonic() + 60
    while True:  # until task has filled the planner up to its margin
        s.poll()
        assert time.monotonic() < deadline, f"queue reached only {s.queue}"
        if s.queue_full:  # fewer than the margin's 200 slots free
            break
        time.sleep(0.05)
    assert s.queue > 1800 and s.interp_state != cnc.INTERP_IDLE
    time.sleep(0.5)  # task keeps the planner topped up, never beyond it
    s.poll()
    assert 1790 <= s.queue <= 2000 and s.state != cnc.RCS_ERROR
    assert machine.messages(0.2) == []
    c.abort()
    c.wait_complete()
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.queue == 0)
