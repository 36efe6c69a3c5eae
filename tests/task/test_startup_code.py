"""[RS274NGC]RS274NGC_STARTUP_CODE: task runs it when it starts, as LinuxCNC's (its
tests/rs274ngc-startup): the G43 it holds is applied before any UI command."""

from __future__ import annotations

import pytest

import cnc


def test_the_startup_code_applies_its_tool_offset(start_machine) -> None:
    machine = start_machine(RS274NGC=["RS274NGC_STARTUP_CODE = G43 H1"])
    s = machine.stat
    s.poll()
    assert s.tool_offset[2] == pytest.approx(10.0)  # T1's length (tests/task/machine)
    assert 430 in s.gcodes  # G43 is the interpreter's mode too


def test_a_bad_startup_code_is_reported_and_task_runs_on(start_machine) -> None:
    machine = start_machine(RS274NGC=["RS274NGC_STARTUP_CODE = G43 H99"])
    texts = [text for _kind, text in machine.messages()]
    assert any("RS274NGC_STARTUP_CODE" in text for text in texts), texts
    machine.command.mdi("G0 X1")
    assert machine.command.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.position[0] == pytest.approx(1.0) and s.inpos)
