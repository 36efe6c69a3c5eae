"""A process that carries safety inputs or outputs dies or freezes mid-move (issue 14 item 2).

Killed (SIGKILL) or stopped (SIGSTOP): the machine brakes to rest, goes to E-stop, the
operator is told which process was lost, and E-stop cannot be reset until the machine is
restarted (the lost process's inputs are no longer read).
"""

from __future__ import annotations

import os
import signal
import time

import pytest

from tests.faults.conftest import (
    WAIT_S,
    FaultyMachine,
    cnc,
    estop_from_another_ui,
    stop_process,
)

pytestmark = pytest.mark.slow


@pytest.mark.parametrize(
    ("name", "sig"),
    [
        ("iocontrol", signal.SIGKILL),
        ("halui", signal.SIGKILL),
        ("iocontrol", signal.SIGSTOP),
        ("halui", signal.SIGSTOP),
    ],
)
def test_a_lost_io_process_brakes_the_machine_to_estop(start_faulty, name, sig) -> None:
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    pid = machine.pids()[name]
    if sig == signal.SIGSTOP:
        stop_process(machine, pid)
    else:
        os.kill(pid, sig)
    stopped_at = machine.wait_at_rest()
    assert stopped_at < 90.0  # braked, not finished
    machine.until(lambda s: s.task_state == cnc.STATE_ESTOP, timeout=WAIT_S)
    texts = machine.text_of_messages()
    assert any(f"E-stop: {name} (pid {pid})" in text for text in texts), texts
    machine.command.state(cnc.STATE_ESTOP_RESET)
    assert machine.command.wait_complete() == cnc.RCS_ERROR
    assert any(
        "cannot reset E-stop" in text and name in text for text in machine.text_of_messages()
    )
    estop_from_another_ui(machine)  # still answered


def test_motion_stops_the_machine_when_task_freezes(start_faulty) -> None:
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    pid = machine.pids()["task"]
    stop_process(machine, pid)
    stopped_at = machine.wait_at_rest()  # from motion's pins: task cannot tell us
    assert stopped_at < 90.0
    texts = machine.text_of_messages()
    assert any(f"E-stop: task (pid {pid}) stopped answering" in text for text in texts), texts
    assert not machine.pin("iocontrol.0.user-enable-out")  # the E-stop chain is open


def test_a_killed_task_brings_the_machine_down_at_rest_positions_saved(start_faulty) -> None:
    machine: FaultyMachine = start_faulty()
    machine.start_long_move()
    os.kill(machine.pids()["task"], signal.SIGKILL)
    assert machine.proc.wait(timeout=WAIT_S) == 1  # the launcher shuts the machine down
    err = machine.proc.stderr.read()
    assert "task (pid" in err and "was killed by SIGKILL; shutting down" in err, err
    saved = [float(word) for word in (machine.folder / "position.txt").read_text().split()]
    assert 0.0 < saved[0] < 90.0  # where motion came to rest, saved by the launcher
    assert not (machine.folder / ".position.txt.running").exists()  # a clean save


def test_estop_from_another_ui_acts_at_once_while_task_is_frozen(start_faulty) -> None:
    machine: FaultyMachine = start_faulty(TASK=["HEARTBEAT_TIMEOUT = 60"])  # not found lost
    machine.start_long_move()
    stop_process(machine, machine.pids()["task"])
    estop_from_another_ui(machine)
    machine.wait_at_rest()  # motion acted on the board, without task
    assert not machine.pin("iocontrol.0.user-enable-out")  # and so did iocontrol


def test_abort_from_another_ui_acts_while_task_is_frozen(start_faulty) -> None:
    machine: FaultyMachine = start_faulty(TASK=["HEARTBEAT_TIMEOUT = 60"])
    machine.command.mdi("M3 S1000")
    machine.command.wait_complete()
    machine.start_long_move()
    stop_process(machine, machine.pids()["task"])
    done = machine.ui("cnc.command().abort()\nprint('sent')")
    assert done.returncode == 0 and "sent" in done.stdout, done.stderr
    last, deadline = machine.x(), time.monotonic() + WAIT_S
    while True:  # decelerated to a stop, still on: an abort, not an E-stop
        time.sleep(0.05)
        now = machine.x()
        if now == last:
            break
        assert time.monotonic() < deadline
        last = now
    assert last < 90.0 and machine.pin("motion.motion-enabled")
    assert machine.pin("spindle.0.speed-out") == 0.0
