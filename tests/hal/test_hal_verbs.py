"""halcmd verbs beyond the basics, run as HAL files through ``cnc halrun``."""

from __future__ import annotations

import sys
from pathlib import Path

from tests.hal.halrun_util import halrun_text, run_cnc, without_halcmd

ECHO = Path(__file__).resolve().parent / "echo_comp.py"


def test_link_unlink_delsig_types_and_functions(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=t period1=1000000\nloadrt and2 count=3\n"
        "newsig a bit\nlinkps and2.0.out a\nlinksp a and2.1.in0\nlinkpp and2.2.out and2.2.in0\n"
        "ptype and2.0.out\nstype a\nlist sig\n"
        "unlinkp and2.1.in0\ndelsig a\nlist sig\n"
        "addf and2.0 t\naddf and2.1 t\naddf and2.2 t 1\nshow thread t\n"
        "delf and2.0\ndelf and2.2 t\nshow thread t\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[:3] == ["bit", "bit", "a and2.2.out "]
    assert lines[3] == "and2.2.out "
    functs = [
        line.split()[1] for line in lines if line.strip()[:1].isdigit() and len(line.split()) == 2
    ]
    assert functs == ["and2.2", "and2.0", "and2.1", "and2.1"]


def test_start_stop_and_locks(tmp_path: Path) -> None:
    sleep = f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.05)'\n"
    text = (
        "loadrt threads name1=t period1=1000000\nloadrt not\naddf not.0 t\n"
        "start\n"
        + sleep
        + "stop\nsetp not.0.in 1\n"
        + sleep
        + "getp not.0.out\n"  # still TRUE: stopped threads run no functions
        "lock all\nsetp not.0.in 1\nnet x not.0.in\nunlock all\nsetp not.0.in 1\n"
        "lock tune\nsetp not.0.in 0\nloadrt and2\nunlock tune\nloadrt and2\nlist comp\n"
    )
    result = halrun_text(tmp_path, text, "-k")
    assert without_halcmd(result.stdout.split()) == ["TRUE", "and2", "not", "__t", "threads"]
    errors = result.stderr.splitlines()
    assert [e.split(": ", 1)[1] for e in errors] == [
        "HAL is locked, setp is not permitted",
        "HAL is locked, net is not permitted",
        "HAL is locked, loading is not permitted",
    ]


def test_save_to_file_then_source_rebuilds_the_nets(tmp_path: Path) -> None:
    saved = tmp_path / "saved.hal"
    first = halrun_text(
        tmp_path,
        f"loadrt and2\nnet s1 and2.0.out and2.0.in0\nnewsig lonely float\nsave all {saved}\n",
    )
    assert first.returncode == 0, first.stderr
    second = halrun_text(tmp_path, f"source {saved}\nshow sig\n")
    assert second.returncode == 0, second.stderr
    assert "float             0  lonely" in second.stdout
    assert "                         ==> and2.0.in0" in second.stdout


def test_echo_help_and_unknown_show_type(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "echo\nnewsig e bit\nunecho\nhelp net\nshow bogus x\n")
    lines = result.stdout.splitlines()
    assert lines[:2] == ["Echo on", "Echo off"]
    assert lines[2].startswith("net signame")
    # the echoed commands go to stderr, as LinuxCNC's halcmd prints them
    assert result.stderr.splitlines()[:2] == ["(2)<echo>: newsig e bit", "(3)<echo>: unecho"]
    assert "Unknown 'show' type 'bogus'" in result.stderr


def test_waitusr_and_unload_of_a_userspace_component(tmp_path: Path) -> None:
    text = (
        f"loadusr -Wn echo {sys.executable} {ECHO}\nshow comp echo\nunload echo\n"
        "list comp\n"
        f"loadusr -Wn echo2 {sys.executable} {ECHO} echo2 --crash\nwaitusr echo2\n"
        "list comp\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert "echo" in lines[2].split()
    # unloaded; crashed and cleaned up by waitusr: only halcmd itself is left
    assert [without_halcmd(line.split()) for line in lines[-2:]] == [[], []]


def test_halcmd_command_line_errors() -> None:
    assert run_cnc("halcmd", "-x").returncode == 2
    result = run_cnc("halcmd", "-i", "/nonexistent.ini", "show")
    assert result.returncode == 1 and "/nonexistent.ini" in result.stderr
