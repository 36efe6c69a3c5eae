"""INI files read as LinuxCNC 2.9 reads them (cnc/ini.py, CFG-001..003), and ``cnc inivar``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cnc.ini import IniError, IniFile, inivar

REPO = Path(__file__).resolve().parents[2]
LINUXCNC_INIVAR = shutil.which("inivar", path="/usr/bin")


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_values_keep_their_file_and_line(tmp_path: Path) -> None:
    ini = IniFile.load(write(tmp_path / "m.ini", "# c\n[EMC]\nMACHINE =  my mill  \n"))
    entry = ini.entry("EMC", "MACHINE")
    assert entry is not None
    assert (entry.value, entry.where) == ("my mill", f"{tmp_path / 'm.ini'}:3")


def test_comments_only_at_the_start_of_a_line(tmp_path: Path) -> None:
    ini = IniFile.from_text("[A]\n; x\n  # y\nK = v # not a comment\nL = a;b\n")
    assert ini.items("A") == [("K", "v # not a comment"), ("L", "a;b")]


def test_an_empty_value_is_not_set_and_ends_a_list_as_in_linuxcnc() -> None:
    ini = IniFile.from_text("[HAL]\nHALFILE = a.hal\nHALFILE =\nHALFILE = c.hal\nX =\n")
    assert ini.find("HAL", "X") is None and ini.find("HAL", "X", "d") == "d"
    assert ini.entry("HAL", "X") is not None  # the line is there
    assert ini.findall("HAL", "HALFILE") == ["a.hal"]
    assert ini.find_nth("HAL", "HALFILE", 3) == "c.hal"
    assert ini.find_nth("HAL", "HALFILE", 2) is None


def test_backslash_continues_a_value_up_to_twenty_times() -> None:
    ini = IniFile.from_text("[A]\nAPP = one \\\ntwo \\\n three\nB = 1\n")
    assert ini.find("A", "APP") == "one two  three" and ini.find("A", "B") == "1"
    assert ini.entry("A", "B").line == 5
    lines = "[A]\nK = 0" + "\\\n1" * 21 + "\nL = 2\n"
    assert IniFile.from_text(lines).find("A", "K") == "0" + "1" * 20


def test_dos_line_endings_and_a_byte_order_mark_read_as_unix(tmp_path: Path) -> None:
    path = tmp_path / "m.ini"
    path.write_bytes(b"\xef\xbb\xbf[EMC]\r\nMACHINE = m\r\n")
    assert IniFile.load(path).find("EMC", "MACHINE") == "m"


def test_only_the_first_of_repeated_sections_counts_with_a_warning() -> None:
    ini = IniFile.from_text("[KINS]\nJOINTS = 3\n[X]\n[KINS]\nJOINTS = 4\nOTHER = 1\n", "m.ini")
    assert ini.findall("KINS", "JOINTS") == ["3"] and ini.find("KINS", "OTHER") is None
    assert ini.warnings == [
        "m.ini:4: [KINS] repeated (first at m.ini:1): LinuxCNC reads only the first, so the "
        "keys up to the next header are ignored"
    ]


def test_lines_linuxcnc_ignores_are_ignored_with_a_warning() -> None:
    ini = IniFile.from_text("K = before\n[A]\nduh\nGOOD = 1\n[B\nLOST = 1\n", "m.ini")
    assert ini.items("A") == [("GOOD", "1")] and ini.sections() == ["A"]
    assert [w.split(": ")[0] for w in ini.warnings] == ["m.ini:1", "m.ini:3", "m.ini:5"]
    assert "K before any [SECTION]" in ini.warnings[0]
    assert ini.find_nth(None, "K") == "before"  # inivar without -sec still finds it


def test_include_is_relative_to_the_ini_file_and_continues_its_section(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write(tmp_path / "inc" / "joint.inc", "HOME = 5\n[JOINT_1]\nHOME = 6\n")
    ini_path = write(
        tmp_path / "m.ini", "[JOINT_0]\nTYPE = LINEAR\n#INCLUDE inc/joint.inc\nMIN_LIMIT = -1\n"
    )
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    ini = IniFile.load(ini_path)
    assert ini.find("JOINT_0", "HOME") == "5"
    assert ini.find("JOINT_1", "HOME") == "6"
    assert ini.find("JOINT_1", "MIN_LIMIT") == "-1"  # the included file's section goes on
    assert ini.entry("JOINT_0", "HOME").where == f"{tmp_path / 'inc' / 'joint.inc'}:1"
    assert ini.warnings == []


def test_include_expands_home_and_variables_one_level_and_warns_what_it_skips(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("PART", "emc")
    write(tmp_path / "home" / "emc.inc", "[EMC]\nMACHINE = m\n#INCLUDE deeper.inc\n")
    write(tmp_path / "home" / "deeper.inc", "[DEEP]\nK = 1\n")
    ini_path = write(
        tmp_path / "m.ini", "#INCLUDE ~/${PART}.inc\n#INCLUDE\n#INCLUDE nosuchfile\n[A]\n"
    )
    ini = IniFile.load(ini_path)
    assert ini.find("EMC", "MACHINE") == "m" and not ini.has_section("DEEP")
    inc = tmp_path / "home" / "emc.inc"
    assert ini.warnings == [
        f"{inc}:3: #INCLUDE in an included file is not expanded (LinuxCNC expands one level only)",
        f"{ini_path}:2: #INCLUDE without a file name: ignored",
        f"{ini_path}:3: #INCLUDE nosuchfile: cannot read {tmp_path / 'nosuchfile'}: ignored",
    ]


def test_an_unreadable_file_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(IniError, match=r"missing\.ini: cannot read INI file"):
        IniFile.load(tmp_path / "missing.ini")


def test_numbers_refuse_nan_inf_and_trailing_text() -> None:
    ini = IniFile.from_text("[A]\nN = nan\nI = -inf\nT = 1,5\nX = 0x1F\nB = Yes\n", "m.ini")
    for key in ("N", "I", "T"):
        with pytest.raises(IniError, match=f"m.ini:[234]: \\[A\\]{key} = .* is not a finite"):
            ini.get_float("A", key)
    assert ini.get_int("A", "X") == 31 and ini.get_bool("A", "B") is True


# --------------------------------------------------------------------------- inivar
def run_inivar(*args: str) -> tuple[int, str, str]:
    proc = subprocess.run(
        [sys.executable, "-m", "cnc", "inivar", *args], capture_output=True, text=True, cwd=REPO
    )
    return proc.returncode, proc.stdout, proc.stderr


MILL = str(REPO / "configs" / "sim" / "mill.ini")
INIVAR_CASES = [
    ("-ini", MILL, "-var", "JOINTS", "-sec", "KINS"),
    ("-ini", MILL, "-var", "HALFILE", "-sec", "HAL", "-num", "3"),
    ("-ini", MILL, "-var", "MAX_LIMIT"),  # any section: the first one
    ("-ini", MILL, "-var", "NOPE", "-sec", "KINS"),
    ("-ini", MILL, "-var", "NOPE"),
    ("-ini", "/nonexistent.ini", "-var", "X"),
    ("-ini", MILL),
    ("-ini", MILL, "-var"),
    ("-ini", MILL, "-var", "X", "-num", "two"),
    ("-bogus",),
]


@pytest.mark.parametrize("args", INIVAR_CASES)
def test_inivar_answers_as_linuxcncs(args: tuple[str, ...], capsys) -> None:
    """Output, messages and exit status, as recorded from LinuxCNC 2.9's inivar (the
    program name aside); compared with it live when it is installed."""
    status = inivar(list(args))
    out, err = capsys.readouterr()
    expected = {
        0: ("3\n", ""),
        1: ("sim_io.hal\n", ""),
        2: ("254.0\n", ""),
        3: ("", "Can not find -sec KINS -var NOPE -num 1 \n"),
        4: ("", "Can not find -sec (null) -var NOPE -num 1 \n"),
        5: ("", "inivar: can't open /nonexistent.ini\n"),
        6: ("", "inivar: no variable supplied\n"),
        7: ("", "inivar: variable name not specified after -var\n"),
        8: ("", "inivar: invalid number after -num\n"),
        9: (
            "",
            "inivar: -var <variable> {-tildeexpand} {-sec <section>} {-ini <INI file>} "
            "[-num <nth item>]\n",
        ),
    }[INIVAR_CASES.index(args)]
    assert (out, err) == expected
    assert status == (255 if "/nonexistent.ini" in args else 0 if out else 1)
    if LINUXCNC_INIVAR:
        theirs = subprocess.run([LINUXCNC_INIVAR, *args], capture_output=True, text=True)
        assert (theirs.returncode, theirs.stdout) == (status, out)
        assert theirs.stderr.replace(LINUXCNC_INIVAR, "inivar") == err


def test_inivar_is_a_cnc_subcommand_and_expands_tilde_on_request(tmp_path: Path) -> None:
    path = write(tmp_path / "m.ini", "[DISPLAY]\nOPEN_FILE = ~/part.ngc\n")
    assert run_inivar("-ini", str(path), "-var", "OPEN_FILE", "-sec", "DISPLAY")[1] == (
        "~/part.ngc\n"
    )
    home = os.path.expanduser("~")
    found = run_inivar("-tildeexpand", "-ini", str(path), "-var", "OPEN_FILE")
    assert found == (0, f"{home}/part.ngc\n", "")
