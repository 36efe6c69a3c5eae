"""The OPC UA bridge end to end: a machine started by ``cnc run`` with ``[OPCUA]ENABLE = 1``
and real asyncua clients, anonymous and authenticated, plain and over a signed and
encrypted channel.

One machine serves the module (each test brings it to the state it needs).
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from collections.abc import Awaitable, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from asyncua import Client, ua

import cnc
from tests.bridges.conftest import WAIT_S, Machine, free_port, running_machine, shared_instance
from tests.bridges.test_mqtt import home_and_move, machine_on
from tests.conftest import Processes

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]  # (a loaded computer)
NAME = "mill-1"
USER, PASSWORD = "mes", "mes-secret"
START_S = 3 * WAIT_S  # for the server to listen


@dataclass
class Rig:
    machine: Machine
    url: str


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Rig]:
    folder = tmp_path_factory.mktemp("opcua")
    procs = Processes()
    port = free_port()
    section = [
        "ENABLE = 1",
        f"PORT = {port}",
        f"MACHINE_NAME = {NAME}",
        f"USERNAME = {USER}",
        f"PASSWORD = {PASSWORD}",
        "CYCLE_TIME = 0.05",
    ]
    try:
        with (
            shared_instance("opcua"),
            running_machine(procs, folder / "machine", {"OPCUA": section}) as machine,
        ):
            yield Rig(machine, f"opc.tcp://127.0.0.1:{port}/cnc/")
    finally:
        procs.kill_all()


@pytest.fixture(autouse=True)
def cnc_instance(rig: Rig) -> str:
    """Replaces tests/conftest.py's per-test instance: the tests share the machine's."""
    return os.environ["CNC_INSTANCE"]


def run(coroutine: Awaitable[Any]) -> Any:
    return asyncio.run(asyncio.wait_for(coroutine, START_S + WAIT_S * 2))


async def connect(url: str, user: str | None = None, password: str | None = None) -> Client:
    """A connected client; the server may still be starting (or starting again: asyncua
    builds its address space in seconds of CPU, minutes on a loaded computer)."""
    deadline = time.monotonic() + START_S
    while True:
        client = Client(url, timeout=WAIT_S)
        if user is not None:
            client.set_user(user)
            client.set_password(password)
        try:
            await client.connect()
            return client
        except (TimeoutError, OSError):
            assert time.monotonic() < deadline, f"no OPC UA server at {url}"
            await asyncio.sleep(0.2)


async def node(client: Client, path: str) -> Any:
    ns = await client.get_namespace_index("urn:cnc:machine-tool")
    return client.get_node(ua.NodeId(f"{NAME}.{path}", ns))


async def until(client: Client, path: str, is_wanted: Callable[[Any], bool]) -> Any:
    """The value of ``path`` once ``is_wanted``."""
    variable = await node(client, path)
    deadline = time.monotonic() + WAIT_S
    while True:
        value = await variable.read_value()
        if is_wanted(value):
            return value
        assert time.monotonic() < deadline, f"{path} is still {value!r}"
        await asyncio.sleep(0.05)


class Events:
    """An event subscription's handler: keeps every event."""

    def __init__(self) -> None:
        self.received: asyncio.Queue[Any] = asyncio.Queue()

    def event_notification(self, event: Any) -> None:
        self.received.put_nowait(event)

    async def wait_for(self, is_wanted: Callable[[Any], bool]) -> Any:
        while True:
            event = await self.received.get()
            if is_wanted(event):
                return event


def test_identification_position_state_and_alarms_arrive(rig: Rig) -> None:
    async def scenario() -> None:
        client = await connect(rig.url)  # anonymous: may read and subscribe
        try:
            identification = await node(client, "Identification.Model")
            assert await identification.read_value() == "test-mill"
            events = Events()
            subscription = await client.create_subscription(50, events)
            await subscription.subscribe_events(await node(client, "Notification.Messages"))

            command = cnc.command()
            await asyncio.to_thread(home_and_move, command, "G0 X10 Y-5")
            await until(client, "Monitoring.Axes.X.ActualPosition", lambda x: x == 10.0)
            await until(client, "Monitoring.Axes.Y.ActualPosition", lambda y: y == -5.0)
            await until(client, "Monitoring.Axes.Z.IsHomed", lambda homed: homed is True)
            await until(client, "Monitoring.MachineTool.TaskState", lambda s: s == "ON")
            await until(client, "Monitoring.MachineTool.EmergencyStop", lambda e: e is False)
            await until(client, "Monitoring.Channel_1.ChannelMode", lambda mode: mode == 1)
            await until(client, "Monitoring.Channel_1.ChannelState", lambda state: state == 2)
            await until(client, "Production.ActiveProgram.State", lambda s: s == "Ended")
            await until(client, "Equipment.Tools.ToolInSpindle", lambda tool: tool == 0)

            command.error_msg("spindle drive fault")
            alarm = await events.wait_for(lambda e: e.Message.Text == "spindle drive fault")
            assert alarm.Severity == 700

            command.state(cnc.STATE_ESTOP)
            await until(client, "Monitoring.MachineTool.EmergencyStop", lambda e: e is True)
            await until(client, "MachineryItemState.CurrentState", lambda s: s == "OutOfService")
            await subscription.delete()
        finally:
            await client.disconnect()

    run(scenario())


def test_anonymous_writes_and_wrong_passwords_are_refused(rig: Rig) -> None:
    async def scenario() -> None:
        client = await connect(rig.url)
        try:
            override = await node(client, "Monitoring.Channel_1.FeedOverride")
            with pytest.raises(ua.uaerrors.BadUserAccessDenied):
                await override.write_value(ua.Variant(30.0, ua.VariantType.Double))
        finally:
            await client.disconnect()
        status = cnc.stat()
        status.poll()
        assert status.feedrate == 1.0
        impostor = Client(rig.url, timeout=WAIT_S)
        impostor.set_user(USER)
        impostor.set_password("guess")
        with pytest.raises(ua.uaerrors.BadUserAccessDenied):
            await impostor.connect()
        await impostor.disconnect()

    run(scenario())


def client_certificate(folder: Path) -> tuple[Path, Path]:
    from asyncua.crypto.cert_gen import (
        dump_private_key_as_pem,
        generate_private_key,
        generate_self_signed_app_certificate,
    )
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import Encoding
    from cryptography.x509.oid import ExtendedKeyUsageOID

    key = generate_private_key()
    uri = "urn:cnc:test-client"
    cert = generate_self_signed_app_certificate(
        key, uri, {}, [x509.UniformResourceIdentifier(uri)], [ExtendedKeyUsageOID.CLIENT_AUTH]
    )
    (folder / "client-key.pem").write_bytes(dump_private_key_as_pem(key))
    (folder / "client-cert.der").write_bytes(cert.public_bytes(Encoding.DER))
    return folder / "client-cert.der", folder / "client-key.pem"


def test_a_user_sets_the_feed_override_over_an_encrypted_channel(rig: Rig, tmp_path: Path) -> None:
    cert, key = client_certificate(tmp_path)

    async def scenario() -> None:
        await (await connect(rig.url)).disconnect()  # the server is up
        client = Client(rig.url, timeout=WAIT_S)
        client.application_uri = "urn:cnc:test-client"
        await client.set_security_string(f"Basic256Sha256,SignAndEncrypt,{cert},{key}")
        client.set_user(USER)
        client.set_password(PASSWORD)
        await client.connect()
        try:
            assert client.security_policy.Mode == ua.MessageSecurityMode.SignAndEncrypt
            override = await node(client, "Monitoring.Channel_1.FeedOverride")
            await override.write_value(ua.Variant(50.0, ua.VariantType.Double))
            status = cnc.stat()
            deadline = time.monotonic() + WAIT_S
            status.poll()
            while status.feedrate != 0.5:
                assert time.monotonic() < deadline, f"feed override {status.feedrate}"
                await asyncio.sleep(0.05)
                status.poll()
            await until(client, "Monitoring.Channel_1.FeedOverride", lambda v: v == 50.0)
            await override.write_value(ua.Variant(100.0, ua.VariantType.Double))
        finally:
            await client.disconnect()

    machine_on(cnc.command())
    run(scenario())


def bridge_pid(launcher_pid: int) -> int:
    for task in Path(f"/proc/{launcher_pid}/task").iterdir():
        for child in (task / "children").read_text().split():
            if b"cnc.bridges.opcua" in Path(f"/proc/{child}/cmdline").read_bytes():
                return int(child)
    raise AssertionError("the launcher runs no OPC UA bridge")


def test_killing_the_bridge_leaves_the_machine_running(rig: Rig) -> None:
    machine_on(cnc.command())
    os.kill(bridge_pid(rig.machine.launcher.pid), signal.SIGKILL)
    status = cnc.stat()
    status.poll()
    assert status.task_state == cnc.STATE_ON
    assert rig.machine.launcher.poll() is None

    async def scenario() -> None:  # the launcher starts it again
        client = await connect(rig.url)
        try:
            await until(client, "Monitoring.MachineTool.TaskState", lambda s: s == "ON")
        finally:
            await client.disconnect()

    run(scenario())
    status.poll()
    assert status.task_state == cnc.STATE_ON
