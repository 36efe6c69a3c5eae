"""configs/sim/mesa_7i96s.ini end to end: the machine of configs/mesa/7i96s.ini on the
simulated 7I96S card, started by ``cnc run --headless``, driven by ``cnc sh`` and the API.

The configs folder is copied first (a running machine writes its files), the card is
given a loopback address of its own, the card's watchdog timeout is raised from 5 ms to
0.5 s, its read timeout from 80 % of the period to 20 ms, the servo period from 1 to 2 ms
and the following error limits to 20 mm / 10 mm: on a shared, loaded test machine a
Python host and a Python card answering over UDP do not always fit a servo period in 1 ms,
and a realtime thread may stall for milliseconds, which would (rightly) make a real card
bite, and makes the stepgens run on at their last speed while motion waits (a following
error that the loop then closes). ``scripts/bench/hw_bench.py`` measures what a period
costs. Everything else is the config as shipped; at rest commanded and fed-back positions
must still agree within a step.
"""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

import cnc
from cnc.runtime import read_runtime_info
from hal import api as hal_api
from hal.core import Hal
from tests.hal.halrun_util import REPO
from tests.hw.conftest import free_loopback_ip

pytestmark = pytest.mark.slow
STEPS_PER_MM = 320.0
BOARD = "hm2_7i96s.0"
PROGRAM = """G21 G90 G54
G0 X10 Y10 Z-5
G1 X40 F900
G1 Y35
G2 X15 Y35 I-12.5 J0
G0 Z0
M2
"""


@dataclass
class Machine:
    folder: Path
    launcher: subprocess.Popen[str]

    def sh(self, *commands: str, is_checked: bool = True) -> str:
        done = subprocess.run(
            [sys.executable, "-m", "cnc", "sh", "-c", "; ".join(commands)],
            cwd=self.folder, capture_output=True, text=True, timeout=180,
            stdin=subprocess.DEVNULL,
        )  # fmt: skip
        if is_checked:
            assert done.returncode == 0 and "ERROR" not in done.stdout, done.stdout + done.stderr
        return done.stdout + done.stderr

    def halcmd(self, *words: str) -> None:
        done = subprocess.run(
            [sys.executable, "-m", "cnc", "halcmd", *words],
            cwd=self.folder, capture_output=True, text=True, timeout=60,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr


def wait_for(condition: Callable[[], bool], what: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def status() -> cnc.stat:
    stat = cnc.stat()
    stat.poll()
    return stat


@pytest.fixture
def machine(procs, tmp_path: Path, cnc_instance: str) -> Iterator[Machine]:
    configs = tmp_path / "configs"
    shutil.copytree(REPO / "configs", configs)
    ini = configs / "sim" / "mesa_7i96s.ini"
    text = ini.read_text().replace("IPADDR = 127.0.0.1", f"IPADDR = {free_loopback_ip()}")
    text = text.replace("FERROR = 1.0", "FERROR = 20.0").replace(
        "MIN_FERROR = 0.25", "MIN_FERROR = 10.0"
    )
    ini.write_text(text)
    hal_file = configs / "mesa" / "7i96s.hal"
    hal_text = hal_file.read_text().replace("timeout_ns 5000000", "timeout_ns 500000000")
    hal_file.write_text(hal_text + f"setp {BOARD}.packet-read-timeout 20000000\n")
    (configs / "sim" / "nc_files" / "square.ngc").write_text(PROGRAM)
    folder = configs / "sim"
    launcher = procs.python("-m", "cnc", "run", "--headless", "mesa_7i96s.ini", cwd=folder)
    deadline = time.monotonic() + 90
    while (info := read_runtime_info()) is None or info.pid != launcher.pid:
        assert launcher.poll() is None, launcher.stderr.read()
        assert time.monotonic() < deadline, "the machine did not come up"
        time.sleep(0.05)
    hal = Hal()  # the machine's HAL, for get() (attached once the machine runs)
    hal_api.set_shared_hal(hal)
    try:
        yield Machine(folder, launcher)
    finally:
        hal_api.set_shared_hal(None)
        hal.close()
        launcher.send_signal(signal.SIGTERM)
        launcher.wait(timeout=60)


def get(name: str):
    return hal_api.get_value(name)


def test_the_machine_homes_on_its_switches_and_runs_a_program(machine: Machine) -> None:
    machine.sh("estop off", "machine on", "home all", "wait")
    stat = status()
    assert stat.task_state == cnc.STATE_ON and all(stat.homed[:3])
    machine.sh("mode auto", "open nc_files/square.ngc", "run", "wait")
    stat = status()
    assert stat.position[:3] == pytest.approx((15.0, 35.0, 0.0), abs=1e-6)
    for joint in range(3):
        # the position loop closes the last of its error after motion is done
        wait_for(
            lambda j=joint: (
                abs(get(f"joint.{j}.motor-pos-fb") - get(f"joint.{j}.motor-pos-cmd"))
                < 1.0 / STEPS_PER_MM
            ),
            f"joint {joint} at its commanded position",
        )
        commanded = get(f"joint.{joint}.motor-pos-cmd")
        feedback = get(f"joint.{joint}.motor-pos-fb")
        assert feedback == get(f"hm2_7i96s.0.stepgen.{joint:02d}.position-fb")
        assert feedback == pytest.approx(commanded, abs=1.0 / STEPS_PER_MM)  # within a step
        # and the motor itself is where the feedback says: the card's step count
        steps = get(f"sim-7i96s.stepgen.{joint:02d}.position")
        assert steps / STEPS_PER_MM == pytest.approx(feedback, abs=1e-6)
    assert get("hm2_7i96s.0.packet-error-exceeded") is False


def test_the_watchdog_bites_when_the_host_stops_writing(machine: Machine) -> None:
    machine.sh("estop off", "machine on")
    errors = cnc.error_channel()
    assert get("sim-7i96s.io.017.is-output")  # X step is driven
    machine.halcmd("delf", "hm2_7i96s.0.write", "servo-thread")  # the host stops writing
    wait_for(lambda: status().task_state == cnc.STATE_ESTOP, "E-stop")
    assert get("hm2_7i96s.0.watchdog.has_bit")
    assert get("sim-7i96s.watchdog.has-bit")
    assert not any(get(f"sim-7i96s.io.{io:03d}.is-output") for io in range(51))  # outputs off
    messages = []
    wait_for(lambda: messages.append(errors.poll()) or any(
        m and "Watchdog has bit" in m[1] for m in messages), "the message")  # fmt: skip


def test_packet_loss_is_counted_and_past_the_limit_stops_the_machine(machine: Machine) -> None:
    machine.sh("estop off", "machine on")
    errors = cnc.error_channel()
    machine.halcmd("setp", "sim-7i96s.drop-one-in", "5")  # one answer in five lost
    wait_for(lambda: get("hm2_7i96s.0.packet-error-total") >= 20, "packet errors")
    machine.halcmd("setp", "sim-7i96s.drop-one-in", "0")
    assert status().task_state == cnc.STATE_ON  # below the limit the machine runs on
    assert not get("hm2_7i96s.0.packet-error-exceeded")
    machine.halcmd("setp", "sim-7i96s.is-mute", "1")  # the link is lost
    wait_for(lambda: status().task_state == cnc.STATE_ESTOP, "E-stop")
    assert get("hm2_7i96s.0.packet-error-exceeded")
    assert get("hm2_7i96s.0.packet-error-level") == get("hm2_7i96s.0.packet-error-limit")
    messages = []
    wait_for(lambda: messages.append(errors.poll()) or any(
        m and "packet errors" in m[1] for m in messages), "the message")  # fmt: skip
