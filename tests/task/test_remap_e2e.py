"""Remapped codes and embedded Python through the whole machine (issue 16; REMAP-023..038,
PY-015..017, PY-024/025, TEST-008): task stops reading ahead at a handler's
``yield INTERP_EXECUTE_FINISH``, lets the queue run, synchronises the interpreter and
resumes the handler; errors abort the program, reach the UIs and run ON_ABORT_COMMAND.

Each test starts tests/task/machine/mill.ini (``start_machine``) with remaps of its own:
the tool changer is iocontrol's, its prepare and change handshakes looped back in HAL.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import cnc
from nml.ipcnames import instance_objects
from tests.task.test_machine import Machine

SIM = Path(__file__).resolve().parents[2] / "configs" / "sim"

pytestmark = pytest.mark.slow

# the standard glue around an NGC procedure that takes the old tool to its rack pocket and
# fetches the new one ([RACK]: pocket n at X = X0 + n * DX, Y, Z; T0 is an empty spindle)
RACK_INI = {
    "RS274NGC": [
        "SUBROUTINE_PATH = nc_subs",
        "REMAP=M6 modalgroup=6 prolog=change_prolog ngc=rack_change epilog=change_epilog",
        "ON_ABORT_COMMAND = O <on_abort> call",
    ],
    "PYTHON": ["PATH_PREPEND = python", "TOPLEVEL = python/toplevel.py"],
    "RACK": ["X0 = 20", "DX = 10", "Y = 50", "Z = -10", "FEED = 600"],
}
RACK_FILES = {
    "python/toplevel.py": "import remap\n",
    "python/remap.py": "from stdglue import *\n",
    "nc_subs/rack_change.ngc": """\
o<rack_change> sub
(debug, rack change from #<tool_in_spindle> to #<selected_tool>)
M5
G53 G0 Z0
o10 if [#<tool_in_spindle> GT 0]
  G53 G0 X[#<_ini[rack]x0> + #<tool_in_spindle> * #<_ini[rack]dx>] Y#<_ini[rack]y>
  G53 G1 Z#<_ini[rack]z> F#<_ini[rack]feed>
  M64 P0
  G4 P0.2 (the clamp lets go; the test's 10 ms polls see the tool down)
  G53 G0 Z0
o10 endif
o20 if [#<selected_tool> GT 0]
  G53 G0 X[#<_ini[rack]x0> + #<selected_tool> * #<_ini[rack]dx>] Y#<_ini[rack]y>
  G53 G1 Z#<_ini[rack]z> F#<_ini[rack]feed>
  M65 P0
  G4 P0.2
  G53 G0 Z0
o20 endif
o<rack_change> endsub [1]
M2
""",
    "nc_subs/on_abort.ngc": """\
o<on_abort> sub
(debug, on_abort reason #1 tool #5400)
M65 P0
o<on_abort> endsub
M2
""",
}


def mdi(machine: Machine, *lines: str) -> None:
    machine.command.mode(cnc.MODE_MDI)
    assert machine.command.wait_complete() == cnc.RCS_DONE
    for line in lines:
        machine.command.mdi(line)
        assert machine.command.wait_complete(30) == cnc.RCS_DONE, line
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos)


def hal(*words: str) -> str:
    done = subprocess.run(
        [sys.executable, "-m", "cnc", "halcmd", *words], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def texts(machine: Machine, wait: float = 0.5) -> list[str]:
    return [text.strip() for _, text in machine.messages(wait)]


def run_program(machine: Machine, name: str, text: str, timeout: float = 60) -> list[tuple]:
    """Run a program to its end; the positions seen every poll (x, y, z)."""
    program = machine.folder / name
    program.write_text(text)
    machine.open_program(program)
    machine.command.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE, timeout=5)
    seen = []
    machine.until(
        lambda s: seen.append(tuple(s.position[:3])) or s.interp_state == cnc.INTERP_IDLE,
        timeout=timeout,
    )
    return seen


def test_remapped_m6_changes_tools_at_the_rack_with_iocontrols_handshake(start_machine) -> None:
    """REMAP-026..030: prolog, NGC procedure and epilog; the epilog's CHANGE_TOOL goes
    through iocontrol's change handshake and its yield makes task synchronise before the
    G43 after it, which then applies the new tool's length (not the old one's)."""
    machine = start_machine(files=RACK_FILES, **RACK_INI)
    texts(machine, 0.1)
    seen = run_program(
        machine,
        "change.ngc",
        "G21 G90\nT1 M6\nG43\nG0 X0 Y0\nT2 M6\nG43\nG0 X5 Y5\nM2\n",
    )
    s = machine.stat
    assert s.tool_in_spindle == 2
    assert s.tool_offset[2] == pytest.approx(20.0)  # T2's length, applied after the synch
    assert s.position[:2] == pytest.approx((5.0, 5.0), abs=1e-6)
    # the spindle went down (G53 Z-10) at pocket 1 for T1, at pocket 1 again to put T1
    # back, at pocket 2 for T2
    at_pockets = {round(x) for x, y, z in seen if z < -9.99 and abs(y - 50) < 1e-6}
    assert at_pockets == {30, 40}, sorted(set(seen))
    messages = texts(machine)
    # (an empty spindle: -1 at start-up, as LinuxCNC's non-random tool table has it)
    assert "rack change from -1.000000 to 1.000000" in " ".join(messages)
    assert "rack change from 1.000000 to 2.000000" in " ".join(messages)
    # iocontrol's view and the interpreter's agree
    assert hal("getp", "iocontrol.0.tool-number") == "2"
    mdi(machine, "(debug, interpreter tool #5400)")
    assert "interpreter tool 2.000000" in " ".join(texts(machine))


def test_abort_in_a_remapped_tool_change_runs_on_abort_and_keeps_the_tool_agreed(
    start_machine,
) -> None:
    """REMAP-037: an abort while the procedure moves to the rack (the interpreter has
    already read ahead through the epilog) runs ON_ABORT_COMMAND with reason 8
    (EMC_ABORT_TASK_ABORT); afterwards the interpreter, task and iocontrol agree that the
    old tool is still in the spindle, and the next remapped change works."""
    rack = [line for line in RACK_INI["RACK"] if not line.startswith("FEED")] + ["FEED = 300"]
    machine = start_machine(files=RACK_FILES, **{**RACK_INI, "RACK": rack})
    mdi(machine, "M61 Q1")  # T1 in the spindle, without moving
    texts(machine, 0.1)
    program = machine.folder / "change.ngc"
    program.write_text("G21 G90\nT2 M6\nG43\nM2\n")
    machine.open_program(program)
    machine.command.auto(cnc.AUTO_RUN, 0)
    # on the way down to pocket 1, to put T1 back
    machine.until(lambda s: s.position[2] < -2.0 and abs(s.position[1] - 50) < 1e-6)
    machine.command.abort()
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos)
    messages = " ".join(texts(machine))
    assert "rack change from 1.000000 to 2.000000" in messages
    assert "on_abort reason 8.000000 tool 1.000000" in messages
    assert machine.stat.tool_in_spindle == 1
    assert hal("getp", "iocontrol.0.tool-number") == "1"
    mdi(machine, "(debug, interpreter tool #5400)")
    assert "interpreter tool 1.000000" in " ".join(texts(machine))
    # nothing of the interrupted remap is left: the next change runs through
    mdi(machine, "T2 M6", "G43")
    assert machine.stat.tool_in_spindle == 2
    assert machine.stat.tool_offset[2] == pytest.approx(20.0)


ERRORS_INI = {
    "RS274NGC": [
        "SUBROUTINE_PATH = nc_subs",
        "REMAP=M402 modalgroup=10 python=refuses",
        "REMAP=M404 modalgroup=10 ngc=clamp_check",
        "REMAP=M405 modalgroup=10 python=raises",
        "ON_ABORT_COMMAND = O <on_abort> call",
    ],
    "PYTHON": ["PATH_PREPEND = python", "TOPLEVEL = python/toplevel.py"],
}
ERRORS_FILES = {
    "python/toplevel.py": "import remap\n",
    "python/remap.py": """\
def refuses(self, **words):
    return "the part is not clamped"


def raises(self, **words):
    return 1 / 0
""",
    "nc_subs/clamp_check.ngc": """\
o<clamp_check> sub
#<clamp> = 3
(abort, clamp #<clamp> is open)
o<clamp_check> endsub
M2
""",
    "nc_subs/on_abort.ngc": RACK_FILES["nc_subs/on_abort.ngc"],
}


def test_an_error_in_a_remap_aborts_reaches_the_uis_and_runs_on_abort(start_machine) -> None:
    """REMAP-038, PY-016: a returned error string, ``(abort, ...)`` and an uncaught
    exception (named with the code and the handler) stop the program; the error reaches
    the UIs and ON_ABORT_COMMAND runs with reason 9 (EMC_ABORT_INTERPRETER_ERROR); in MDI
    with reason 10 (EMC_ABORT_INTERPRETER_ERROR_MDI)."""
    machine = start_machine(files=ERRORS_FILES, **ERRORS_INI)
    texts(machine, 0.1)
    for code, error in [
        ("M402", "the part is not clamped"),
        ("M404", "clamp 3.000000 is open"),
        ("M405", "M405/raises: ZeroDivisionError: division by zero"),
    ]:
        seen = run_program(machine, "error.ngc", f"G21 G90\nG0 X0\nG0 X1\n{code}\nG0 X2\nM2\n")
        program = machine.folder / "error.ngc"
        messages = texts(machine)
        assert f"{error} (line 4 of {program})" in messages, code
        assert "on_abort reason 9.000000 tool 0.000000" in messages, code
        assert max(x for x, _, _ in seen) < 1.5  # the line after it never ran
        machine.command.mode(cnc.MODE_MDI)
        assert machine.command.wait_complete() == cnc.RCS_DONE
        machine.command.mdi(code)
        assert machine.command.wait_complete(30) == cnc.RCS_ERROR
        machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
        messages = texts(machine)
        assert error in messages, code
        assert "on_abort reason 10.000000 tool 0.000000" in messages, code


INPUTS_INI = {
    "RS274NGC": [
        "REMAP=M400 modalgroup=10 argspec=q python=wait_for_fall",
        "REMAP=M401 modalgroup=10 argspec=Q python=wait_for_high",
        "REMAP=M403 modalgroup=10 python=report_status",
    ],
    "PYTHON": ["PATH_PREPEND = python", "TOPLEVEL = python/toplevel.py"],
}
INPUTS_FILES = {
    "python/toplevel.py": "import remap\n",
    "python/remap.py": """\
import emccanon
from interpreter import INTERP_EXECUTE_FINISH


def wait_for_fall(self, **words):
    # PY-017: wait up to 5 s (or Q) for digital input 00 (falling edge), let task synchronise
    emccanon.WAIT(0, 1, 2, words.get("q", 5.0))
    yield INTERP_EXECUTE_FINISH
    emccanon.MESSAGE("input 00 = %d" % emccanon.GET_EXTERNAL_DIGITAL_INPUT(0, 0))


def wait_for_high(self, **words):
    emccanon.WAIT(0, 1, 3, words["q"])
    yield INTERP_EXECUTE_FINISH
    emccanon.MESSAGE("after the wait: %d" % emccanon.GET_EXTERNAL_DIGITAL_INPUT(0, 0))


def report_status(self, **words):
    from emctask import emcstat, ini_filename, operator_text

    tool = emcstat.io.tool
    operator_text("spindle T%d estop %d ini %s" % (tool.toolInSpindle, emcstat.io.aux.estop,
                                                     ini_filename().rsplit("/", 1)[-1]))
""",
}


def test_a_python_handler_waits_for_an_input_and_reads_it_after_the_synch(
    start_machine,
) -> None:
    """PY-015, PY-017: ``emccanon.WAIT`` + ``yield INTERP_EXECUTE_FINISH``: task stops
    reading ahead, waits for the input, synchronises the interpreter and resumes the
    handler, which reads the input's value as it is now; after a timeout it reads -1.
    PY-024/025: ``emctask.emcstat`` is task's status."""
    machine = start_machine(files=INPUTS_FILES, **INPUTS_INI)
    texts(machine, 0.1)
    hal("setp", "motion.digital-in-00", "1")
    machine.command.mdi("M400 Q60")  # (60 s: time enough for a slow halcmd below)
    assert texts(machine, 1.0) == []  # waiting for the fall
    machine.stat.poll()
    assert machine.stat.interp_state != cnc.INTERP_IDLE
    hal("setp", "motion.digital-in-00", "0")
    machine.command.wait_complete(10)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
    assert texts(machine) == ["input 00 = 0"]

    mdi(machine, "M401 Q0.2")  # input 00 stays low: the wait times out
    assert texts(machine) == ["after the wait: -1"]
    assert machine.stat.input_timeout
    hal("setp", "motion.digital-in-00", "1")
    mdi(machine, "M401 Q5")
    assert texts(machine) == ["after the wait: 1"]

    mdi(machine, "M61 Q2", "M403")
    assert texts(machine) == ["spindle T2 estop 0 ini mill.ini"]


def test_the_minimal_remap_configuration_starts_runs_and_leaves_nothing(
    procs, tmp_path: Path, cnc_instance
) -> None:
    """TEST-015 (REMAP-053): configs/sim/remap/minimal.ini starts through the launcher without
    an error, goes through E-stop reset, on and homing, runs a program in AUTO and stops
    leaving no shared memory or semaphore behind."""
    folder = tmp_path / "sim"
    shutil.copytree(SIM, folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "remap/minimal.ini", cwd=folder)
    machine = Machine(proc, folder / "remap")
    machine.wait_ready()
    machine.ready_to_move()
    seen = run_program(machine, "smoke.ngc", "G21 G90\nG0 X10 Y10 Z10\nG1 X20 F3000\nM2\n")
    assert seen[-1] == pytest.approx((20.0, 10.0, 10.0))
    assert texts(machine) == []  # no error, no message
    machine.stop()
    assert proc.returncode == 0
    errors = proc.stderr.read()
    assert "rror" not in errors and "Traceback" not in errors, errors
    assert instance_objects(cnc_instance) == []
