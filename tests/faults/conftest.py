"""Fault injection through whole machines: what a fault does to a machine that moves.

``moving`` starts the test mill (tests/task/machine, with halui and a short interpreter
timeout), brings it on, homed, in MDI mode, and starts a long feed move along X; the test
then injects its fault and checks what a machinist must be able to count on: the machine
comes to rest and goes to E-stop, the operator is told why, E-stop still works from another
process, nothing is lost. Positions come from HAL (motion's own pins), so they are seen
even when task, which publishes the status, is the process that was hit.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

import cnc
from hal.core import Hal
from nml.safety import NUM_SLOTS, SafetyBoard
from tests.conftest import REPO
from tests.task.test_machine import MACHINE, Machine

WAIT_S = 20.0  # how long a test waits for the machine to react before it fails
INI_LINES = {
    "HAL": ["HALUI = halui"],
    "TASK": ["INTERP_TIMEOUT = 2"],
}


class FaultyMachine(Machine):
    """A running test mill plus what fault tests need: pids, HAL pins, other UIs."""

    def pids(self) -> dict[str, int]:
        """Pid of each process on the safety board: task, motion (the realtime host),
        iocontrol, halui."""
        board = SafetyBoard.attach()
        assert board is not None
        try:
            found = {}
            for index in range(NUM_SLOTS):
                slot = board._slot(index)
                if slot.pid and slot.is_supervised:
                    found[slot.name] = slot.pid
            return found
        finally:
            board.close()

    def pin(self, name: str) -> float | bool:
        hal = Hal(is_creating=False)
        try:
            found = hal.find_pin(name)
            assert found is not None, name
            return hal.pin_value(found[1])
        finally:
            hal.close()

    def x(self) -> float:
        return float(self.pin("joint.0.pos-cmd"))

    def wait_at_rest(self, timeout: float = WAIT_S) -> float:
        """Until motion (its HAL pins, not task's status) is off and X stands still; X."""
        deadline = time.monotonic() + timeout
        last = self.x()
        while time.monotonic() < deadline:
            time.sleep(0.05)
            now = self.x()
            if not self.pin("motion.motion-enabled") and now == last:
                return now
            last = now
        raise AssertionError("motion did not come to rest and turn off")

    def start_long_move(self) -> None:
        """A feed move of 90 mm at 20 mm/s: 4.5 s of motion to interrupt."""
        self.command.mdi("G1 F1200 X90")
        deadline = time.monotonic() + WAIT_S
        start = self.x()
        while self.x() == start:
            assert time.monotonic() < deadline, "the move did not start"
            time.sleep(0.01)

    def text_of_messages(self, wait: float = 1.0) -> list[str]:
        return [text for _, text in self.messages(wait)]

    def ui(self, code: str, timeout: float = WAIT_S) -> subprocess.CompletedProcess[str]:
        """Run ``code`` in another process that imports cnc, as another UI would."""
        return subprocess.run(
            [sys.executable, "-c", "import cnc\n" + code],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=timeout,
            env={**os.environ, "PYTHONPATH": str(REPO)},
        )


@pytest.fixture
def start_faulty(procs, tmp_path: Path) -> Iterator[Callable[..., FaultyMachine]]:
    """``start_faulty(**sections)``: a fresh test mill with halui (extra INI lines per
    section as in tests/task/conftest.py), on, homed, in MDI mode; stopped at the end,
    whatever the test left stopped (SIGSTOP) is continued first."""
    started: list[FaultyMachine] = []
    stopped: list[int] = []

    def start(**sections: list[str]) -> FaultyMachine:
        folder = tmp_path / f"machine{len(started)}"
        shutil.copytree(MACHINE, folder)
        ini = folder / "mill.ini"
        text = ini.read_text()
        for section, lines in {**INI_LINES, **sections}.items():
            header = f"[{section}]\n"
            text = text.replace(header, header + "".join(f"{line}\n" for line in lines))
        ini.write_text(text)
        proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
        machine = FaultyMachine(proc, folder)
        machine.stopped_pids = stopped  # type: ignore[attr-defined]
        started.append(machine)
        machine.wait_ready()
        machine.ready_to_move()
        return machine

    yield start
    for pid in stopped:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGCONT)
    for machine in started:
        machine.stop()


def stop_process(machine: FaultyMachine, pid: int) -> None:
    """SIGSTOP ``pid``, remembered so the fixture continues it before shutting down."""
    machine.stopped_pids.append(pid)  # type: ignore[attr-defined]
    os.kill(pid, signal.SIGSTOP)


def estop_from_another_ui(machine: FaultyMachine) -> None:
    """E-stop from a separate process, which must return, not hang."""
    done = machine.ui("cnc.command().state(cnc.STATE_ESTOP)\nprint('sent')")
    assert done.returncode == 0 and "sent" in done.stdout, done.stderr


__all__ = ["WAIT_S", "FaultyMachine", "cnc", "estop_from_another_ui", "stop_process"]
