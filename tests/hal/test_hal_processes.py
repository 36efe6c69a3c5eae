"""Several real processes sharing one HAL: host, halcmd, userspace components (HAL-001)."""

from __future__ import annotations

import signal
import sys
import time
from pathlib import Path

from hal.core import Hal
from hal.halcmd import HalCmd
from tests.hal.halrun_util import REPO, halrun_text, run_cnc, without_halcmd

ECHO = Path(__file__).resolve().parent / "echo_comp.py"
SLEEP = f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.2)'\n"


def test_userspace_component_and_realtime_host_share_pins(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt scale\n"
        f"loadusr -Wn echo {sys.executable} {ECHO}\n"
        "newsig x float\n"
        "net x echo.in\n"
        "sets x 1.5\n"
        "net y echo.out scale.0.in\n"
        "setp scale.0.gain 3\n"
        "addf scale.0 servo-thread\n"
        "start\n" + SLEEP + "getp echo.out\ngetp scale.0.out\nshow comp echo\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[:2] == ["3", "9"]
    assert lines[-2].split()[1:3] == ["User", "echo"] and lines[-2].endswith("ready")


def test_halcmd_processes_see_one_hal(procs) -> None:  # type: ignore[no-untyped-def]
    host = procs.python("-m", "hal.rtapi_app", "--no-rt")
    assert host.stdout.readline().strip() == "rtapi_app: ready"
    assert run_cnc("halcmd", "loadrt", "and2").returncode == 0
    assert run_cnc("halcmd", "setp", "and2.0.in0", "TRUE").returncode == 0
    shown = run_cnc("halcmd", "-s", "show", "pin", "and2.0.in0")
    assert shown.stdout.split()[3] == "TRUE"
    echo = procs.python(str(ECHO), "echo2")
    hal = Hal()
    try:
        deadline = time.monotonic() + 10
        while not hal.meta["comps"].get("echo2", {}).get("is_ready"):
            assert time.monotonic() < deadline and echo.poll() is None
            time.sleep(0.01)
        cmd = HalCmd(hal)
        assert cmd.run_words(["newsig", "v", "float"])
        assert cmd.run_words(["net", "v", "echo2.in"])
        assert cmd.run_words(["sets", "v", "4"])
        while hal.pin_value(hal.find_pin("echo2.out")[1]) != 8.0:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        echo.send_signal(signal.SIGTERM)
        echo.wait(timeout=10)
        assert "echo2" not in hal.meta["comps"]
        assert "echo2.in" not in hal.meta["pins"]
    finally:
        hal.close()
    assert run_cnc("halcmd", "unload", "all").returncode == 0
    host.send_signal(signal.SIGTERM)
    assert host.wait(timeout=10) == 0


def test_halrun_cleans_up_after_a_killed_userspace_component(tmp_path: Path) -> None:
    text = f"loadusr -Wn echo {sys.executable} {ECHO} echo --crash\n" + SLEEP + "show comp\n"
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert "echo" in result.stdout
    # the autouse fixture fails the test if any HAL segment or semaphore is left


def test_halcmd_interactive_reads_commands_from_stdin(tmp_path: Path) -> None:
    result = run_cnc(
        "halrun", cwd=REPO, text_in="newsig s u32\nsets s 50\ngets s\nshow sig\nquit\n"
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "50"
    assert "u32      0x00000032  s" in lines


def test_a_new_host_replaces_a_crashed_one(procs) -> None:  # type: ignore[no-untyped-def]
    host = procs.python("-m", "hal.rtapi_app", "--no-rt")
    assert host.stdout.readline().strip() == "rtapi_app: ready"
    assert run_cnc("halcmd", "loadrt", "and2").returncode == 0
    host.kill()
    host.wait(timeout=10)
    again = run_cnc("halcmd", "loadrt", "and2")  # starts a new host, forgets the dead one's
    assert again.returncode == 0, again.stderr
    listed = run_cnc("halcmd", "list", "comp")
    assert without_halcmd(listed.stdout.split()) == ["and2"]
    assert run_cnc("halcmd", "unload", "all").returncode == 0
