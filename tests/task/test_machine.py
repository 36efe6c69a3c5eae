"""A whole machine through real processes: ``cnc run`` + the ``cnc`` API (TASK-*, IO-*).

The launcher starts the realtime host with motion, iocontrol and task from
tests/task/machine/mill.ini (copied to a scratch folder: the machine writes its parameter,
position and tool files); the test drives it like a LinuxCNC script would.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import cnc
from cnc.runtime import read_runtime_info
from nml.channels import DEFAULT_NML_FILE
from nml.ipcnames import instance_objects, remove_instance_objects

MACHINE = Path(__file__).with_name("machine")


class Machine:
    def __init__(self, proc: subprocess.Popen[str], folder: Path) -> None:
        self.proc = proc
        self.folder = folder

    def wait_ready(self, timeout: float = 30) -> None:
        """Until this launcher says its machine runs; then connect, as a UI would."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            assert self.proc.poll() is None, self.proc.stderr.read()
            info = read_runtime_info()
            if info is not None and info.pid == self.proc.pid:
                self.stat = cnc.stat()
                self.command = cnc.command()
                self.errors = cnc.error_channel()
                self.stat.poll()
                return
            time.sleep(0.05)
        raise AssertionError("the machine did not come up")

    def until(self, condition, timeout: float = 20) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.stat.poll()
            if condition(self.stat):
                return
            time.sleep(0.01)
        raise AssertionError(f"condition not reached; task_state {self.stat.task_state}")

    def messages(self, wait: float = 0.5) -> list[tuple[int, str]]:
        found = []
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            message = self.errors.poll()
            if message is None:
                time.sleep(0.01)
                continue
            found.append(message)
        return found

    def open_program(self, path: Path) -> None:
        """AUTO mode, then ``path`` opened, as a UI does before running it."""
        self.command.mode(cnc.MODE_AUTO)
        assert self.command.wait_complete() == cnc.RCS_DONE
        self.command.program_open(str(path))
        assert self.command.wait_complete() == cnc.RCS_DONE

    def stop(self) -> None:
        """SIGTERM to the launcher, as Ctrl-C would; killed if it does not stop."""
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()

    def ready_to_move(self) -> None:
        c = self.command
        c.state(cnc.STATE_ESTOP_RESET)
        assert c.wait_complete() == cnc.RCS_DONE
        c.state(cnc.STATE_ON)
        assert c.wait_complete() == cnc.RCS_DONE
        c.mode(cnc.MODE_MANUAL)
        c.wait_complete()
        c.home(-1)
        c.wait_complete()
        self.until(lambda s: all(s.homed[:3]) and s.inpos)
        c.mode(cnc.MODE_MDI)
        assert c.wait_complete() == cnc.RCS_DONE


@contextlib.contextmanager
def launched(procs, folder: Path) -> Iterator[Machine]:
    """The machine of ``folder``/mill.ini started headless and ready; stopped at the end."""
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(proc, folder)
    try:
        machine.wait_ready()
        yield machine
    finally:
        machine.stop()


def test_estop_reset_on_home_and_mdi_move(machine: Machine) -> None:
    s = machine.stat
    s.poll()
    assert s.task_state == cnc.STATE_ESTOP
    machine.ready_to_move()
    c = machine.command
    c.mdi("G0 X10 Y-5")
    assert c.wait_complete(10) == cnc.RCS_DONE
    s.poll()
    assert s.position[:3] == pytest.approx((10.0, -5.0, 10.0))  # Z homed to HOME = 10
    assert s.task_mode == cnc.MODE_MDI and s.interp_state == cnc.INTERP_IDLE


def test_status_shows_ini_limits_joint_types_and_unset_traj_limits_as_unlimited(
    machine: Machine,
) -> None:
    """stat.axis limits come from [AXIS_L] (as LinuxCNC's task fills them); an absent
    [TRAJ]MAX_LINEAR_ACCELERATION reads 1e99, as in LinuxCNC."""
    s = machine.stat
    s.poll()
    assert [(a["min_position_limit"], a["max_position_limit"]) for a in s.axis[:3]] == [
        (-100.0, 100.0),
        (-100.0, 100.0),
        (-50.0, 50.0),
    ]
    assert (s.max_velocity, s.max_acceleration) == (50.0, 1e99)
    assert s.block_delete is True  # as the canon starts, in LinuxCNC too
    assert [(j["jointType"], j["units"]) for j in s.joint[:3]] == [(cnc.LINEAR, 1.0)] * 3


def test_bad_mdi_line_is_an_error_with_the_interpreters_text(machine: Machine) -> None:
    machine.ready_to_move()
    machine.messages(0.1)
    c = machine.command
    c.mdi("G999")
    assert c.wait_complete(5) == cnc.RCS_ERROR
    assert (cnc.OPERATOR_ERROR, "G-code out of range") in machine.messages()
    c.mdi("G1 X1 F0")
    assert c.wait_complete(5) == cnc.RCS_ERROR
    assert (cnc.OPERATOR_ERROR, "Cannot do g1 with zero feed rate") in machine.messages()


def test_a_long_non_ascii_error_is_cut_to_fit_and_task_goes_on(machine: Machine) -> None:
    """The error for a missing program repeats its name: with 2-byte characters it was
    longer than the message field, and task crashed writing it (the machine shut down)."""
    machine.ready_to_move()
    machine.messages(0.1)
    c = machine.command
    c.mode(cnc.MODE_AUTO)
    c.wait_complete()
    missing = machine.folder / ("ñandú" * 24 + ".ngc")  # the name alone: 168 bytes
    c.program_open(str(missing))
    assert c.wait_complete(5) == cnc.RCS_ERROR
    errors = [text for kind, text in machine.messages() if kind == cnc.OPERATOR_ERROR]
    assert len(errors) == 1 and "ñandú" in errors[0], errors
    assert len(errors[0].encode("utf-8")) < 255
    c.mode(cnc.MODE_MDI)
    c.wait_complete()
    c.mdi("G0 X1")
    assert c.wait_complete(10) == cnc.RCS_DONE  # task is still there


def test_errors_nobody_reads_keep_the_newest_and_never_stall_task(start_machine) -> None:
    """A machine whose error channel nobody drains (here one a tenth of the usual size):
    once the queue is full the oldest messages make room, and the reader is told how many
    it missed (task used to wait a second for room, then drop the newest)."""
    small = DEFAULT_NML_FILE.read_text().replace(
        "emcError      SHMEM  localhost  262144", "emcError      SHMEM  localhost  26214"
    )
    machine = start_machine(files={"small.nml": small}, EMC=["NML_FILE = small.nml"])
    c = machine.command
    for index in range(150):  # far more than the channel holds
        c.error_msg(f"note {index}")
        assert c.wait_complete(5) == cnc.RCS_DONE
    texts = [text for kind, text in machine.messages() if kind == cnc.OPERATOR_ERROR]
    missed = int(texts[0].split()[0])
    assert texts[0].endswith(
        "were dropped before this display read them: the error channel was full"
    )
    kept = [text for text in texts[1:] if text.startswith("note ")]
    assert 10 < len(kept) < 150 and missed >= 150 - len(kept)
    assert kept == [f"note {index}" for index in range(150 - len(kept), 150)]


def test_commands_in_the_wrong_state_or_mode_are_refused(machine: Machine) -> None:
    c = machine.command
    c.mode(cnc.MODE_MDI)
    c.wait_complete()
    c.mdi("G0 X1")
    assert c.wait_complete(5) == cnc.RCS_ERROR  # still in E-stop
    assert any("machine must be on" in text for _, text in machine.messages())


def test_program_with_a_loop_and_a_tool_change_runs_to_the_end(machine: Machine) -> None:
    program = machine.folder / "part.ngc"
    program.write_text(
        "G21 G90 G17\n"
        "G10 L2 P2 X5 Y-2 Z-3\n"  # offsets: G55 moved, then used with the tool length
        "G10 L1 P2 Z12.5\n"  # a tool table edit from the program
        "T2 M6 G43\n"
        "G55 G0 X0 Y0 Z5\n"
        "#1 = 0\n"
        "o100 while [#1 LT 3]\n"
        "  G1 X[10 * [#1 + 1]] F600\n"
        "  #1 = [#1 + 1]\n"
        "o100 endwhile\n"
        "G2 X10 Y0 I-10 J0\n"
        "G3 X30 Y0 I10 J0\n"
        "M8\n"
        "G0 Z8\n"
        "M9\n"
        "M2\n"
    )
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE, timeout=5)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos, timeout=30)
    s = machine.stat
    assert s.g5x_index == 1  # M2 went back to G54, as in LinuxCNC
    assert s.tool_offset[2] == pytest.approx(12.5)
    assert s.position[:3] == pytest.approx((35.0, -2.0, 17.5))  # work (30, 0, 8) in machine
    assert s.tool_in_spindle == 2 and s.tool_table[2].zoffset == pytest.approx(12.5)
    assert not s.flood
    assert "Z+12.5" in (machine.folder / "test.tbl").read_text()


def test_sigterm_stops_everything_and_leaves_nothing(procs, tmp_path: Path, cnc_instance) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(proc, folder)
    machine.wait_ready()
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=30) == 0
    assert instance_objects(cnc_instance) == []
    assert (folder / "position.txt").exists()


def machine_pids(launcher: subprocess.Popen[str], folder: Path) -> dict[str, int]:
    """The machine's processes: the launcher's children and whatever was started with the
    machine's INI file (iocontrol outlives the halcmd that started it)."""
    found: dict[str, int] = {}
    children = subprocess.run(["pgrep", "-P", str(launcher.pid)], capture_output=True, text=True)
    by_ini = subprocess.run(
        ["pgrep", "-f", f"ini {folder}/mill.ini"], capture_output=True, text=True
    )
    for pid in {*children.stdout.split(), *by_ini.stdout.split()}:
        with contextlib.suppress(OSError):
            found[Path(f"/proc/{pid}/cmdline").read_text().replace("\0", " ")] = int(pid)
    return found


@pytest.mark.parametrize(
    ("process", "name"), [("-m task", "task"), ("hal.rtapi_app", "the realtime host")]
)
def test_killing_task_or_the_realtime_host_mid_program_stops_and_cleans_up(
    process: str, name: str, procs, tmp_path: Path, cnc_instance
) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(proc, folder)
    machine.wait_ready()
    start_long_program(machine)
    (pid,) = [pid for line, pid in machine_pids(proc, folder).items() if process in line]
    os.kill(pid, signal.SIGKILL)
    assert proc.wait(timeout=30) == 1  # the launcher noticed and shut everything down
    assert f"{name} (pid {pid}) was killed by SIGKILL; shutting down" in proc.stderr.read()
    assert all(not Path(f"/proc/{pid}").exists() for pid in machine_pids(proc, folder).values())
    assert instance_objects(cnc_instance) == []


def test_a_restart_after_kill_9_of_everything_starts_clean(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    first = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    Machine(first, folder).wait_ready()
    pids = machine_pids(first, folder)
    assert any("hal.rtapi_app" in line for line in pids) and any(
        "iocontrol" in line for line in pids
    )
    for pid in [first.pid, *pids.values()]:  # nobody gets a chance to clean up
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    first.wait(timeout=10)
    second = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(second, folder)
    machine.wait_ready()
    machine.ready_to_move()  # stale buffers, HAL and runtime file replaced: it works
    second.send_signal(signal.SIGTERM)
    assert second.wait(timeout=30) == 0


def test_a_second_launch_of_the_same_instance_is_refused(machine: Machine, procs) -> None:
    second = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=machine.folder)
    assert second.wait(timeout=30) == 1
    assert "a machine is already running" in second.stderr.read()
    machine.stat.poll()  # the first one is untouched, and keeps working
    assert machine.stat.task_state == cnc.STATE_ESTOP
    machine.ready_to_move()
    machine.command.mdi("G0 X1")
    assert machine.command.wait_complete(10) == cnc.RCS_DONE
    assert read_runtime_info().pid == machine.proc.pid


def start_long_program(machine: Machine) -> None:
    program = machine.folder / "long.ngc"
    program.write_text("G21 G90\nG1 X40 F1800\nG1 X0\nM2\n")
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 0)
    machine.until(lambda s: s.position[0] > 2.0, timeout=10)


def test_pause_holds_position_and_resume_continues_the_program(machine: Machine) -> None:
    start_long_program(machine)
    c, s = machine.command, machine.stat
    c.auto(cnc.AUTO_PAUSE)
    c.wait_complete()
    machine.until(lambda s: s.paused and s.current_vel == 0.0)
    held = s.position[0]
    time.sleep(0.3)
    s.poll()
    assert s.position[0] == held and s.interp_state == cnc.INTERP_PAUSED
    c.auto(cnc.AUTO_RESUME)
    c.wait_complete()
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos, timeout=30)
    assert s.position[0] == pytest.approx(0.0, abs=1e-9)  # the whole program ran


def test_abort_mid_move_stops_and_reports_it(machine: Machine) -> None:
    start_long_program(machine)
    machine.messages(0.05)
    c, s = machine.command, machine.stat
    c.abort()
    c.wait_complete()
    machine.until(lambda s: s.inpos and s.interp_state == cnc.INTERP_IDLE, timeout=5)
    stopped_at = s.position[0]
    assert 2.0 < stopped_at < 40.0  # decelerated on the way, the rest of the program dropped
    time.sleep(0.3)
    s.poll()
    assert s.position[0] == stopped_at
    assert (cnc.OPERATOR_TEXT, "task: aborted") in machine.messages()


def test_killing_a_ui_mid_program_changes_nothing(machine: Machine, procs) -> None:
    start_long_program(machine)
    watcher = procs.python(
        "-c",
        "import cnc, time\ns = cnc.stat(); e = cnc.error_channel()\n"
        "while True:\n    s.poll(); e.poll(); time.sleep(0.01)\n",
    )
    time.sleep(0.5)
    watcher.kill()
    watcher.wait(10)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos, timeout=30)
    assert machine.stat.position[0] == pytest.approx(0.0, abs=1e-9)
    assert machine.stat.task_state == cnc.STATE_ON


def test_after_homing_a_ui_jogs_axes_in_teleop_mode(machine: Machine) -> None:
    machine.ready_to_move()
    c = machine.command
    c.mode(cnc.MODE_MANUAL)
    c.wait_complete()
    c.teleop_enable(1)
    assert c.wait_complete() == cnc.RCS_DONE
    c.jog(cnc.JOG_INCREMENT, False, 1, 10.0, 3.0)  # axis Y, as AXIS does once homed
    machine.until(lambda s: s.position[1] == pytest.approx(3.0) and s.inpos)
    assert machine.stat.motion_mode == cnc.TRAJ_MODE_TELEOP


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            lambda f: (f / "mill.hal").write_text(
                (f / "mill.hal").read_text() + "net bad nosuch.pin\n"
            ),
            "mill.hal:14: Pin 'nosuch.pin' does not exist",
        ),
        (
            lambda f: (f / "mill.ini").write_text(
                (f / "mill.ini").read_text().replace("HALFILE = mill.hal", "HALFILE = gone.hal")
            ),
            "[HAL]HALFILE: HAL file 'gone.hal' not found",
        ),
        (
            lambda f: (f / "mill.ini").write_text(
                (f / "mill.ini").read_text().replace("CYCLE_TIME = 0.005", "CYCLE_TIME = fast")
            ),
            "mill.ini:11: [TASK]CYCLE_TIME = 'fast' is not a finite number",
        ),
    ],
)
def test_a_failed_start_says_where_and_leaves_nothing(
    procs,
    tmp_path: Path,
    cnc_instance,
    change,
    expected: str,
) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    change(folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    assert proc.wait(timeout=60) == 1
    assert expected in proc.stderr.read()
    assert instance_objects(cnc_instance) == []
    assert not subprocess.run(["pgrep", "-f", f"ini {folder}"], capture_output=True).stdout


def test_on_abort_command_runs_after_an_abort(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    ini = folder / "mill.ini"
    ini.write_text(ini.read_text().replace("[RS274NGC]\n", "[RS274NGC]\nON_ABORT_COMMAND = M9\n"))
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(proc, folder)
    try:
        machine.wait_ready()
        machine.ready_to_move()
        c = machine.command
        c.mdi("M8")
        c.wait_complete()
        machine.until(lambda s: s.flood == cnc.FLOOD_ON)
        c.abort()
        c.wait_complete()
        machine.until(lambda s: s.flood == cnc.FLOOD_OFF)  # the M9 of ON_ABORT_COMMAND
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)


def test_run_from_line_skips_what_comes_before_it(machine: Machine) -> None:
    program = machine.folder / "lines.ngc"
    program.write_text("G21 G90\nM8\nG0 X10\nG0 Y5\nM2\n")  # line 4 is "G0 Y5"
    machine.ready_to_move()
    c = machine.command
    machine.open_program(program)
    c.auto(cnc.AUTO_RUN, 4)
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE, timeout=5)
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE and s.inpos, timeout=20)
    s = machine.stat
    # the skipped G0 X10 moved nothing: as LinuxCNC (checked on its sim), the start line
    # starts from where the machine stands, and the skipped M8 was not carried out
    assert s.position[:2] == pytest.approx((0.0, 5.0))
    assert s.flood == cnc.FLOOD_OFF


def test_step_carries_out_one_line_at_a_time(machine: Machine) -> None:
    program = machine.folder / "steps.ngc"
    program.write_text("G21 G90\nG0 X5\nG0 Y5\nG0 X0\nM2\n")
    machine.ready_to_move()
    c, s = machine.command, machine.stat
    machine.open_program(program)
    seen = []
    for _ in range(3):
        c.auto(cnc.AUTO_STEP)
        c.wait_complete()
        machine.until(lambda s: s.interp_state == cnc.INTERP_PAUSED and s.inpos, timeout=10)
        seen.append(tuple(round(v, 6) for v in s.position[:2]))
    assert seen == [(5.0, 0.0), (5.0, 5.0), (0.0, 5.0)]
    c.auto(cnc.AUTO_RESUME)
    c.wait_complete()
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE, timeout=10)


def test_opening_the_estop_chain_puts_the_machine_in_estop(machine: Machine) -> None:
    machine.ready_to_move()
    machine.messages(0.05)
    for words in (
        ["unlinkp", "iocontrol.0.emc-enable-in"],
        ["setp", "iocontrol.0.emc-enable-in", "0"],
    ):
        done = subprocess.run([sys.executable, "-m", "cnc", "halcmd", *words], capture_output=True)
        assert done.returncode == 0, done.stderr
    machine.until(lambda s: s.task_state == cnc.STATE_ESTOP and not s.enabled, timeout=10)
    assert any("E-stop" in text for _, text in machine.messages())


def test_the_machine_reappears_where_it_was_after_a_restart(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    first = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(first, folder)
    machine.wait_ready()
    machine.ready_to_move()
    machine.command.mdi("G0 X12.5 Y-3")
    machine.command.wait_complete(10)
    first.send_signal(signal.SIGTERM)
    assert first.wait(timeout=30) == 0
    assert len((folder / "position.txt").read_text().split()) == 16  # LinuxCNC's format
    second = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    machine = Machine(second, folder)
    try:
        machine.wait_ready()
        machine.until(lambda s: s.joint_actual_position[:2] == pytest.approx((12.5, -3.0)))
        assert not any(machine.stat.homed[:3])  # where it was, but not homed
    finally:
        second.send_signal(signal.SIGTERM)
        second.wait(timeout=30)


def test_a_killed_launcher_takes_its_machine_down_with_it(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    launcher = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    Machine(launcher, folder).wait_ready()
    pids = machine_pids(launcher, folder)
    assert len(pids) >= 3  # realtime host, iocontrol, task
    os.kill(launcher.pid, signal.SIGKILL)
    launcher.wait(timeout=10)
    deadline = time.monotonic() + 20
    while any(Path(f"/proc/{pid}").exists() for pid in pids.values()):
        assert time.monotonic() < deadline, f"still running: {list(pids)}"
        time.sleep(0.05)
    # what they left in shared memory is removed by the next launch (see the restart test)
    remove_instance_objects()


def test_a_launch_while_another_one_starts_up_is_refused(procs, tmp_path: Path) -> None:
    """The instance is claimed (a kernel lock) before anything is made, so a second launch
    never removes the buffers of a machine still starting up."""
    from cnc.runtime import claim_instance, release_instance

    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    lock = claim_instance()  # as a launcher that has not finished starting holds it
    assert lock is not None and claim_instance() is None
    try:
        second = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
        assert second.wait(timeout=30) == 1
        assert "already running for instance" in second.stderr.read()
    finally:
        release_instance(lock)
