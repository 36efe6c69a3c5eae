"""[RS274NGC]RS274NGC_STARTUP_CODE: task runs it when it starts, as LinuxCNC's (its
tests/rs274ngc-startup): the G43 it holds is applied before any UI command."""

from __future__ import annotations

import ast
import shutil
import sys

import pytest

import cnc
from tests.task.test_machine import MACHINE


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


# A display started with the machine, as LinuxCNC's launcher starts it (before task's first
# status): it notes the work offsets of every status it sees until task is up, then exits.
FIRST_STATUS_DISPLAY = """\
import sys, time
import cnc
s = cnc.stat()
seen = []
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    s.poll()
    if s.task_state:  # (zero until task's first status)
        seen.append((s.g5x_index, round(s.g5x_offset[0], 6), round(s.g92_offset[1], 6)))
        if len(seen) >= 20:
            break
    time.sleep(0.0005)
with open("seen.txt", "w") as out:
    out.write(repr(seen))
"""


def test_the_first_status_shows_the_offsets_of_the_parameter_file(procs, tmp_path) -> None:
    """The .var file's G55 with its offset, and a G92 offset, are in the very first status
    task publishes (LinuxCNC's startup-state test reads them as soon as the status looks
    initialised), not only once task's first cycle carried out what its interpreter queued."""
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    (folder / "mill.var").write_text(
        "5210\t1.000000\n5212\t2.500000\n5220\t2.000000\n5241\t7.000000\n"
    )
    ini = folder / "mill.ini"
    text = ini.read_text().replace("PARAMETER_FILE = test.var", "PARAMETER_FILE = mill.var")
    (folder / "first_status.py").write_text(f"#!{sys.executable}\n{FIRST_STATUS_DISPLAY}")
    (folder / "first_status.py").chmod(0o755)
    text = text.replace("[DISPLAY]\nDISPLAY =\n", "[DISPLAY]\nDISPLAY = ./first_status.py\n")
    ini.write_text(text)
    proc = procs.python("-m", "cnc", "run", "mill.ini", cwd=folder)
    _out, err = proc.communicate(timeout=90)
    assert proc.returncode == 0, err
    seen = ast.literal_eval((folder / "seen.txt").read_text())
    assert seen, "the display saw no status"
    assert set(seen) == {(2, 7.0, 2.5)}
