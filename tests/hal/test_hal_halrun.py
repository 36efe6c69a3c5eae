"""HAL files through ``cnc halrun``: show layouts, links, INI values and errors (HAL-012/013)."""

from __future__ import annotations

import sys
from pathlib import Path

from tests.hal.halrun_util import FILES, halrun_text

AND2_FILE = """\
loadrt threads name1=servo-thread period1=1000000
loadrt and2 count=2
addf and2.0 servo-thread
net foo and2.0.out and2.1.in0
setp and2.0.in0 1
newsig bar float
sets bar 2.5
"""


def _section(text: str, title: str) -> list[str]:
    lines = text.splitlines()
    start = lines.index(title)
    end = lines.index("", start)
    return lines[start:end]


def _drop_owner(lines: list[str]) -> list[str]:
    """Owner ids are allocation details; compare everything else."""
    return [line[6:] if line[:6].strip().isdigit() else line for line in lines]


def test_show_pin_param_sig_thread_layout_matches_linuxcnc(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, AND2_FILE + "show pin and2\nshow sig\nshow thread\n")
    assert result.returncode == 0, result.stderr
    lcnc = (FILES / "lcnc_t1_output.txt").read_text()
    ours = _drop_owner(_section(result.stdout, "Component Pins:"))
    theirs = [
        line
        for line in _drop_owner(_section(lcnc, "Component Pins:"))
        if "p0." not in line and "servo-thread" not in line
    ]
    assert ours == theirs
    assert _section(result.stdout, "Signals:") == _section(lcnc, "Signals:")
    thread = _section(result.stdout, "Realtime Threads:")
    assert thread[:3] == _section(lcnc, "Realtime Threads:")[:3]
    assert thread[3] == "                  1 and2.0"


def test_in_pin_follows_out_pin_once_thread_runs(tmp_path: Path) -> None:
    text = AND2_FILE + (
        "setp and2.0.in1 1\nstart\n"
        f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.1)'\n"
        "getp and2.1.in0\ngets foo\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["TRUE", "TRUE"]


def test_stopped_threads_do_not_run_functions(tmp_path: Path) -> None:
    text = AND2_FILE + (
        "setp and2.0.in1 1\n"
        f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.05)'\n"
        "getp and2.1.in0\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.stdout.split() == ["FALSE"]


def test_ini_substitution_comments_and_continuation(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[HAL]\nPERIOD = 2000000\n[AXIS_X]\nGAIN = 2.5\n")
    text = (
        "# a comment line\n"
        "loadrt threads name1=servo-thread \\\n  period1=[HAL]PERIOD   # trailing comment\n"
        "newsig g float\nsets g [AXIS_X]GAIN\ngets g\nshow thread\n"
    )
    result = halrun_text(tmp_path, text, "-i", str(ini))
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == "2.5"
    assert "    2000000  YES          servo-thread" in result.stdout


def test_errors_name_file_line_and_cause(tmp_path: Path) -> None:
    cases = {
        "loadrt nonexist\n": "nonexist: realtime component not found",
        "loadrt and2\nloadrt or2\nnet a and2.0.out\nnet a or2.0.out\n": (
            "Signal 'a' can not add OUT pin 'or2.0.out', it already has OUT pin 'and2.0.out'"
        ),
        "loadrt and2\nnewsig f float\nnet f and2.0.in0\n": "type mismatch 'and2.0.in0' <- 'f'",
        "newsig " + "x" * 48 + " bit\n": "is too long",
        "setp and2.0.in0 1\n": "parameter or pin 'and2.0.in0' not found",
        "frobnicate\n": "Unknown command 'frobnicate'",
        "loadrt and2\nsetp and2.0.out 1\n": "pin 'and2.0.out' is not writable",
        "loadrt and2\nsetp and2.0.in0 maybe\n": "value 'maybe' invalid for bit",
        "loadrt pid num_chan=17\n": "pid: ERROR: invalid num_chan: 17 (1 to 16)",
        "loadrt threads name1=t period1=1000000\nloadrt and2\naddf and2.0 t x\n": (
            "addf: position 'x' is not a whole number"
        ),
        "loadrt threads name1=t period1=nope\n": "threads: period1 and fp1 must be whole numbers",
    }
    for text, cause in cases.items():
        result = halrun_text(tmp_path, text)
        line = text.count("\n")
        assert result.returncode != 0, text
        assert f"{tmp_path / 'test.hal'}:{line}: " in result.stderr, result.stderr
        assert cause in result.stderr, result.stderr


def test_missing_ini_key_is_an_error(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[HAL]\n")
    result = halrun_text(tmp_path, "newsig g float\nsets g [HAL]NOPE\n", "-i", str(ini))
    assert result.returncode != 0
    assert f"{tmp_path / 'test.hal'}:2: Ini variable '[HAL]NOPE' not found" in result.stderr


def test_keep_going_runs_lines_after_an_error(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "bogus\nnewsig s s32\nsets s 7\ngets s\n", "-k")
    assert result.returncode != 0
    assert result.stdout.strip() == "7"


def test_save_prints_commands_that_rebuild_the_config(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, AND2_FILE + "save\n")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert "loadrt and2 count=2 " in lines  # LinuxCNC ends each argument with a space
    assert "net foo and2.0.out => and2.1.in0" in lines
    assert "newsig bar float" in lines
    assert "addf and2.0 servo-thread" in lines


def test_alias_and_lists(tmp_path: Path) -> None:
    text = (
        "loadrt and2\nalias pin and2.0.in1 myin\nsetp myin 1\nlist pin\ngetp and2.0.in1\n"
        "show alias\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split() == ["and2.0.in0", "and2.0.out", "and2.0.time", "myin"]
    assert lines[1] == "TRUE"
    assert " myin                                             and2.0.in1" in lines


def test_script_mode_has_no_headers(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "loadrt and2\nnet foo and2.0.out and2.0.in0\nshow pin\n", "-s")
    assert result.stdout.splitlines()[0] == "and2 bit   IN FALSE and2.0.in0 <== foo"


def test_non_compliant_signal_names_are_warned_about_once(tmp_path: Path) -> None:
    text = "loadrt and2\nnet Spindle_On and2.0.out\nnet Spindle_On and2.0.in0\n"
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    warnings = [line for line in result.stderr.splitlines() if "Warning" in line]
    assert warnings == [
        f"{tmp_path / 'test.hal'}:2: Warning: signal name 'Spindle_On' does not follow the HAL "
        "naming rules (lowercase letters, digits, '.' and '-')"
    ]


def test_first_pin_gives_a_signal_its_value_and_unlinked_pins_keep_it(tmp_path: Path) -> None:
    # expected values are LinuxCNC 2.9's output for the same file
    text = (
        "loadrt and2 count=2\nsetp and2.0.in0 1\nnet x and2.0.in0\ngets x\n"
        "setp and2.1.in0 1\nnet x and2.1.in0\ngetp and2.1.in0\n"
        "setp and2.1.in1 1\nnewsig y bit\nsets y 0\nnet y and2.1.in1\ngetp and2.1.in1\n"
        "unlinkp and2.1.in1\ngetp and2.1.in1\nsets x 0\nunlinkp and2.0.in0\ngetp and2.0.in0\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["TRUE", "TRUE", "TRUE", "TRUE", "FALSE"]


def test_substitution_happens_before_the_line_is_split(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    ini = tmp_path / "m.ini"
    ini.write_text("[KINS]\nKINEMATICS = and2 count=2\n[X]\nNAME = in1\n")
    monkeypatch.setenv("HAL_TEST_VALUE", "TRUE")
    text = (
        "loadrt [KINS]KINEMATICS\nsetp and2.1.[X](NAME) $(HAL_TEST_VALUE)\n"
        'setp and2.0.in0 "$HAL_TEST_VALUE" # quoted and commented\n'
        "getp and2.1.in1\ngetp and2.0.in0\n"
    )
    result = halrun_text(tmp_path, text, "-i", str(ini))
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["TRUE", "TRUE"]
    missing = halrun_text(tmp_path, "newsig s bit\nsets s $(NO_SUCH_VARIABLE_HERE)\n")
    assert "test.hal:2: Environment variable 'NO_SUCH_VARIABLE_HERE' not found" in (missing.stderr)


def test_threads_fastest_first_fp_flag_and_script_layout(tmp_path: Path) -> None:
    # expected lines are LinuxCNC 2.9's `halrun -s` output for the same file
    text = (
        "loadrt threads name1=base period1=50000 fp1=0 name2=servo-thread period2=1000000\n"
        "loadrt and2 count=1\naddf and2.0 servo-thread\nshow thread\n"
    )
    result = halrun_text(tmp_path, text, "-s")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[:2] == [
        "1000000 YES servo-thread        0 0 and2.0",
        "50000 NO base        0 0",
    ]
    slower_first = halrun_text(
        tmp_path, "loadrt threads name1=slow period1=1000000 name2=fast period2=50000\n"
    )
    assert "new thread period 50000 is less than clock period 1000000" in slower_first.stderr
    rolled_back = halrun_text(
        tmp_path,
        "loadrt threads name1=slow period1=1000000 name2=fast period2=50000\nlist thread\n",
        "-k",
    )
    assert rolled_back.stdout.strip() == ""  # a failed loadrt leaves no thread behind
