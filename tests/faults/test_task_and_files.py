"""Task stays answering, jogs end with their UI, files survive faults (items 1, 7, 13, 14)."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from nml.ipcnames import instance_objects
from tests.conftest import REPO
from tests.faults.conftest import WAIT_S, FaultyMachine, cnc
from tests.task.test_machine import MACHINE

pytestmark = pytest.mark.slow

ENDLESS_SUB = (
    "o<spin> sub\n#1 = 0\no100 while [1]\n#1 = [#1 + 1]\no100 endwhile\no<spin> endsub\nM2\n"
)


def test_task_answers_while_an_mdi_subroutine_loops_forever(start_faulty) -> None:
    machine: FaultyMachine = start_faulty(RS274NGC=["SUBROUTINE_PATH = ."])
    (machine.folder / "spin.ngc").write_text(ENDLESS_SUB)
    c, s = machine.command, machine.stat
    c.mdi("o<spin> call")
    machine.until(lambda s: s.interp_state != cnc.INTERP_IDLE)
    c.abort()  # answered at once: the interpreter reads only a slice of each cycle
    assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_DONE
    machine.until(lambda s: s.interp_state == cnc.INTERP_IDLE)
    c.mdi("o<spin> call")
    time.sleep(0.2)
    c.state(cnc.STATE_ESTOP)
    assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_DONE
    s.poll()
    assert s.task_state == cnc.STATE_ESTOP and s.interp_state == cnc.INTERP_IDLE


def test_an_interpreter_that_never_produces_motion_is_stopped(start_faulty) -> None:
    machine: FaultyMachine = start_faulty(RS274NGC=["SUBROUTINE_PATH = ."])  # timeout 2 s
    (machine.folder / "spin.ngc").write_text(ENDLESS_SUB)
    c = machine.command
    c.mdi("o<spin> call")
    assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_ERROR
    texts = machine.text_of_messages()
    assert any("without producing motion" in text and "INTERP_TIMEOUT" in text for text in texts)
    c.mdi("G0 X1")  # and task works on
    assert c.wait_complete(timeout=WAIT_S) == cnc.RCS_DONE


JOG_AND_VANISH = """
import os, signal, sys, time
import cnc
c = cnc.command()
c.mode(cnc.MODE_MANUAL); c.wait_complete()
c.teleop_enable(1); c.wait_complete()
c.jog(cnc.JOG_CONTINUOUS, 0, 0, 10.0)
c.wait_complete()
print("jogging", flush=True)
time.sleep(0.3)
os.kill(os.getpid(), getattr(signal, sys.argv[1]))
"""


@pytest.mark.parametrize("how", ["SIGKILL", "SIGSTOP"])
def test_a_continuous_jog_stops_when_its_ui_goes_away(start_faulty, procs, how) -> None:
    machine: FaultyMachine = start_faulty()
    ui = procs.python("-c", JOG_AND_VANISH, how)
    assert ui.stdout.readline().strip() == "jogging"
    if how == "SIGSTOP":
        machine.stopped_pids.append(ui.pid)  # type: ignore[attr-defined]
    start = machine.x()
    deadline, last = time.monotonic() + WAIT_S, start
    while True:  # moving, then stopped by motion once the UI's lease ran out
        time.sleep(0.1)
        now = machine.x()
        if now == last and now > start:
            break
        assert time.monotonic() < deadline, "the jog never stopped"
        last = now
    assert last < 90.0  # stopped long before the soft limit
    assert machine.pin("motion.motion-enabled")  # a stopped jog, not an E-stop
    texts = machine.text_of_messages()
    assert any("continuous jog stopped" in text for text in texts), texts


def test_a_failing_realtime_function_puts_the_machine_in_estop(start_faulty) -> None:
    broken = REPO / "tests" / "hal" / "files" / "broken.py"
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    for words in (["loadrt", str(broken)], ["addf", "broken.0", "servo-thread"]):
        done = subprocess.run([sys.executable, "-m", "cnc", "halcmd", *words], cwd=REPO)
        assert done.returncode == 0
    machine.wait_at_rest()
    machine.until(lambda s: s.task_state == cnc.STATE_ESTOP)
    assert machine.pin("broken.0.calls") > 1  # never disabled


def positions(folder: Path) -> list[float]:
    return [float(word) for word in (folder / "position.txt").read_text().split()]


def test_sigterm_mid_move_saves_where_the_machine_came_to_rest(start_faulty) -> None:
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    samples: list[float] = []
    machine.proc.send_signal(signal.SIGTERM)
    while machine.proc.poll() is None:  # motion's position until the machine is gone
        try:
            samples.append(machine.x())
        except Exception:  # (HAL removed while we read)
            break
        time.sleep(0.002)
    assert machine.proc.wait(timeout=WAIT_S) == 0
    saved = positions(machine.folder)[0]
    assert 0.0 < saved < 90.0
    assert saved == pytest.approx(samples[-1], abs=1e-9)  # at rest when saved, not passing by


def test_a_machine_killed_outright_is_not_restored_from_stale_positions(
    start_faulty, procs
) -> None:
    machine: FaultyMachine = start_faulty()
    machine.command.mdi("G0 X20")
    machine.command.wait_complete(WAIT_S)
    for pid in [*machine.pids().values(), machine.proc.pid]:  # all at once: a power cut
        os.kill(pid, signal.SIGKILL)
    machine.proc.wait(timeout=WAIT_S)
    assert (machine.folder / ".position.txt.running").exists()  # the run never saved
    again = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=machine.folder)
    restarted = FaultyMachine(again, machine.folder)
    try:
        restarted.wait_ready()
        texts = restarted.text_of_messages(2.0)
        assert any("ended without saving the joint positions" in text for text in texts), texts
        c = restarted.command
        c.state(cnc.STATE_ESTOP_RESET)
        c.wait_complete()
        c.state(cnc.STATE_ON)
        c.wait_complete()
        c.mode(cnc.MODE_MDI)
        c.wait_complete()
        c.mdi("G0 X1")  # not homed: refused, even though this machine does not force homing
        assert c.wait_complete(WAIT_S) == cnc.RCS_ERROR
        texts = restarted.text_of_messages()
        assert any("the last run did not save positions" in text for text in texts), texts
    finally:
        restarted.stop()


def test_a_closed_stderr_pipe_does_not_stop_the_machine(procs, tmp_path: Path) -> None:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    proc.stderr.readline()  # as `cnc run mill.ini 2>&1 | head -1`
    proc.stderr.close()
    machine = FaultyMachine(proc, folder)
    machine.wait_ready()
    machine.ready_to_move()
    machine.command.mdi("G0 X5")
    assert machine.command.wait_complete(WAIT_S) == cnc.RCS_DONE
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=WAIT_S) == 0
    assert instance_objects() == []  # cleaned up as usual


def test_a_failed_position_save_reaches_the_error_channel(start_faulty) -> None:
    machine: FaultyMachine = start_faulty(TRAJ=["POSITION_FILE = gone/position.txt"])
    texts: list[str] = []
    machine.proc.send_signal(signal.SIGTERM)
    while machine.proc.poll() is None:  # task saves while the launcher shuts down
        try:
            message = machine.errors.poll()
        except cnc.error:
            break  # the machine is gone
        if message is None:
            time.sleep(0.005)
        else:
            texts.append(message[1])
    assert any("cannot save the joint positions to" in text for text in texts), texts
