"""``cnc run``: LinuxCNC's launcher options and the HAL library in whole machines (issue 17,
"Launcher parity")."""

from __future__ import annotations

import re
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

import cnc
from cnc.launcher import last_config, parse_arguments
from cnc.runtime import read_runtime_info
from nml.ipcnames import instance_objects
from tests.hal.halrun_util import REPO
from tests.launch.conftest import needs_tcl

START_TIMEOUT_S = 60


def test_linuxcnc_options(tmp_path: Path) -> None:
    args, options = parse_arguments(
        ["-r", "-v", "-k", "-H", str(tmp_path), "-t", "tpmod", "mill.ini", "--fullscreen"]
    )
    assert args.ini == "mill.ini" and args.is_runtests
    assert options.is_verbose and options.is_keep_going and not options.is_debug
    assert options.hal_dirs == [str(tmp_path)] and options.tpmod == "tpmod"
    assert options.display_args == ["--fullscreen"]  # after the INI: the display's
    args, options = parse_arguments(["mill.ini", "--headless"])
    assert args.headless and options.display_args == []
    with pytest.raises(SystemExit):
        parse_arguments(["-H", str(tmp_path / "missing"), "mill.ini"])


def test_l_takes_the_last_ini_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.setenv("HOME", str(tmp_path))
    assert last_config() is None
    (tmp_path / ".linuxcncrc").write_text("[PICKCONFIG]\nLAST_CONFIG = /m/lathe.ini\n")
    assert last_config() == "/m/lathe.ini"  # LinuxCNC's, while we have none of our own
    (tmp_path / "config" / "cnc").mkdir(parents=True)
    (tmp_path / "config" / "cnc" / "last-config").write_text("/m/mill.ini\n")
    args, _ = parse_arguments(["-l"])
    assert args.ini == "/m/mill.ini"


# ---------------------------------------------------------------- whole machines
def machine_folder(tmp_path: Path, hal: str, display: str = "") -> Path:
    """configs/ copied, with sim/test.ini: mill.ini with other [HAL] files and DISPLAY."""
    configs = tmp_path / "configs"
    shutil.copytree(REPO / "configs", configs)
    folder = configs / "sim"
    text = (folder / "mill.ini").read_text()
    text = re.sub(r"^HALFILE = .*\n", "", text, flags=re.MULTILINE)
    text = text.replace("HALUI = halui\n", f"HALUI = halui\n{hal}")
    text = re.sub(r"^DISPLAY = .*$", f"DISPLAY = {display}", text, flags=re.MULTILINE)
    (folder / "test.ini").write_text(text)
    return folder


def wait_until_ready(launcher: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while (info := read_runtime_info()) is None or info.pid != launcher.pid:
        assert launcher.poll() is None, launcher.stderr.read()
        assert time.monotonic() < deadline, "the machine did not come up"
        time.sleep(0.05)


def turn_on_and_home() -> cnc.stat:
    stat, command = cnc.stat(), cnc.command()
    command.state(cnc.STATE_ESTOP_RESET)
    command.state(cnc.STATE_ON)
    command.mode(cnc.MODE_MANUAL)
    command.home(-1)
    command.wait_complete()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        stat.poll()
        if stat.joints and all(stat.homed[: stat.joints]):
            break
        time.sleep(0.05)
    return stat


@needs_tcl
@pytest.mark.slow
@pytest.mark.parametrize("twopass", ["", "TWOPASS = on\n"])
def test_a_linuxcnc_style_config_built_by_basic_sim_tcl(
    procs, tmp_path: Path, cnc_instance: str, twopass: str
) -> None:
    # LinuxCNC's sample configs: the library builds the machine, hal_manualtoolchange
    # takes tool changes (our stand-in answers at once)
    folder = machine_folder(tmp_path, twopass + "HALFILE = LIB:basic_sim.tcl -no_sim_spindle\n")
    launcher = procs.python("-m", "cnc", "run", "--headless", "test.ini", cwd=folder)
    try:
        wait_until_ready(launcher)
        stat = turn_on_and_home()
        assert stat.task_state == cnc.STATE_ON and all(stat.homed[:3])
        command = cnc.command()
        command.mode(cnc.MODE_MDI)
        command.mdi("T2 M6 G0 X5 Y-3")
        assert command.wait_complete(30) == cnc.RCS_DONE
        stat.poll()
        assert stat.tool_in_spindle == 2
        work = [
            stat.position[i] - stat.g5x_offset[i] - stat.g92_offset[i] - stat.tool_offset[i]
            for i in range(2)
        ]
        assert work == pytest.approx([5.0, -3.0], abs=1e-6)
    finally:
        launcher.send_signal(signal.SIGTERM)
        code = launcher.wait(timeout=60)
    stderr = launcher.stderr.read()
    assert code == 0, stderr
    assert "hal_manualtoolchange: insert tool 2" in stderr
    assert (folder / "test_cmds.hal").read_text().count("net J0:pos-fb") == 1  # save_hal_cmds
    assert instance_objects(cnc_instance) == []


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def connect(port: int, launcher: subprocess.Popen[str]) -> socket.socket:
    """The display's server, once it listens (as LinuxCNC's test waits with nc -z)."""
    deadline = time.monotonic() + START_TIMEOUT_S
    while True:
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=30)
        except ConnectionRefusedError:
            assert launcher.poll() is None, launcher.stderr.read()
            assert time.monotonic() < deadline, "linuxcncrsh did not listen"
            time.sleep(0.05)


@pytest.mark.slow
def test_linuxcncrsh_as_the_display_drives_the_machine_and_shuts_it_down(
    procs, tmp_path: Path, cnc_instance: str
) -> None:
    port = free_port()
    folder = machine_folder(
        tmp_path,
        "HALFILE = core_sim.hal\nHALFILE = sim_io.hal\nHALFILE = tool_loopback.hal\n",
        display=f"linuxcncrsh --port {port}",
    )
    launcher = procs.python("-m", "cnc", "run", "test.ini", cwd=folder)
    wait_until_ready(launcher)
    with connect(port, launcher) as client:
        reader = client.makefile("rb")

        def say(line: str) -> None:
            client.sendall(line.encode() + b"\r\n")

        def reply() -> bytes:
            return reader.readline()

        say("get estop")  # before hello: gets work, sets do not
        assert reply() == b"ESTOP ON\r\n"
        say("set estop off")
        assert reply() == b"SET NAK\r\n"
        say("hello EMC pendant 1.0")
        assert reply() == b"HELLO ACK EMCNETSVR 1.1\r\n"
        say("set echo off")
        assert reply() == b"set echo off\r\n"  # echoed before it took effect
        say("set estop off")  # not enabled yet
        assert reply() == b"SET ESTOP NAK\n"
        assert reader.read(1) == b"\r"
        say("set enable EMCTOO")
        say("set verbose on")
        assert reply() == b"SET VERBOSE ACK\n"
        assert reader.read(1) == b"\r"
        for line in ("set set_wait done", "set estop off", "set machine on"):
            say(line)
            assert reply() == f"SET {line.split()[1].upper()} ACK\n".encode()
            assert reader.read(1) == b"\r"
        say("get machine")
        assert reply() == b"MACHINE ON\r\n"
        stat = cnc.stat()
        stat.poll()
        assert stat.task_state == cnc.STATE_ON
        say("set estop on")  # takes effect in the machine
        assert reply() == b"SET ESTOP ACK\n"
        assert reader.read(1) == b"\r"
        stat.poll()
        assert stat.task_state == cnc.STATE_ESTOP
        say("set mode mdi")  # the machine is not on: refused
        assert reply() == b"SET MODE NAK\n"
        assert reader.read(1) == b"\r"
        say("get nonsense")
        assert reply() == b"GET NONSENSE NAK\r\n"
        assert reply() == b"\r\n"
        say("shutdown")
    code = launcher.wait(timeout=60)
    assert code == 0, launcher.stderr.read()  # the display's status is the run's
    assert instance_objects(cnc_instance) == []


@pytest.mark.slow
def test_cnc_run_exits_with_the_displays_status(procs, tmp_path: Path, cnc_instance: str) -> None:
    script = tmp_path / "mydisplay"
    script.write_text('#!/bin/sh\necho "$@" > "$(dirname "$0")/display-args"\nexit 3\n')
    script.chmod(0o755)
    folder = machine_folder(tmp_path, "HALFILE = core_sim.hal\nHALFILE = sim_io.hal\n",
                            display=f"{script} --big")  # fmt: skip
    launcher = procs.python("-m", "cnc", "run", "test.ini", "--extra", cwd=folder)
    assert launcher.wait(timeout=120) == 3, launcher.stderr.read()
    # LinuxCNC's order: -ini INI, then the DISPLAY entry's arguments, then the command line's
    args = (tmp_path / "display-args").read_text().split()
    assert args == ["-ini", str(folder / "test.ini"), "--big", "--extra"]
    assert instance_objects(cnc_instance) == []
