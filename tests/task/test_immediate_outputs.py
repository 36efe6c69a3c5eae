"""Immediate outputs (M64, M65, M68) through the whole machine: once the MDI command that
sets one is taken (the command method returns), the status already shows the output, as
LinuxCNC's does (its tests/remap/remap-io reads stat.dout right after ``c.mdi("M64 P1")``)."""

from __future__ import annotations

import cnc
from tests.task.test_machine import Machine


def test_an_immediate_output_is_in_the_status_when_its_mdi_command_returns(
    machine: Machine,
) -> None:
    machine.ready_to_move()
    c, s = machine.command, machine.stat
    for line, expected_dout, expected_aout in (
        ("M64 P1", 1, 0.0),
        ("M68 E1 Q42.13", 1, 42.13),
        ("M65 P1", 0, 42.13),
        ("M68 E1 Q-13.42", 0, -13.42),
    ):
        c.mdi(line)  # no wait_complete: returns once task has taken the line
        s.poll()
        assert (s.dout[1], s.aout[1]) == (expected_dout, expected_aout), line
        assert c.wait_complete() == cnc.RCS_DONE
