"""cnc top: the snapshot shows what the controller publishes; the curses view runs at 80x24."""

from __future__ import annotations

import fcntl
import math
import os
import pty
import select
import signal
import struct
import subprocess
import termios
import time
from pathlib import Path

import pytest

import cnc
from cnc.ui.controller import Controller
from cnc.ui.top import snapshot, status_screen
from nml import emc
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from tests.api.fake_task import machine_status
from tests.ui.conftest import UI_MAIN, WAIT_S, read_until


def test_once_shows_the_state_and_positions_the_task_publishes(fake_task, run_ui) -> None:
    fake_task()
    result = run_ui("top", "--once")
    assert result.returncode == 0, result
    lines = result.lines
    assert lines[0].startswith("cnc top  running machine")
    assert "Task ESTOP  mode MANUAL  interp IDLE  command DONE" in lines
    rows = {line.split()[0]: line.split() for line in lines if line[:1] in "XYZ"}
    # axis, work, machine, to go | joint, position, homed, limits
    assert rows["X"] == ["X", "2.500", "12.500", "0.000", "0", "12.500", "yes", "ok"]
    assert rows["Y"] == ["Y", "-3.250", "-3.250", "0.000", "1", "-3.250", "yes", "ok"]
    assert rows["Z"] == ["Z", "40.000", "40.000", "0.000", "2", "40.000", "no", "-S"]
    assert "Tool 3 in spindle  prepared pocket 0" in lines
    assert "Spindle 0 forward  speed 1000 rpm  override 100%  brake off" in lines
    assert "G-codes G1 G17 G40 G21 G90 G94 G54 G49 G99 G64 G97 G91.1 G8 G92.2" in lines
    assert lines[-1] == "Messages: none"


def test_once_follows_what_the_shell_did(fake_task, run_ui) -> None:
    fake_task()
    assert run_ui("sh", "-c", "estop off; machine on; mode mdi").returncode == 0
    result = run_ui("top", "--once")
    assert "Task ON  mode MDI  interp IDLE  command DONE" in result.lines
    assert "Exec DONE  e-stop no  enabled yes" in result.lines


def test_once_without_a_controller_says_why_and_fails(run_ui) -> None:
    result = run_ui("top", "--once")
    assert result.returncode == 1
    assert result.stdout == ""
    assert "the controller is not running" in result.stderr


def test_a_missing_machine_file_is_one_line(run_ui, tmp_path: Path) -> None:
    result = run_ui("top", str(tmp_path / "mill.ini"), "--once")
    assert result.returncode == 2
    assert result.stderr.startswith("cnc top: ") and result.stderr.count("\n") == 1
    assert "mill.ini" in result.stderr


def test_operator_messages_are_shown_newest_last(controller: Nml) -> None:
    controller[EMC_STATUS].write(machine_status())
    watcher = Controller()
    try:
        for text in ("first", "spindle\non fire"):
            controller[EMC_ERROR].write(emc.EMC_OPERATOR_ERROR(error=text))
        controller[EMC_ERROR].write(emc.EMC_OPERATOR_TEXT(text="tool changed"))
        is_up, lines = snapshot(watcher)
    finally:
        watcher.close()
    assert is_up
    assert lines[-4] == "Messages:"
    assert [line.split(maxsplit=1)[1] for line in lines[-3:]] == [  # after the time
        "error: first",
        "error: spindle on fire",
        "text: tool changed",
    ]


def test_the_screen_of_a_three_axis_machine_fits_80x24(controller: Nml) -> None:
    controller[EMC_STATUS].write(machine_status())
    s = cnc.stat()
    s.poll()
    lines = status_screen(s, [], "title", height=24)
    assert len(lines) <= 24
    assert max(len(line) for line in lines) <= 80
    assert lines[-1] == "Messages: none"


def odd_status() -> emc.EMC_STAT:
    """A status no controller should publish: unknown states, NaN, garbage codes."""
    status = emc.EMC_STAT(status=99, echo_serial_number=-5)
    task = status.task
    task.state, task.mode, task.execState, task.interpState = 0, -3, 6, 1000
    task.file = "\x1b[2J\x07bell\nnewline"
    task.g5x_index, task.rotation_xy = 42, math.nan
    task.activeGCodes[:] = [7, 123456, -9, 5, 0, 1, 2, 3, 4, -1, -1, 999999, 17, 18, 19, 20, 21]
    task.activeMCodes[:] = [-1] * 10
    task.activeSettings[:] = [math.nan, math.inf, -math.inf, 0.0, 1e300]
    traj = status.motion.traj
    traj.joints, traj.spindles, traj.axis_mask = 1000, -4, -1
    traj.linearUnits, traj.scale, traj.rapid_scale = math.nan, math.inf, -1e308
    traj.mode, traj.motion_type, traj.queue = 17, -2, -1
    traj.position.tran.x, traj.position.tran.y, traj.position.c = math.inf, 1e300, math.nan
    status.motion.joint[0].homing = 1
    status.motion.joint[3].fault = 1
    status.motion.spindle[0].direction = 5
    status.io.tool.toolInSpindle = -7
    return status


def test_odd_status_values_never_crash_the_view(controller: Nml) -> None:
    controller[EMC_STATUS].write(odd_status())
    s = cnc.stat()
    s.poll()
    lines = status_screen(s, [], "title", height=24)
    assert len(lines) <= 24
    assert all(line.isprintable() for line in lines)
    text = "\n".join(status_screen(s, [], "title"))
    assert "Task unknown(0)  mode unknown(-3)  interp unknown(1000)" in text
    assert "File ?[2J?bell newline" in text
    rows = {line.split()[0]: line.split() for line in text.splitlines() if line[:1] in "XA"}
    # work X: inf minus offsets, rotated by NaN degrees; joint 0 homing, joint 3 faulted
    assert rows["X"] == ["X", "nan", "inf", "0.0000", "0", "0.0000", "homing", "ok"]
    assert rows["A"][-1] == "FAULT"
    assert "G5x(42) X0.0000 Y0.0000" in text  # every axis: the mask has all bits set


def _start_in_terminal(procs, *args: str) -> tuple[object, int]:
    """Run cnc top in an 80x24 pseudo-terminal; (process, the terminal's master side)."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    proc = procs.python(
        "-c",
        UI_MAIN.format(name="top"),
        *args,
        stdin=slave,
        stdout=slave,
        stderr=slave,
        env={"TERM": "xterm", "LINES": "24", "COLUMNS": "80"},
    )
    os.close(slave)
    return proc, master


def test_the_full_screen_view_renders_at_80x24_and_quits_on_q(fake_task, procs) -> None:
    fake_task()
    proc, master = _start_in_terminal(procs, "--interval", "0,05")
    try:
        screen = read_until(master, b"Messages:")
        os.write(master, b"q")
        assert proc.wait(timeout=WAIT_S) == 0
    finally:
        os.close(master)
    for text in (b"ESTOP", b"MANUAL", b"12.500", b"G91.1", b"forward"):
        assert text in screen
    assert b"Traceback" not in screen


def test_the_view_waits_for_the_controller_then_shows_it(procs) -> None:
    proc, master = _start_in_terminal(procs, "--interval", "0.05")
    try:
        read_until(master, b"Waiting")
        nml = Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR])
        try:
            nml[EMC_STATUS].write(machine_status())
            read_until(master, b"ESTOP")
            os.write(master, b"q")
            assert proc.wait(timeout=WAIT_S) == 0
        finally:
            nml.close()
    finally:
        os.close(master)


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_ends_the_view_and_restores_the_terminal(fake_task, procs, signum) -> None:
    """The launcher ends its display with SIGTERM; Ctrl-C sends SIGINT."""
    fake_task()
    proc, master = _start_in_terminal(procs)
    try:
        read_until(master, b"Messages:")
        proc.send_signal(signum)
        # xterm's "leave the alternate screen": curses gave the terminal back
        read_until(master, b"\x1b[?1049l")
        assert proc.wait(timeout=WAIT_S) == 0
    finally:
        os.close(master)


def test_without_a_terminal_it_prints_the_view_until_a_signal(fake_task, procs) -> None:
    """As a machine's display started from a script or a service (no terminal), top must
    keep running (its exit would shut the machine down) and print what it would show."""
    fake_task()
    proc = procs.python(
        "-c", UI_MAIN.format(name="top"), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE
    )
    seen = ""
    deadline = time.monotonic() + WAIT_S
    while "Messages:" not in seen:
        assert time.monotonic() < deadline, seen
        assert proc.poll() is None, proc.stderr.read()
        if select.select([proc.stdout], [], [], 0.5)[0]:
            seen += os.read(proc.stdout.fileno(), 4096).decode()
    assert "ESTOP" in seen and "MANUAL" in seen
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=WAIT_S) == 0
    assert "not a terminal" in proc.stderr.read()
