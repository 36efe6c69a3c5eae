"""The MQTT bridges end to end: a real Mosquitto with password authentication, a machine
started by ``cnc run`` with ``[MQTT]ENABLE = 1`` and LinuxCNC's ``mqtt-publisher`` in its
HAL file, and MQTT clients as a dashboard and an MES would be.

One machine serves the module (each test brings it to the state it needs).
"""

from __future__ import annotations

import os
import shutil
import signal
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

import cnc
from tests.bridges.conftest import (
    USERS,
    WAIT_S,
    Broker,
    Machine,
    close,
    needs_mosquitto,
    running_machine,
    shared_instance,
    start_broker,
    subscribe,
)
from tests.conftest import Processes

pytestmark = [needs_mosquitto, pytest.mark.slow, pytest.mark.timeout(600)]
ROOT = "cnc/mill-1"
PUBLISHER_PREFIX = "devices/linuxcnc/mill-1"
# the keys of LinuxCNC's tests/mqtt/simulator.hal, with this machine's signal names
PUBLISHER_KEYS = (
    "x-pos,y-pos,z-pos,halui.axis.a.pos-feedback,halui.axis.x.pos-feedback,"
    "halui.axis.y.pos-feedback,halui.axis.z.pos-feedback,halui.estop.is-activated,"
    "halui.joint.0.is-homed,halui.joint.1.is-homed,halui.joint.2.is-homed,"
    "halui.machine.is-on,halui.max-velocity.value,halui.mode.is-auto,halui.mode.is-manual,"
    "halui.mode.is-mdi,halui.mode.is-teleop,halui.program.is-running"
)


def mqtt_section(port: int, *extra: str) -> list[str]:
    return [
        "ENABLE = 1",
        "BROKER = 127.0.0.1",
        f"PORT = {port}",
        "USERNAME = cnc",
        f"PASSWORD = {USERS['cnc']}",
        "MACHINE_NAME = mill-1",
        "CYCLE_TIME = 0.05",
        *extra,
    ]


@dataclass
class Rig:
    broker: Broker
    machine: Machine
    procs: Processes
    folder: Path


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Rig]:
    folder = tmp_path_factory.mktemp("mqtt")
    procs = Processes()
    try:
        with shared_instance("mqtt"):
            broker = start_broker(procs, folder / "broker")
            hal_lines = [
                # LinuxCNC's loadusr line (tests/mqtt/simulator.hal), [MQTT] substituted
                "loadusr -W mqtt-publisher --mqtt-broker=[MQTT]BROKER "
                "--mqtt-port=[MQTT]PORT --mqtt-user=[MQTT]USERNAME "
                f"--mqtt-password=[MQTT]PASSWORD --mqtt-prefix={PUBLISHER_PREFIX} "
                f"keys={PUBLISHER_KEYS}",
                "setp mqtt-publisher.period 1",
            ]
            sections = {"MQTT": mqtt_section(broker.port)}
            with running_machine(procs, folder / "machine", sections, hal_lines) as machine:
                yield Rig(broker, machine, procs, folder)
    finally:
        procs.kill_all()


@pytest.fixture(autouse=True)
def cnc_instance(rig: Rig) -> str:
    """Replaces tests/conftest.py's per-test instance: the tests share the machine's."""
    return os.environ["CNC_INSTANCE"]


def machine_on(command: cnc.command) -> None:
    command.state(cnc.STATE_ESTOP_RESET)
    command.state(cnc.STATE_ON)
    assert command.wait_complete() == cnc.RCS_DONE


def home_and_move(command: cnc.command, line: str) -> None:
    machine_on(command)
    command.home(-1)
    command.wait_complete()
    status = cnc.stat()
    deadline = time.monotonic() + WAIT_S
    while not all(status.homed[:3]):
        assert time.monotonic() < deadline, "the machine did not home"
        time.sleep(0.05)
        status.poll()
    command.mode(cnc.MODE_MDI)
    command.wait_complete()
    command.mdi(line)
    assert command.wait_complete(WAIT_S) == cnc.RCS_DONE


def test_status_position_and_alarms_arrive_and_a_subscriber_sees_an_estop(rig: Rig) -> None:
    dashboard = subscribe(rig.broker.port, f"{ROOT}/#")
    try:
        # retained: a dashboard that connects late sees the machine at once
        assert dashboard.wait_for(f"{ROOT}/online") is True
        info = dashboard.wait_for(f"{ROOT}/info")
        assert info["name"] == "mill-1"
        assert info["machine"] == "test-mill"
        assert info["coordinates"] == "XYZ"
        command = cnc.command()
        home_and_move(command, "G0 X10 Y-5")
        assert dashboard.wait_for(f"{ROOT}/state") in ("ON", "ESTOP", "ESTOP_RESET", "OFF")
        dashboard.wait_for(f"{ROOT}/state", lambda state: state == "ON")
        position = dashboard.wait_for(f"{ROOT}/position", lambda p: p["X"] == 10.0)
        assert position == {"X": 10.0, "Y": -5.0, "Z": 10.0}
        dashboard.wait_for(f"{ROOT}/mode", lambda mode: mode == "MDI")
        dashboard.wait_for(f"{ROOT}/homed", lambda homed: homed == [True, True, True])

        command.feedrate(0.5)
        dashboard.wait_for(f"{ROOT}/feed/override", lambda value: value == 0.5)
        command.feedrate(1.0)

        command.error_msg("coolant pressure low")  # an operator error: an alarm
        alarm = dashboard.wait_for(f"{ROOT}/alarm", lambda a: "coolant" in a["text"])
        assert alarm["kind"] == "error"
        dashboard.wait_for(f"{ROOT}/message", lambda m: m["text"] == "coolant pressure low")

        command.state(cnc.STATE_ESTOP)
        assert dashboard.wait_for(f"{ROOT}/estop", lambda estop: estop is True)
        assert dashboard.wait_for(f"{ROOT}/state", lambda state: state == "ESTOP")
    finally:
        close(dashboard)


def test_mqtt_publisher_publishes_hal_values_as_linuxcnc_s(rig: Rig) -> None:
    import hal

    listener = subscribe(rig.broker.port, PUBLISHER_PREFIX)
    try:
        command = cnc.command()
        home_and_move(command, "G0 X1 Y0 Z0")  # as LinuxCNC's tests/mqtt/display.py
        last = hal.get_value("mqtt-publisher.lastpublish")
        data = listener.wait_for(  # at rest: halui's feedback pin follows a cycle later
            PUBLISHER_PREFIX,
            lambda d: d["x-pos"] == 1.0 and d.get("halui.axis.x.pos-feedback") == 1.0,
        )
        # signals and pins by name, bits as booleans, the period added; missing keys left out
        assert data["y-pos"] == 0.0
        assert data["halui.axis.x.pos-feedback"] == 1.0
        assert data["halui.machine.is-on"] is True
        assert data["halui.estop.is-activated"] is False
        assert data["halui.mode.is-mdi"] is True
        assert data["mqtt-publisher.period"] == 1
        assert "halui.axis.a.pos-feedback" not in data  # no A axis on this machine
        deadline = time.monotonic() + WAIT_S
        while hal.get_value("mqtt-publisher.lastpublish") == last:
            assert time.monotonic() < deadline, "lastpublish did not change"
            time.sleep(0.1)
        assert abs(hal.get_value("mqtt-publisher.lastpublish") - time.time()) < 5
    finally:
        close(listener)


def test_wrong_credentials_are_refused(rig: Rig, procs: Processes, tmp_path: Path) -> None:
    assert subscribe(rig.broker.port, f"{ROOT}/#", password="wrong") is None
    assert subscribe(rig.broker.port, f"{ROOT}/#", user=None) is None
    # a bridge with a wrong password says so and publishes nothing
    ini = copy_ini(rig, tmp_path, "PASSWORD = wrong", "MACHINE_NAME = impostor")
    watcher = subscribe(rig.broker.port, "cnc/impostor/#")
    bridge = procs.python("-m", "cnc", "bridge", "mqtt", str(ini))
    try:
        line = bridge.stderr.readline()
        while "refused" not in line:
            assert line, "the bridge ended without saying it was refused"
            line = bridge.stderr.readline()
        assert "Not authorized" in line or "password" in line
        with pytest.raises(AssertionError):
            watcher.wait_for("cnc/impostor/online", timeout=0.5)
    finally:
        close(watcher)


def copy_ini(rig: Rig, folder: Path, *mqtt_lines: str, port: int | None = None) -> Path:
    """The machine's INI with its [MQTT] section replaced (for a bridge started by hand)."""
    text = rig.machine.ini.read_text().split("\n[MQTT]\n")[0]
    lines = mqtt_section(port or rig.broker.port)
    names = {line.split("=")[0].strip() for line in mqtt_lines}
    lines = [line for line in lines if line.split("=")[0].strip() not in names]
    ini = folder / "bridge.ini"
    ini.write_text(text + "\n[MQTT]\n" + "\n".join([*lines, *mqtt_lines]) + "\n")
    for name in ("test.tbl", "test.var", "mill.hal"):
        shutil.copy(rig.machine.folder / name, folder / name)
    return ini


def ask(client, root: str, request: dict) -> dict:
    client.publish(f"{root}/command", request)
    return client.wait_for(f"{root}/command/response", lambda r: r["id"] == request["id"])


def test_commands_are_refused_unless_enabled(rig: Rig) -> None:
    client = subscribe(rig.broker.port, f"{ROOT}/command/response")
    try:
        status = cnc.stat()
        status.poll()
        before = status.rapidrate
        answer = ask(client, ROOT, {"id": 1, "command": "rapid_override", "value": 0.25})
        assert answer["ok"] is False
        assert "disabled" in answer["error"]
        status.poll()
        assert status.rapidrate == before
        answer = ask(client, ROOT, {"id": 2, "command": "format_disk"})
        assert answer["ok"] is False
        assert "unknown command" in answer["error"]
    finally:
        close(client)


def test_commands_are_carried_out_when_enabled_on_an_authenticating_broker(
    rig: Rig, procs: Processes, tmp_path: Path
) -> None:
    ini = copy_ini(rig, tmp_path, "COMMANDS = 1", "MACHINE_NAME = mill-1-ops")
    procs.python("-m", "cnc", "bridge", "mqtt", str(ini))
    root = "cnc/mill-1-ops"
    client = subscribe(rig.broker.port, f"{root}/#")
    try:
        client.wait_for(f"{root}/online", lambda online: online is True)
        machine_on(cnc.command())
        answer = ask(client, root, {"id": "a", "command": "rapid_override", "value": 0.25})
        assert answer == {"id": "a", "command": "rapid_override", "ok": True, "result": "done"}
        status = cnc.stat()
        status.poll()
        assert status.rapidrate == 0.25
        client.wait_for(f"{root}/feed/rapid_override", lambda value: value == 0.25)
        answer = ask(client, root, {"id": "b", "command": "mode", "mode": "sideways"})
        assert answer["ok"] is False and "'mode' must be one of" in answer["error"]
        answer = ask(client, root, {"id": "c", "command": "estop"})
        assert answer["ok"] is True
        status.poll()
        assert status.task_state == cnc.STATE_ESTOP
    finally:
        close(client)
        cnc.command().rapidrate(1.0)


def test_commands_are_refused_by_a_broker_that_lets_anyone_in(
    rig: Rig, procs: Processes, tmp_path: Path
) -> None:
    open_broker = start_broker(procs, tmp_path / "open", is_anonymous_allowed=True)
    ini = copy_ini(rig, tmp_path, "COMMANDS = 1", port=open_broker.port)
    procs.python("-m", "cnc", "bridge", "mqtt", str(ini))
    client = subscribe(open_broker.port, f"{ROOT}/#", user=None)
    try:
        client.wait_for(f"{ROOT}/online", lambda online: online is True)
        answer = ask(client, ROOT, {"id": 7, "command": "machine_off"})
        assert answer["ok"] is False
        assert "anonymous" in answer["error"]
    finally:
        close(client)


def bridge_pid(launcher_pid: int) -> int:
    """The MQTT bridge among the launcher's children."""
    for task in Path(f"/proc/{launcher_pid}/task").iterdir():
        for child in (task / "children").read_text().split():
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes().split(b"\0")
            if b"cnc.bridges.mqtt" in cmdline:
                return int(child)
    raise AssertionError("the launcher runs no MQTT bridge")


def test_killing_the_bridge_leaves_the_machine_running(rig: Rig) -> None:
    dashboard = subscribe(rig.broker.port, f"{ROOT}/online")
    try:
        command = cnc.command()
        machine_on(command)
        dashboard.wait_for(f"{ROOT}/online", lambda online: online is True)
        dashboard.seen.clear()
        os.kill(bridge_pid(rig.machine.launcher.pid), signal.SIGKILL)
        # the broker publishes the bridge's will; the launcher starts it again
        dashboard.wait_for(f"{ROOT}/online", lambda online: online is False)
        dashboard.wait_for(f"{ROOT}/online", lambda online: online is True)
        status = cnc.stat()
        status.poll()
        assert status.task_state == cnc.STATE_ON
        assert rig.machine.launcher.poll() is None
        command.mode(cnc.MODE_MDI)
        command.wait_complete()
        command.mdi("G0 Z5")  # (homed or not, task still answers)
        assert command.wait_complete(WAIT_S) in (cnc.RCS_DONE, cnc.RCS_ERROR)
    finally:
        close(dashboard)
