"""configs/sim/mesa_7i96s.ini end to end: the machine of configs/mesa/7i96s.ini on the
simulated 7I96S card, started by ``cnc run --headless``, driven by ``cnc sh`` and the API.

The configs folder is copied first (a running machine writes its files) and the card is
given a loopback address of its own. Four settings are eased for a shared, loaded test
machine, where a Python host and a Python card answering over UDP do not always fit a
servo period in 1 ms and a realtime thread may stall for milliseconds: the servo period is
4 ms (with the position loops' gain for it, P = 1 / period as pncconf sets it: an overrun
period is a longer period, and with P for 1 ms the loops then oscillate), the card's
watchdog timeout 0.5 s (a stall would, rightly, make a real card bite), its read timeout
20 ms and the following error limits 20 mm / 10 mm. ``scripts/bench/hw_bench.py``
measures what a period costs. Everything else is the config as shipped; at rest commanded
and fed-back positions must still agree within a step.
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
from hal import pymodule
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
    for old, new in (
        ("FERROR = 1.0", "FERROR = 20.0"),
        ("MIN_FERROR = 0.25", "MIN_FERROR = 10.0"),
        ("SERVO_PERIOD = 1000000", "SERVO_PERIOD = 4000000"),
        ("P = 1000.0", "P = 250.0"),  # the loops' gain for 4 ms (pncconf's P = 1 / period)
    ):
        assert old in text, old
        text = text.replace(old, new)
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
        # the VFD's link comes up a moment after the machine (hy_vfd is a program of its
        # own): before it does, its spindle fault refuses "machine on", as in LinuxCNC
        wait_for(
            lambda: get("spindle-vfd.hycomm-ok") and not get("spindle.0.amp-fault-in"),
            "the VFD link up",
        )
        yield Machine(folder, launcher)
    finally:
        hal_api.set_shared_hal(None)
        hal.close()
        launcher.send_signal(signal.SIGTERM)
        launcher.wait(timeout=60)


def get(name: str):
    return pymodule.get_value(name)


@pytest.mark.timeout(400)
def test_the_machine_homes_runs_a_program_and_drives_its_spindle(machine: Machine) -> None:
    """One start for the machine's slow part (homing): a program, then the spindle."""
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
    check_the_vfd_follows_the_spindle_and_a_lost_link_stops_the_program(machine)


def messages_seen(errors: cnc.error_channel, text: str) -> Callable[[], bool]:
    """A condition: an operator message containing ``text`` has come."""
    seen: list[str] = []

    def condition() -> bool:
        while (message := errors.poll()) is not None:
            seen.append(message[1])
        return any(text in m for m in seen)

    return condition


def test_lost_packets_then_a_stalled_host_stop_the_machine(machine: Machine) -> None:
    """Lost answers are counted and forgiven below the limit; past it the link stops and
    the machine goes to E-stop; once reset, a host that stops writing makes the card's
    watchdog bite: outputs off, E-stop, a message."""
    machine.sh("estop off", "machine on")
    errors = cnc.error_channel()
    machine.halcmd("setp", "sim-7i96s.drop-one-in", "5")  # one answer in five lost
    wait_for(lambda: get(f"{BOARD}.packet-error-total") >= 20, "packet errors")
    machine.halcmd("setp", "sim-7i96s.drop-one-in", "0")
    assert status().task_state == cnc.STATE_ON  # below the limit the machine runs on
    assert not get(f"{BOARD}.packet-error-exceeded")

    machine.halcmd("setp", "sim-7i96s.is-mute", "1")  # the cable is cut
    wait_for(lambda: status().task_state == cnc.STATE_ESTOP, "E-stop")
    assert get(f"{BOARD}.packet-error-exceeded") and get(f"{BOARD}.io_error")
    assert get(f"{BOARD}.packet-error-level") == get(f"{BOARD}.packet-error-limit")
    wait_for(messages_seen(errors, "packet errors"), "the link message")
    # the stopped link writes nothing: the card's watchdog bites 0.5 s later (the cable
    # must stay cut that long, or the writes that follow pet it in time)
    wait_for(lambda: get("sim-7i96s.watchdog.has-bit"), "the card's watchdog biting")

    # the cable is back: clear io_error (and the watchdog, which bit meanwhile), reset
    machine.halcmd("setp", "sim-7i96s.is-mute", "0")
    machine.halcmd("setp", f"{BOARD}.io_error", "0")
    wait_for(lambda: get(f"{BOARD}.watchdog.has_bit"), "the bite noticed")
    machine.halcmd("sets", "watchdog-has-bit", "FALSE")
    wait_for(lambda: get("sim-7i96s.io.017.is-output"), "the outputs back")
    machine.sh("estop off", "machine on")
    while errors.poll() is not None:  # the messages so far, the first bite's among them
        pass

    machine.halcmd("delf", f"{BOARD}.write", "servo-thread")  # the host stops writing
    wait_for(lambda: status().task_state == cnc.STATE_ESTOP, "E-stop")
    assert get(f"{BOARD}.watchdog.has_bit") and get("sim-7i96s.watchdog.has-bit")
    assert not any(get(f"sim-7i96s.io.{io:03d}.is-output") for io in range(51))  # outputs off
    wait_for(messages_seen(errors, "Watchdog has bit"), "the watchdog message")


def check_the_vfd_follows_the_spindle_and_a_lost_link_stops_the_program(machine: Machine) -> None:
    """The Huanyang VFD on its pseudo-terminal (hy_vfd <-> hy_vfd_sim) follows S and
    M3/M4/M5, its speed comes back to motion, and losing its link stops the program."""
    errors = cnc.error_channel()
    machine.sh("mode mdi", "mdi S12000 M3", "wait")
    wait_for(lambda: abs(get("sim-vfd.rpm") - 12000) < 1, "the spindle at 12000 rpm forward")
    wait_for(lambda: get("spindle-vfd.spindle-at-speed"), "at speed")
    assert get("spindle-vfd.spindle-speed-fb") == pytest.approx(12000, abs=1)
    # rps, for motion: through a scale on the servo thread, which may be a read behind
    wait_for(lambda: abs(get("spindle.0.speed-in") - 200.0) < 0.1, "motion's speed-in 200 rps")
    machine.sh("mdi M4", "wait")
    wait_for(lambda: abs(get("sim-vfd.rpm") + 12000) < 1, "the spindle at 12000 rpm reverse")
    machine.sh("mdi S18000", "wait")
    wait_for(lambda: abs(get("sim-vfd.rpm") + 18000) < 1, "the spindle at 18000 rpm reverse")
    machine.sh("mdi M5", "wait")
    wait_for(lambda: get("sim-vfd.rpm") == 0, "the spindle stopped")

    (machine.folder / "nc_files" / "long.ngc").write_text(
        "G21 G90\nS12000 M3\nG1 X100 F60\nM5\nM2\n"  # a 100 s cut
    )
    machine.sh("mode auto", "open nc_files/long.ngc", "run")
    wait_for(lambda: get("spindle-vfd.spindle-at-speed") and status().current_vel > 0, "cutting")
    machine.halcmd("setp", "sim-vfd.is-mute", "1")  # the RS-485 cable is cut
    wait_for(lambda: not status().enabled, "motion disabled by the spindle fault")
    wait_for(lambda: status().interp_state == cnc.INTERP_IDLE, "the program stopped")
    stat = status()
    work_x = stat.position[0] - stat.g5x_offset[0] - stat.g92_offset[0]
    assert work_x < 99.5  # the cut stopped short
    assert get("spindle-vfd.error-count") > 0 and not get("spindle-vfd.hycomm-ok")
    messages: list = []
    wait_for(
        lambda: messages.append(errors.poll())
        or (any(m and "VFD link lost" in m[1] for m in messages)
            and any(m and "spindle 0 amplifier fault" in m[1] for m in messages)),
        "the messages",
    )  # fmt: skip
