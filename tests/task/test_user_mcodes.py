"""User M codes M100..M199 through the whole machine (TASK-*, INTERP: M100-M199): task finds
the executable files in PROGRAM_PREFIX and USER_M_PATH at start-up, runs them with P and Q,
and waits for them before the program goes on."""

from __future__ import annotations

import pytest

import cnc

SCRIPT = '#!/bin/sh\necho "$(basename "$0") $1 $2" >> "$(dirname "$0")/../calls.txt"\n'


def test_user_m_codes_run_with_p_and_q_in_order(start_machine) -> None:
    machine = start_machine(
        files={"nc/M101": SCRIPT, "more/M150": SCRIPT, "more/M101": "#!/bin/sh\nexit 0\n"},
        DISPLAY=["PROGRAM_PREFIX = nc"],
        RS274NGC=["USER_M_PATH = more"],
    )
    c = machine.command
    for line in ("M101 P1.5 Q-2", "M150", "G0 X3"):
        c.mdi(line)
        assert c.wait_complete(10) == cnc.RCS_DONE, line
    calls = (machine.folder / "calls.txt").read_text().splitlines()
    # nc/ before more/; an absent P or Q is -1, as LinuxCNC passes it
    assert calls == ["M101 1.500000 -2.000000", "M150 -1.000000 -1.000000"]


def test_an_m_code_without_a_program_is_an_error(start_machine) -> None:
    machine = start_machine()
    machine.messages(0.1)
    machine.command.mdi("M123")
    assert machine.command.wait_complete(5) == cnc.RCS_ERROR
    assert (cnc.OPERATOR_ERROR, "Unknown m code used: M123") in machine.messages()


@pytest.mark.parametrize("value", ["1 2", "a b c"])
def test_a_bad_tool_change_position_names_the_ini_line(value, tmp_path) -> None:
    from cnc.ini import IniError, IniFile
    from task.setup import load_setup

    ini = tmp_path / "m.ini"
    ini.write_text(f"[EMCIO]\nTOOL_CHANGE_POSITION = {value}\n")
    with pytest.raises(IniError, match=r"m.ini:2: .*TOOL_CHANGE_POSITION"):
        load_setup(IniFile.load(ini))
