"""The machine status publisher: one MQTT topic tree per machine, so a fleet shares a broker.

``cnc bridge mqtt INI`` (the launcher starts it when ``[MQTT]ENABLE = 1``) attaches to the
machine like any UI (``cnc.stat``, ``cnc.error_channel``) and publishes below
``<[MQTT]TOPIC_PREFIX>/<machine name>/`` (``cnc/mill-1/...``), every payload JSON:

====================== ======== ===================================================
topic                  retained payload
====================== ======== ===================================================
online                 yes      true while the bridge and the controller run (the
                                broker publishes false if the bridge dies: its will)
info                   yes      identification: name, software revision, host, axes...
state                  yes      "ESTOP", "ESTOP_RESET", "OFF", "ON" ("OFFLINE")
estop                  yes      true while in E-stop
mode                   yes      "MANUAL", "AUTO", "MDI"
program/state          yes      "IDLE", "RUNNING", "PAUSED"
program/file           yes      the open program
program/line           yes      the line being executed
position               yes      {"X": ..., "Y": ..., "Z": ...}: machine coordinates, actual
work_position          yes      the same in the active work coordinates
homed                  yes      [true, false, ...] per joint
feed/override          yes      1.0 is 100 %; also feed/rapid_override
feed/velocity          yes      the current velocity, units per minute
spindle/speed          yes      rpm; also spindle/direction (-1, 0, 1), spindle/override
tool                   yes      the tool number in the spindle
alarm                  yes      the last error: {"time", "kind", "text"}
message                no       every operator message (errors, texts, displays)
command/response       no       the answer to each command
====================== ======== ===================================================

A value is published when it changes (polled every ``[MQTT]CYCLE_TIME``), everything again
after a reconnection. Commands: a JSON object on ``<root>/command``, e.g. ``{"id": 1,
"command": "mode", "mode": "MDI"}`` (``COMMANDS`` below lists them), each answered on
``<root>/command/response`` with ``{"id", "command", "ok", "result" | "error"}``. They are
carried out only when ``[MQTT]COMMANDS = 1`` and the broker authenticates every client
(the bridge checks that it refuses an anonymous connection); otherwise each is refused with
the reason. Who may publish on the command topic is the broker's ACL's business.
"""

from __future__ import annotations

import contextlib
import json
import queue
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import paho.mqtt.client as mqtt

import cnc
from cnc.bridges.machine import OFFLINE, MachineView, identification, machine_name
from cnc.ini import IniError
from cnc.inischema import MachineConfig, load_config

COMMAND_WAIT_S = 1.0  # how long a command's answer waits for task to finish it
PROBE_TIMEOUT_S = 5.0  # the anonymous-connection check
MODES = {"MANUAL": cnc.MODE_MANUAL, "AUTO": cnc.MODE_AUTO, "MDI": cnc.MODE_MDI}
# E-stop and abort never wait behind another command
URGENT_COMMANDS = ("estop", "abort")


class CommandError(Exception):
    """A command refused before it reached the controller; the message says why."""


def _number(request: dict[str, Any], name: str) -> float:
    value = request.get(name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CommandError(f"'{name}' must be a number")
    return float(value)


def _text(request: dict[str, Any], name: str) -> str:
    value = request.get(name)
    if not isinstance(value, str) or not value:
        raise CommandError(f"'{name}' must be a non-empty string")
    return value


def _joint(request: dict[str, Any]) -> int:
    value = request.get("joint", -1)
    if isinstance(value, bool) or not isinstance(value, int):
        raise CommandError("'joint' must be an integer (-1: all)")
    return value


def _mode(request: dict[str, Any]) -> int:
    name = str(request.get("mode", "")).upper()
    if name not in MODES:
        raise CommandError(f"'mode' must be one of {', '.join(MODES)}")
    return MODES[name]


# command name -> what it does with a cnc.command and the request's fields
COMMANDS: dict[str, Callable[[cnc.command, dict[str, Any]], None]] = {
    "estop": lambda c, r: c.state(cnc.STATE_ESTOP),
    "estop_reset": lambda c, r: c.state(cnc.STATE_ESTOP_RESET),
    "machine_on": lambda c, r: c.state(cnc.STATE_ON),
    "machine_off": lambda c, r: c.state(cnc.STATE_OFF),
    "abort": lambda c, r: c.abort(),
    "mode": lambda c, r: c.mode(_mode(r)),
    "home": lambda c, r: c.home(_joint(r)),
    "mdi": lambda c, r: c.mdi(_text(r, "line")),
    "program_open": lambda c, r: c.program_open(_text(r, "file")),
    "run": lambda c, r: c.auto(cnc.AUTO_RUN, int(r.get("line", 0))),
    "pause": lambda c, r: c.auto(cnc.AUTO_PAUSE),
    "resume": lambda c, r: c.auto(cnc.AUTO_RESUME),
    "step": lambda c, r: c.auto(cnc.AUTO_STEP),
    "feed_override": lambda c, r: c.feedrate(_number(r, "value")),
    "rapid_override": lambda c, r: c.rapidrate(_number(r, "value")),
    "spindle_override": lambda c, r: c.spindleoverride(_number(r, "value")),
}
RESULTS = {cnc.RCS_DONE: "done", cnc.RCS_ERROR: "error", -1: "running"}


@dataclass(frozen=True)
class MqttSettings:
    broker: str
    port: int
    username: str | None
    password: str | None
    root: str  # <TOPIC_PREFIX>/<machine name>
    cycle_time: float
    is_commands_enabled: bool

    @classmethod
    def from_config(cls, config: MachineConfig) -> MqttSettings:
        prefix = (config.value("MQTT", "TOPIC_PREFIX") or "").strip().strip("/")
        name = machine_name(config.ini, "MQTT")
        return cls(
            broker=config.value("MQTT", "BROKER").strip(),
            port=config.value("MQTT", "PORT"),
            username=config.value("MQTT", "USERNAME") or None,
            password=config.value("MQTT", "PASSWORD") or None,
            root=f"{prefix}/{name}" if prefix else name,
            cycle_time=config.value("MQTT", "CYCLE_TIME"),
            is_commands_enabled=config.value("MQTT", "COMMANDS"),
        )


def new_client(settings: MqttSettings, *, is_anonymous: bool = False) -> mqtt.Client:
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    if settings.username and not is_anonymous:
        client.username_pw_set(settings.username, settings.password)
    return client


def accepts_anonymous(settings: MqttSettings) -> bool | None:
    """Whether the broker lets a client in without a user name: True, False, or None if
    the broker could not be asked (not reachable)."""
    answer: list[bool] = []
    done = threading.Event()
    client = new_client(settings, is_anonymous=True)

    def on_connect(_c: Any, _d: Any, _f: Any, reason: Any, _p: Any) -> None:
        answer.append(not reason.is_failure)
        done.set()

    client.on_connect = on_connect
    try:
        client.connect(settings.broker, settings.port, keepalive=10)
    except OSError:
        return None
    client.loop_start()
    done.wait(PROBE_TIMEOUT_S)
    client.disconnect()
    client.loop_stop()
    return answer[0] if answer else None


class MqttBridge:
    """Publishes one machine's status and carries out its commands."""

    def __init__(self, ini_path: str, config: MachineConfig) -> None:
        self.ini_path = ini_path
        self.settings = MqttSettings.from_config(config)
        self.root = self.settings.root
        self.info = identification(ini_path, config.ini, self.root.rsplit("/", 1)[-1])
        self.view = MachineView(ini_path)
        self.is_stopping = False
        self.is_resync_needed = threading.Event()  # (re)connected: publish everything
        # set once the command topic is subscribed: nothing is published before, so a
        # client that sees online = true knows its commands are heard
        self.is_connected = threading.Event()
        self.is_anonymous_refused: bool | None = None  # what the broker said, once known
        self.commands: dict[bool, queue.Queue[dict[str, Any]]] = {
            is_urgent: queue.Queue() for is_urgent in (True, False)
        }
        self.client = new_client(self.settings)
        self.client.will_set(f"{self.root}/online", "false", qos=1, retain=True)
        self.client.on_connect = self._on_connect
        self.client.on_disconnect = self._on_disconnect
        self.client.on_message = self._on_message

    # ------------------------------------------------------------ the broker's thread
    def _on_connect(self, client: Any, _data: Any, _flags: Any, reason: Any, _p: Any) -> None:
        if reason.is_failure:
            say(f"the broker {self.settings.broker}:{self.settings.port} refused us: {reason}")
            return
        say(f"connected to {self.settings.broker}:{self.settings.port} as {self.root}")
        client.subscribe(f"{self.root}/command", qos=1)
        self.is_resync_needed.set()
        self.is_connected.set()

    def _on_disconnect(self, _c: Any, _d: Any, _f: Any, reason: Any, _p: Any) -> None:
        self.is_connected.clear()
        if not self.is_stopping:
            say(f"disconnected from the broker ({reason}): reconnecting")

    def _on_message(self, _client: Any, _data: Any, message: Any) -> None:
        try:
            request = json.loads(message.payload)
        except (ValueError, UnicodeDecodeError):
            request = None
        if not isinstance(request, dict):
            self._answer({}, error="a command is a JSON object with a 'command' field")
            return
        name = request.get("command")
        self.commands[name in URGENT_COMMANDS].put(request)

    # ------------------------------------------------------------ commands (own threads)
    def _serve_commands(self, is_urgent: bool) -> None:
        command = cnc.command(self.ini_path)
        requests = self.commands[is_urgent]
        while not self.is_stopping:
            try:
                request = requests.get(timeout=0.5)
            except queue.Empty:
                continue
            try:
                result = self._carry_out(command, request)
            except (CommandError, cnc.error, ValueError, TypeError) as exc:
                self._answer(request, error=str(exc))
            else:
                self._answer(request, result=result)

    def refusal(self) -> str | None:
        """Why commands are refused now, or None when they may be carried out."""
        if not self.settings.is_commands_enabled:
            return "commands are disabled ([MQTT]COMMANDS = 0)"
        if self.is_anonymous_refused is None:
            allowed = accepts_anonymous(self.settings)
            self.is_anonymous_refused = None if allowed is None else not allowed
        if self.is_anonymous_refused is None:
            return "could not check that the broker refuses anonymous clients"
        if not self.is_anonymous_refused:
            return "the broker accepts anonymous clients: commands need an authenticating broker"
        return None

    def _carry_out(self, command: cnc.command, request: dict[str, Any]) -> str:
        name = request.get("command")
        action = COMMANDS.get(name) if isinstance(name, str) else None
        if action is None:
            raise CommandError(f"unknown command {name!r}: one of {', '.join(COMMANDS)}")
        why = self.refusal()
        if why is not None:
            raise CommandError(why)
        action(command, request)
        return RESULTS.get(command.wait_complete(COMMAND_WAIT_S), "running")

    def _answer(self, request: dict[str, Any], **outcome: str) -> None:
        answer = {"id": request.get("id"), "command": request.get("command")}
        answer["ok"] = "error" not in outcome
        answer.update(outcome)
        self.client.publish(f"{self.root}/command/response", json.dumps(answer), qos=1)

    # ------------------------------------------------------------ the status loop
    def publish(self, name: str, value: Any, *, retain: bool = True, qos: int = 1) -> None:
        self.client.publish(f"{self.root}/{name}", json.dumps(value), qos=qos, retain=retain)

    def run(self) -> None:
        self.client.connect_async(self.settings.broker, self.settings.port, keepalive=30)
        self.client.loop_start()
        for is_urgent in (True, False):
            threading.Thread(target=self._serve_commands, args=(is_urgent,), daemon=True).start()
        is_online = None
        due = time.monotonic()
        while not self.is_stopping:
            if not self.is_connected.wait(self.settings.cycle_time):
                continue  # (what changes meanwhile is published in full on connecting)
            changed = self.view.poll()
            if self.is_resync_needed.is_set():
                self.is_resync_needed.clear()
                self.publish("info", self.info)
                changed = dict(self.view.values)
                is_online = None
            if (self.view.values.get("state") != OFFLINE) != is_online:
                is_online = self.view.values.get("state") != OFFLINE
                self.publish("online", is_online)
            for name, value in changed.items():
                self.publish(name, value, qos=0 if "position" in name else 1)
            for message in self.view.messages():
                self.publish("message", message.as_dict(), retain=False)
                if message.is_alarm:
                    self.publish("alarm", message.as_dict())
            due = max(due + self.settings.cycle_time, time.monotonic())
            time.sleep(max(0.0, due - time.monotonic()))

    def stop(self) -> None:
        """Say offline (the retained value), then leave the broker."""
        self.is_stopping = True
        info = self.client.publish(f"{self.root}/online", "false", qos=1, retain=True)
        if self.client.is_connected():
            with contextlib.suppress(RuntimeError, ValueError):  # (lost meanwhile)
                info.wait_for_publish(2.0)
        self.client.disconnect()
        self.client.loop_stop()
        self.view.close()


def say(text: str) -> None:
    print(f"cnc bridge mqtt: {text}", file=sys.stderr, flush=True)


def main(argv: list[str]) -> int:
    if len(argv) != 1 or argv[0].startswith("-"):
        print("usage: cnc bridge mqtt INI", file=sys.stderr)
        return 2
    try:
        bridge = MqttBridge(argv[0], load_config(argv[0]))
    except IniError as exc:  # (cnc run would not start either)
        say(str(exc))
        return 1

    def on_signal(_signum: int, _frame: object) -> None:
        bridge.is_stopping = True

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    try:
        bridge.run()
    finally:
        bridge.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
