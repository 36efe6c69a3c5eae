"""Fixtures of the bridge tests: a real Mosquitto broker with password authentication on a
free loopback port, an MQTT subscriber, and a machine started by ``cnc run``.

The tests of a module share one machine (its own IPC instance, checked for leftovers once
it has stopped); each module's broker is its own. Without Mosquitto the MQTT tests skip
(scripts/install-mosquitto installs it).
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from cnc.runtime import read_runtime_info
from nml.ipcnames import INSTANCE_ENV, remove_instance_objects
from tests.conftest import Processes

MACHINE = Path(__file__).parents[1] / "halui" / "machine"  # a small XYZ mill with halui
WAIT_S = 60.0  # generous: reached only when something is broken
USERS = {"cnc": "cnc-secret", "operator": "operator-secret"}


def mosquitto() -> str | None:
    return shutil.which("mosquitto") or shutil.which("mosquitto", path="/usr/sbin:/usr/bin")


needs_mosquitto = pytest.mark.skipif(
    mosquitto() is None or shutil.which("mosquitto_passwd") is None,
    reason="no Mosquitto broker (scripts/install-mosquitto)",
)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_for_port(port: int, proc: subprocess.Popen[Any]) -> None:
    deadline = time.monotonic() + WAIT_S
    while True:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.5):
            return
        assert proc.poll() is None, f"the server on port {port} exited: {proc.communicate()}"
        assert time.monotonic() < deadline, f"nothing listens on port {port}"
        time.sleep(0.05)


@dataclass
class Broker:
    port: int
    proc: subprocess.Popen[str]


def start_broker(procs: Processes, folder: Path, *, is_anonymous_allowed: bool = False) -> Broker:
    """Mosquitto on a free loopback port, with USERS in its password file."""
    folder.mkdir(parents=True, exist_ok=True)
    passwords = folder / "passwd"
    passwords.touch(mode=0o600)
    for user, password in USERS.items():
        subprocess.run(["mosquitto_passwd", "-b", str(passwords), user, password], check=True)
    port = free_port()
    conf = folder / "mosquitto.conf"
    lines = [
        f"listener {port} 127.0.0.1",
        f"allow_anonymous {'true' if is_anonymous_allowed else 'false'}",
        f"password_file {passwords}",
        "persistence false",
        "log_dest stderr",
        "log_type error",
    ]
    if os.geteuid() == 0:  # (else it would become user mosquitto, who cannot read our files)
        lines.append("user root")
    conf.write_text("\n".join(lines) + "\n")
    proc = procs.start(mosquitto(), "-c", str(conf))
    wait_for_port(port, proc)
    return Broker(port, proc)


@dataclass
class Subscriber:
    """An MQTT client that keeps every message it receives: (topic, JSON payload, time)."""

    client: Any
    received: queue.Queue[tuple[str, Any, float]] = field(default_factory=queue.Queue)
    seen: list[tuple[str, Any, float]] = field(default_factory=list)
    connect_reason: list[Any] = field(default_factory=list)

    def wait_for(
        self, topic: str, is_wanted: Callable[[Any], bool] = lambda _: True, timeout: float = WAIT_S
    ) -> Any:
        """The payload of the first message on ``topic`` (seen before or arriving) that
        ``is_wanted``."""
        for seen_topic, payload, _ in self.seen:
            if seen_topic == topic and is_wanted(payload):
                return payload
        deadline = time.monotonic() + timeout
        while True:
            try:
                item = self.received.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                last = [p for t, p, _ in self.seen if t == topic][-3:]
                raise AssertionError(f"no wanted message on {topic}; last ones: {last}") from None
            self.seen.append(item)
            if item[0] == topic and is_wanted(item[1]):
                return item[1]

    def publish(self, topic: str, payload: Any) -> None:
        self.client.publish(topic, json.dumps(payload), qos=1).wait_for_publish(WAIT_S)


def subscribe(port: int, topic: str, user: str | None = "operator", password: str | None = None):
    """A connected subscriber of ``topic`` (None if the broker refused the connection)."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    if user is not None:
        client.username_pw_set(user, USERS.get(user) if password is None else password)
    subscriber = Subscriber(client)
    connected = queue.Queue()

    def on_connect(c: Any, _d: Any, _f: Any, reason: Any, _p: Any) -> None:
        if not reason.is_failure:
            c.subscribe(topic, qos=1)
        connected.put(reason)

    def on_message(_c: Any, _d: Any, message: Any) -> None:
        try:
            payload = json.loads(message.payload)
        except ValueError:
            payload = message.payload.decode(errors="replace")
        subscriber.received.put((message.topic, payload, time.monotonic()))

    client.on_connect = on_connect
    client.on_message = on_message
    client.connect("127.0.0.1", port)
    client.loop_start()
    reason = connected.get(timeout=WAIT_S)
    subscriber.connect_reason.append(reason)
    if reason.is_failure:
        client.loop_stop()
        return None
    return subscriber


def close(subscriber: Subscriber | None) -> None:
    if subscriber is not None:
        subscriber.client.disconnect()
        subscriber.client.loop_stop()


@dataclass
class Machine:
    folder: Path
    launcher: subprocess.Popen[str]

    @property
    def ini(self) -> Path:
        return self.folder / "mill.ini"


@contextlib.contextmanager
def shared_instance(name: str) -> Iterator[str]:
    """One IPC instance for a module's machine, checked for leftovers at the end."""
    instance = f"t{os.getpid()}-{name}"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(INSTANCE_ENV, instance)
        yield instance
    leftovers = remove_instance_objects(instance)
    assert not leftovers, f"the machine left IPC objects behind (now removed): {leftovers}"


@contextlib.contextmanager
def running_machine(
    procs: Processes, folder: Path, sections: dict[str, list[str]], hal_lines: list[str] = ()
) -> Iterator[Machine]:
    """The small mill copied to ``folder`` with extra INI sections and HAL lines, started
    headless; stopped (SIGTERM, as Ctrl-C) at the end."""
    shutil.copytree(MACHINE, folder)
    ini = folder / "mill.ini"
    text = ini.read_text()
    for section, lines in sections.items():
        text += f"\n[{section}]\n" + "".join(f"{line}\n" for line in lines)
    ini.write_text(text)
    with (folder / "mill.hal").open("a") as hal:
        hal.write("".join(f"{line}\n" for line in hal_lines))
    launcher = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    try:
        deadline = time.monotonic() + WAIT_S
        while (info := read_runtime_info()) is None or info.pid != launcher.pid:
            assert launcher.poll() is None, launcher.communicate()[1]
            assert time.monotonic() < deadline, "the machine did not come up"
            time.sleep(0.05)
        yield Machine(folder, launcher)
    finally:
        launcher.send_signal(signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            launcher.wait(timeout=30)
