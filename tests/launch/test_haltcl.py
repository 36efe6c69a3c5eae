"""Tcl HAL files through a real Tcl interpreter (issue 17, "Tcl HAL files")."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniFile
from hal.core import HAL_FLOAT, HAL_IN, HAL_OUT
from hal.halcmd import HalCmd
from hal.haltcl import HALCMD_VERBS, HalTcl
from tests.launch.conftest import needs_tcl

pytestmark = needs_tcl

INI = """\
[KINS]
KINEMATICS = trivkins coordinates=XZ
JOINTS = 2
[HAL]
HALFILE = first.tcl
HALFILE = LIB:second.hal -x
[JOINT_0]
HOME_SEARCH_VEL = -5
"""


def run(session: HalCmd, tmp_path: Path, script: str, *args: str, ini: str = INI) -> bool:
    path = tmp_path / "test.tcl"
    path.write_text(script)
    inifile = IniFile.from_text(ini, str(tmp_path / "test.ini"))
    return HalTcl(session, inifile).run_file(path, args)


def with_pin(session: HalCmd) -> None:
    """A component of the test's own with float pins tc.in (IN) and tc.out (OUT)."""
    with session.hal.edit():
        session.hal.new_component("tc")
        session.hal.new_pin("tc", "tc.in", HAL_FLOAT, HAL_IN)
        session.hal.new_pin("tc", "tc.out", HAL_FLOAT, HAL_OUT)


def test_ini_values_are_lists_per_key_as_linuxcnc_parse_ini(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    script = (
        'puts "[llength $::KINS(KINEMATICS)]|[lindex $::KINS(KINEMATICS) 0]"\n'
        'puts "$::KINS(JOINTS)|[llength $::HAL(HALFILE)]|[lindex $::HAL(HALFILE) 1]"\n'
        'puts "[expr {$::JOINT_0(HOME_SEARCH_VEL) < 0}]|$::argv|$::argc"\n'
        "puts [info exists ::env(PATH)]\n"
    )
    assert run(session, tmp_path, script, "-no_sim_spindle", "two")
    assert capfd.readouterr().out.splitlines() == [
        "1|trivkins coordinates=XZ",
        "2|2|LIB:second.hal -x",
        "1|-no_sim_spindle two|2",
        "1",
    ]


def test_halcmd_verbs_are_tcl_commands_with_halcmds_output(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    with_pin(session)
    script = (
        "setp tc.in 2*1.25\n"  # setp evaluates its value with expr, as haltcl does
        "puts [getp tc.in]\n"
        "net s tc.out tc.in\n"
        "puts [hal stype s]\n"
        "newsig lonely u32\n"
        "sets lonely 0x10\n"
        "puts [hal gets lonely]\n"
        "puts [llength [hal --commands]]\n"
        "show sig lonely\n"
    )
    assert run(session, tmp_path, script)
    lines = capfd.readouterr().out.splitlines()
    assert lines[:4] == ["2.5", "float", "16", str(len(HALCMD_VERBS))]
    assert any("lonely" in line for line in lines[4:])  # show printed, not returned
    assert session.hal.meta["pins"]["tc.in"]["sig"] == "s"


def test_a_failing_verb_is_a_tcl_error_that_catch_sees(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    script = 'if {[catch {setp no.such.pin 1} msg]} { puts "caught: $msg" }\n'
    assert run(session, tmp_path, script)
    assert capfd.readouterr().out.strip() == "caught: parameter or pin 'no.such.pin' not found"


def test_errors_name_the_file_and_line_even_inside_procedures(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    script = "proc connect {} {\n    net s no.such.pin\n}\n\nconnect\n"
    assert not run(session, tmp_path, script)
    err = capfd.readouterr().err.strip()
    assert err == f"{tmp_path / 'test.tcl'}:2: Pin 'no.such.pin' does not exist"
    # an error Tcl itself raises: the line of the command in the file
    assert not run(session, tmp_path, "set a 1\nno_such_command 1 2\n")
    err = capfd.readouterr().err.strip()
    assert err == f'{tmp_path / "test.tcl"}:2: invalid command name "no_such_command"'


def test_exit_ends_the_file_and_its_status_counts(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    assert run(session, tmp_path, "puts before\nexit 0\nputs after\n")
    assert capfd.readouterr().out.split() == ["before"]
    assert not run(session, tmp_path, "exit 3\n")
    assert capfd.readouterr().err.strip().endswith(": exit 3")


def test_packages_and_the_library_procedures_load(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str], monkeypatch
) -> None:
    from hal.hallib import LIBRARY_DIR

    monkeypatch.setenv("HALLIB_DIR", str(LIBRARY_DIR))
    with_pin(session)
    script = (
        "package require Hal\npackage require Linuxcnc\n"
        "source [file join $::env(HALLIB_DIR) hal_procs_lib.tcl]\n"
        "net s tc.out tc.in\n"
        "puts [pin_exists tc.in][pin_exists tc.nope]\n"
        "puts [is_connected tc.in name]:$name\n"
        "get_netlist ins out ios s\n"
        'puts "$ins|$out|$ios"\n'
        "connection_info info tc.out\n"
        'puts "$info(direction) $info(type) $info(signame) $info(separator)"\n'
    )
    assert run(session, tmp_path, script)
    assert capfd.readouterr().out.splitlines() == [
        "10",
        "is_input:s",
        "tc.in|tc.out|",
        "OUT float s ==>",
    ]
