"""cnc sh: commands reach the controller in order, failures stop scripts, errors are one line."""

from __future__ import annotations

import io
import os
import pty
import signal
from pathlib import Path

import pytest

from cnc.ui.controller import Controller
from cnc.ui.sh import Shell
from tests.ui.conftest import UI_MAIN, WAIT_S, read_until


def kinds_and_fields(commands: list[dict]) -> list[tuple[str, dict]]:
    """(type, fields) of received commands, without serial numbers and what the safety
    board adds (a request's stamp, a jog's lease: they change from run to run)."""
    return [
        (c["type"], {k: v for k, v in c["fields"].items() if k not in _VARYING}) for c in commands
    ]


_VARYING = ("serial_number", "tag", "request", "lease_slot", "lease_pid")


def test_commands_are_sent_in_order_and_each_reports_done(fake_task, run_ui) -> None:
    task = fake_task()
    result = run_ui("sh", "-c", "machine on; mode mdi; mdi G0 X1")
    assert result.returncode == 0, result
    received = kinds_and_fields([task.next_command() for _ in range(3)])
    assert received == [
        ("EMC_TASK_SET_STATE", {"state": 4}),
        ("EMC_TASK_SET_MODE", {"mode": 3}),
        ("EMC_TASK_PLAN_EXECUTE", {"command": "G0 X1"}),
    ]
    assert result.lines == [
        "cnc> machine on",
        "DONE",
        "cnc> mode mdi",
        "DONE",
        "cnc> mdi G0 X1",
        "DONE",
    ]


def test_a_failing_command_stops_the_script_with_the_controllers_error(fake_task, run_ui) -> None:
    task = fake_task("--fail", "G1 X1")
    result = run_ui("sh", "-c", "mdi G1 X1; mdi G0 X0")
    assert result.returncode == 1
    assert result.lines == ["cnc> mdi G1 X1", "ERROR: failed: G1 X1"]
    assert "-c:1: stopped at the first error" in result.stderr
    assert task.next_command()["fields"]["command"] == "G1 X1"
    run_ui("sh", "-c", "mode auto")  # the next command task sees is this one, not G0 X0
    assert task.next_command()["type"] == "EMC_TASK_SET_MODE"


def test_keep_going_runs_every_command_and_still_fails(fake_task, run_ui) -> None:
    task = fake_task("--fail", "G1 X1")
    result = run_ui("sh", "-k", "-c", "mdi G1 X1; mdi G0 X0")
    assert result.returncode == 1
    assert result.lines[-2:] == ["cnc> mdi G0 X0", "DONE"]
    assert [task.next_command()["fields"]["command"] for _ in range(2)] == ["G1 X1", "G0 X0"]


def test_a_script_file_runs_every_kind_of_command(fake_task, run_ui, tmp_path: Path) -> None:
    task = fake_task()
    program = tmp_path / "part.ngc"
    program.write_text("G0 X1\nM2\n")
    script = tmp_path / "job.cnc"
    script.write_text(
        "# bring the machine up\n"
        "estop off\nmachine on\n\n"
        "mode manual; home all\n"
        "jog 0 incr 0,5 120\n"  # 0.5 units at 120 units/min = 2 units/s, decimal comma
        "jog Y - 30; jog y stop\n"
        "vector 600 -300 0\n"  # units/min: 10 and -5 units/s
        "feed 75,5%\n"
        "spindle fwd\n"  # at the programmed S (1000 in the fake task's settings)
        "flood on\n"
        f"mode auto; open {program}; set optional_stop on; run; wait\n"
        "stop\n"
    )
    result = run_ui("sh", str(script))
    assert result.returncode == 0, result
    assert result.lines.count("DONE") == 17  # one per command
    received = kinds_and_fields([task.next_command() for _ in range(17)])  # open sends two
    assert received == [
        ("EMC_TASK_SET_STATE", {"state": 2}),
        ("EMC_TASK_SET_STATE", {"state": 4}),
        ("EMC_TASK_SET_MODE", {"mode": 1}),
        ("EMC_JOINT_HOME", {"joint": -1}),
        ("EMC_JOG_INCR", {"joint_or_axis": 0, "incr": 0.5, "vel": 2.0, "jjogmode": 1}),
        ("EMC_JOG_CONT", {"joint_or_axis": 1, "vel": -0.5, "jjogmode": 0}),
        ("EMC_JOG_STOP", {"joint_or_axis": 1, "jjogmode": 0}),
        (
            "EMC_TRAJ_SET_TELEOP_VECTOR",
            {"vector": {"tran": {"x": 10.0, "y": -5.0, "z": 0.0}} | dict.fromkeys("abcuvw", 0.0)},
        ),
        ("EMC_TRAJ_SET_SCALE", {"scale": 0.755}),
        (
            "EMC_SPINDLE_ON",
            {
                "spindle": 0,
                "speed": 1000.0,
                "factor": 0.0,
                "xoffset": 0.0,
                "wait_for_spindle_at_speed": 0,
            },
        ),
        ("EMC_COOLANT_FLOOD_ON", {}),
        ("EMC_TASK_SET_MODE", {"mode": 2}),
        ("EMC_TASK_PLAN_CLOSE", {}),
        ("EMC_TASK_PLAN_OPEN", {"file": str(program)}),
        ("EMC_TASK_PLAN_SET_OPTIONAL_STOP", {"state": True}),
        ("EMC_TASK_PLAN_RUN", {"line": 0}),
        ("EMC_TASK_ABORT", {}),
    ]


def test_commands_piped_on_stdin_are_a_script(fake_task, run_ui) -> None:
    task = fake_task()
    result = run_ui("sh", stdin="mode mdi\nmdi G0 X2\n")
    assert result.returncode == 0, result
    assert [task.next_command()["type"] for _ in range(2)] == [
        "EMC_TASK_SET_MODE",
        "EMC_TASK_PLAN_EXECUTE",
    ]


def test_show_pos_prints_work_and_machine_coordinates_of_the_axes(fake_task, run_ui) -> None:
    fake_task()
    result = run_ui("sh", "-c", "show pos")
    assert result.returncode == 0, result
    assert result.lines == [
        "cnc> show pos",
        "Axis        Work     Machine       To go",
        "X          2.500      12.500       0.000",
        "Y         -3.250      -3.250       0.000",
        "Z         40.000      40.000       0.000",
        "G54 X10.000 Y0.000 Z0.000   rotation 0.0",
        "G92 X0.000 Y0.000 Z0.000",
        "DONE",
    ]


def test_show_state_follows_the_commands(fake_task, run_ui) -> None:
    fake_task()
    result = run_ui("sh", "-c", "estop off; machine on; mode mdi; show state; show gcodes")
    assert result.returncode == 0, result
    assert "Task ON  mode MDI  interp IDLE  command DONE" in result.lines
    assert "G-codes G1 G17 G40 G21 G90 G94 G54 G49 G99 G64 G97 G91.1 G8 G92.2" in result.lines
    assert "M-codes M5 M9 M48   F500 S1000" in result.lines


def test_without_a_controller_commands_fail_with_the_reason(run_ui) -> None:
    result = run_ui("sh", "-c", "machine on")
    assert result.returncode == 1
    assert result.lines[-1].startswith("ERROR: emcCommand: the controller is not running")


def test_a_missing_script_or_machine_file_is_one_line(run_ui, tmp_path: Path) -> None:
    missing = run_ui("sh", str(tmp_path / "nothing.cnc"))
    assert missing.returncode == 2
    assert missing.stderr.startswith("cnc sh: cannot read") and missing.stderr.count("\n") == 1
    bad_ini = run_ui("sh", str(tmp_path / "nothing.ini"), "-c", "show")
    assert bad_ini.returncode == 2
    assert "nothing.ini" in bad_ini.stderr and bad_ini.stderr.count("\n") == 1


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("frobnicate", "ERROR: unknown command 'frobnicate' (help lists the commands)"),
        ("estop maybe", "ERROR: estop: 'maybe' is not one of on|off (usage: estop on|off)"),
        ("machine on now", "ERROR: machine: expects 1 argument (usage: machine on|off)"),
        ("mode fast", "ERROR: mode: 'fast' is not one of manual|auto|mdi"),
        ("home x", "ERROR: home: joint: 'x' is not a whole number"),
        ("jog 0 sideways", "ERROR: jog: 'sideways' is not one of +|-"),
        ("jog Q + 10", "ERROR: jog: joint: 'Q' is not a whole number"),
        ("jog 0 incr", "ERROR: jog: expects 3 to 4 arguments"),
        ("vector 1 2", "ERROR: vector: expects 3 to 6 arguments"),
        ("feed 1,000.5", "ERROR: feed: percent: '1,000.5' is not a number (use one"),
        ("feed -5", "ERROR: feed: percent must be at least 0"),
        ("mdi", "ERROR: mdi: expects a line of G-code (usage: mdi GCODE)"),
        ("run one", "ERROR: run: line: 'one' is not a whole number"),
        ("spindle fwd -100", "ERROR: spindle: RPM must be at least 0"),
        ("set colour on", "ERROR: set: 'colour' is not one of optional_stop|block_delete|"),
        ("set timeout soon", "ERROR: set: timeout: 'soon' is not a number"),
        ("show everything", "ERROR: show: 'everything' is not one of pos|joints|state|"),
        ("sleep -1", "ERROR: sleep: seconds must be at least 0"),
        ("help frob", "ERROR: help: 'frob' is not one of estop|machine|"),
    ],
)
def test_a_bad_command_or_argument_is_one_error_line(line: str, expected: str) -> None:
    out = io.StringIO()
    shell = Shell(Controller(), out)
    assert shell.execute(line) is False
    assert out.getvalue().count("\n") == 1
    assert out.getvalue().startswith(expected)


def test_decimal_comma_or_point_in_numbers(fake_task) -> None:
    task = fake_task()
    out = io.StringIO()
    shell = Shell(Controller(), out)
    assert shell.execute("feed 1000,5") and shell.execute("rapid 50.25")
    assert task.next_command()["fields"]["scale"] == pytest.approx(10.005)
    assert task.next_command()["fields"]["scale"] == pytest.approx(0.5025)


def test_the_interactive_shell_runs_typed_commands(fake_task, procs, tmp_path: Path) -> None:
    task = fake_task()
    master, slave = pty.openpty()
    env = {"TERM": "xterm", "HOME": str(tmp_path)}  # history file in the test's folder
    proc = procs.python(
        "-c", UI_MAIN.format(name="sh"), stdin=slave, stdout=slave, stderr=slave, env=env
    )
    os.close(slave)
    try:
        read_until(master, b"cnc> ")
        os.write(master, b"mode mdi\n")
        read_until(master, b"DONE\r\ncnc> ")  # the shell is reading the next line
        os.write(master, b"sleep 1000\n")
        read_until(master, b"sleep 1000\r\n")  # the shell has read it
        proc.send_signal(signal.SIGINT)  # Ctrl-C ends the command, not the shell
        read_until(master, b"interrupted")
        os.write(master, b"quit\n")
        assert proc.wait(timeout=WAIT_S) == 0
    finally:
        os.close(master)
    assert task.next_command()["type"] == "EMC_TASK_SET_MODE"
    history = (tmp_path / ".cnc_sh_history").read_text().splitlines()
    assert history[-3:] == ["mode mdi", "sleep 1000", "quit"]
