"""An OPC UA server for one machine, shaped as OPC 40501-1 (OPC UA for Machine Tools) where
it applies.

``cnc bridge opcua INI`` (the launcher starts it when ``[OPCUA]ENABLE = 1``) serves
``opc.tcp://<HOST>:<PORT>/cnc/`` with this address space, in the namespace
``urn:cnc:machine-tool`` (NodeIds are strings, ``<name>.Monitoring.Channel_1.FeedOverride``):

    Objects/Machines/<name>/
        Identification/       Manufacturer, Model ([EMC]MACHINE), SoftwareRevision,
                              ProductInstanceUri, Location (host), ComponentName
        MachineryItemState/CurrentState       NotAvailable, OutOfService, NotExecuting,
                                              Executing (OPC 40001-1's states)
        MachineryOperationMode/CurrentState   Setup (MANUAL, MDI), Processing (AUTO)
        Monitoring/
            MachineTool/      EmergencyStop, OperationMode ("MANUAL", "AUTO", "MDI"),
                              TaskState ("ESTOP", "ESTOP_RESET", "OFF", "ON", "OFFLINE")
            Channel_1/        ChannelState (0 Active, 1 Interrupted, 2 Reset),
                              ChannelMode (0 Automatic, 1 MdaMdi, 2 JogManual),
                              FeedOverride %, RapidOverride % (writable), FeedRate
            Spindle_1/        IsRotating, Override % (writable), RotationSpeed (rpm)
            Axes/<L>/         ActualPosition (machine), WorkPosition, IsHomed
        Production/ActiveProgram/   Name, State (Running, Interrupted, Ended), CurrentLine
        Equipment/Tools/ToolInSpindle
        Notification/Messages       event notifier: every operator message as a
                                    CncMessageEventType event (Severity 700 error, 500
                                    display, 300 text; also emitted by the Server object)

Values follow the machine on change (polled every ``[OPCUA]CYCLE_TIME``). Security: the
policies listed in ``[OPCUA]SECURITY`` (asyncua's: None, Basic256Sha256_Sign,
Basic256Sha256_SignAndEncrypt, Aes128Sha256RsaOaep_*, Aes256Sha256RsaPss_*), with the
certificate and key named by ``CERTIFICATE``/``PRIVATE_KEY`` or made once next to the INI;
users: the one ``USERNAME``/``PASSWORD`` may write the overrides; anonymous sessions
(``ALLOW_ANONYMOUS``) may browse, read and subscribe, never write.

Not modelled: OPC 40501's types themselves (the companion nodesets are not loaded; the
names and enumeration values are the specification's), jobs, part counters, stack lights.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import logging
import signal
import socket
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.common.callback import CallbackType
from asyncua.crypto.permission_rules import USER_TYPES, PermissionRuleset, User, UserRole
from asyncua.server.user_managers import UserManager

import cnc
from cnc.atomicfile import atomic_write_text
from cnc.bridges.machine import OFFLINE, MachineView, identification, machine_name
from cnc.ini import IniError
from cnc.inischema import MachineConfig, load_config
from cnc.ui import formatting as fmt

NAMESPACE = "urn:cnc:machine-tool"
SEVERITIES = {"error": 700, "display": 500, "text": 300}
CHANNEL_STATES = {"RUNNING": 0, "PAUSED": 1, "IDLE": 2}  # OPC 40501 ChannelState
CHANNEL_MODES = {"AUTO": 0, "MDI": 1, "MANUAL": 2}  # OPC 40501 ChannelMode (7: Other)
PROGRAM_STATES = {"RUNNING": "Running", "PAUSED": "Interrupted", "IDLE": "Ended"}
# anonymous sessions: everything a user may do but write, call methods or change history
READ_ONLY_TYPES = set(USER_TYPES) - {
    ua.ObjectIds.WriteRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CallRequest_Encoding_DefaultBinary,
}


class OpcuaConfigError(Exception):
    """A bad [OPCUA] value; the message says which and why."""


@dataclass(frozen=True)
class OpcuaSettings:
    host: str
    port: int
    name: str
    username: str | None
    password: str | None
    is_anonymous_allowed: bool
    policies: list[ua.SecurityPolicyType]
    certificate: Path | None
    private_key: Path | None
    cycle_time: float

    @classmethod
    def from_config(cls, config: MachineConfig, folder: Path) -> OpcuaSettings:
        policies = []
        for word in (config.value("OPCUA", "SECURITY") or "").split():
            name = "NoSecurity" if word.lower() == "none" else word
            if name not in ua.SecurityPolicyType.__members__:
                allowed = ["None", *list(ua.SecurityPolicyType.__members__)[1:]]
                raise OpcuaConfigError(
                    f"[OPCUA]SECURITY: unknown policy {word!r}; allowed: {' '.join(allowed)}"
                )
            policies.append(ua.SecurityPolicyType[name])
        if not policies:
            raise OpcuaConfigError("[OPCUA]SECURITY: no security policy")

        def file(key: str) -> Path | None:
            value = config.value("OPCUA", key)
            return (folder / Path(value).expanduser()) if value else None

        return cls(
            host=config.value("OPCUA", "HOST").strip(),
            port=config.value("OPCUA", "PORT"),
            name=machine_name(config.ini, "OPCUA"),
            username=config.value("OPCUA", "USERNAME") or None,
            password=config.value("OPCUA", "PASSWORD") or "",
            is_anonymous_allowed=config.value("OPCUA", "ALLOW_ANONYMOUS"),
            policies=policies,
            certificate=file("CERTIFICATE"),
            private_key=file("PRIVATE_KEY"),
            cycle_time=config.value("OPCUA", "CYCLE_TIME"),
        )


class MachineUsers(UserManager):
    """The one configured user (role User: may write what is writable), anonymous sessions
    as read-only when allowed; anything else is refused."""

    def __init__(self, settings: OpcuaSettings) -> None:
        self.settings = settings

    def get_user(
        self,
        iserver: Any,
        username: str | None = None,
        password: str | None = None,
        certificate: Any = None,
    ) -> User | None:
        if username is None:
            return User(role=UserRole.Anonymous) if self.settings.is_anonymous_allowed else None
        expected = self.settings.username
        is_user = expected is not None and hmac.compare_digest(username, expected)
        is_password = hmac.compare_digest(password or "", self.settings.password or "")
        return User(role=UserRole.User, name=username) if is_user and is_password else None


class MachineRules(PermissionRuleset):
    """Which requests each role may make: anonymous ones read, users also write."""

    def __init__(self) -> None:
        self.allowed = {
            UserRole.Admin: {ua.NodeId(t) for t in USER_TYPES},
            UserRole.User: {ua.NodeId(t) for t in USER_TYPES},
            UserRole.Anonymous: {ua.NodeId(t) for t in READ_ONLY_TYPES},
        }

    def check_validity(self, user: User, action_type_id: ua.NodeId, body: Any) -> bool:
        return action_type_id in self.allowed[user.role]


def certificate_files(settings: OpcuaSettings, folder: Path) -> tuple[Path, Path]:
    """The server's certificate and key: the INI's, else made once (PEM) next to the INI."""
    if settings.certificate and settings.private_key:
        return settings.certificate, settings.private_key
    from asyncua.crypto.cert_gen import (
        dump_private_key_as_pem,
        generate_private_key,
        generate_self_signed_app_certificate,
    )
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import Encoding
    from cryptography.x509.oid import ExtendedKeyUsageOID

    cert = folder / f"opcua-{settings.name}-cert.pem"
    key = folder / f"opcua-{settings.name}-key.pem"
    if cert.exists() and key.exists():
        return cert, key
    say(f"making a self-signed certificate for the secure policies: {cert}")
    private = generate_private_key()
    host = socket.gethostname()
    certificate = generate_self_signed_app_certificate(
        private,
        f"{NAMESPACE}:{settings.name}",
        {"organizationName": "cnc"},
        [x509.UniformResourceIdentifier(application_uri(settings)), x509.DNSName(host)],
        extended=[ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH],
        days=3650,
    )
    atomic_write_text(key, dump_private_key_as_pem(private).decode())
    key.chmod(0o600)
    atomic_write_text(cert, certificate.public_bytes(Encoding.PEM).decode())
    return cert, key


def application_uri(settings: OpcuaSettings) -> str:
    return f"{NAMESPACE}:{settings.name}"


class OpcuaBridge:
    """The server, its nodes, and the loop that keeps them in step with the machine."""

    def __init__(self, ini_path: str, config: MachineConfig) -> None:
        self.ini_path = ini_path
        self.folder = Path(ini_path).resolve().parent
        self.settings = OpcuaSettings.from_config(config, self.folder)
        self.info = identification(ini_path, config.ini, self.settings.name)
        self.view = MachineView(ini_path)
        self.server = Server(user_manager=MachineUsers(self.settings))
        self.nodes: dict[str, Any] = {}  # our variable name -> node
        self.writable: dict[ua.NodeId, str] = {}  # node -> the override it sets
        self.command: cnc.command | None = None
        self.events: list[Any] = []  # event generators: Messages, Server
        self.stopping = asyncio.Event()

    # ------------------------------------------------------------ address space
    async def setup(self) -> None:
        settings = self.settings
        server = self.server
        await server.init()
        server.set_endpoint(f"opc.tcp://{settings.host}:{settings.port}/cnc/")
        server.set_server_name(f"cnc {settings.name}")
        await server.set_application_uri(application_uri(settings))
        server.set_security_policy(settings.policies, permission_ruleset=MachineRules())
        tokens = [ua.UserNameIdentityToken]
        if settings.is_anonymous_allowed:
            tokens.append(ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)
        if any(p != ua.SecurityPolicyType.NoSecurity for p in settings.policies):
            cert, key = certificate_files(settings, self.folder)
            await server.load_certificate(str(cert))
            await server.load_private_key(str(key))
        self.ns = await server.register_namespace(NAMESPACE)
        machines = await server.nodes.objects.add_folder(self._id("Machines"), "Machines")
        machine = await machines.add_object(self._id(settings.name), settings.name)
        self.machine = machine
        await self._identification(machine)
        await self._state_machines(machine)
        await self._monitoring(machine)
        production = await self._object(machine, "Production")
        program = await self._object(production, "ActiveProgram")
        await self._variable(program, "program/file", "Name", "", ua.VariantType.String)
        await self._variable(program, "program/state", "State", "Ended", ua.VariantType.String)
        await self._variable(program, "program/line", "CurrentLine", 0, ua.VariantType.Int32)
        equipment = await self._object(machine, "Equipment")
        tools = await self._object(equipment, "Tools")
        await self._variable(tools, "tool", "ToolInSpindle", 0, ua.VariantType.Int32)
        notification = await self._object(machine, "Notification")
        messages = await self._object(notification, "Messages")
        await messages.set_event_notifier([ua.EventNotifier.SubscribeToEvents])
        event_type = await server.create_custom_event_type(
            self.ns, "CncMessageEventType", ua.ObjectIds.BaseEventType,
            [("Kind", ua.VariantType.String)],
        )  # fmt: skip
        for emitter in (messages.nodeid, ua.ObjectIds.Server):
            self.events.append(await server.get_event_generator(event_type, emitter))
        server.subscribe_server_callback(CallbackType.PostWrite, self._on_write)

    def _id(self, path: str) -> ua.NodeId:
        return ua.NodeId(path, self.ns)

    async def _object(self, parent: Any, name: str) -> Any:
        return await parent.add_object(self._id(f"{parent.nodeid.Identifier}.{name}"), name)

    async def _variable(
        self, parent: Any, key: str, name: str, value: Any, kind: ua.VariantType
    ) -> Any:
        node = await parent.add_variable(
            self._id(f"{parent.nodeid.Identifier}.{name}"), name, ua.Variant(value, kind)
        )
        self.nodes[key] = (node, kind)
        return node

    async def _identification(self, machine: Any) -> None:
        info = self.info
        identification_node = await self._object(machine, "Identification")
        for name, value in (
            ("Manufacturer", info["manufacturer"]),
            ("Model", info["machine"] or info["name"]),
            ("ComponentName", info["name"]),
            ("SoftwareRevision", info["software_revision"]),
            ("ProductInstanceUri", application_uri(self.settings)),
            ("Location", info["host"]),
            ("Coordinates", info["coordinates"]),
            ("LinearUnits", info["linear_units"]),
        ):
            await identification_node.add_property(
                self._id(f"{identification_node.nodeid.Identifier}.{name}"),
                name,
                ua.Variant(value, ua.VariantType.String),
            )

    async def _state_machines(self, machine: Any) -> None:
        item = await self._object(machine, "MachineryItemState")
        await self._variable(item, "item_state", "CurrentState", "NotAvailable", STRING)
        mode = await self._object(machine, "MachineryOperationMode")
        await self._variable(mode, "operation_mode", "CurrentState", "Setup", STRING)

    async def _monitoring(self, machine: Any) -> None:
        monitoring = await self._object(machine, "Monitoring")
        tool = await self._object(monitoring, "MachineTool")
        await self._variable(tool, "estop", "EmergencyStop", True, ua.VariantType.Boolean)
        await self._variable(tool, "mode", "OperationMode", "MANUAL", STRING)
        await self._variable(tool, "state", "TaskState", OFFLINE, STRING)
        channel = await self._object(monitoring, "Channel_1")
        await self._variable(channel, "channel_state", "ChannelState", 2, ua.VariantType.Int32)
        await self._variable(channel, "channel_mode", "ChannelMode", 2, ua.VariantType.Int32)
        for key, name in (
            ("feed/override", "FeedOverride"),
            ("feed/rapid_override", "RapidOverride"),
        ):
            await self._override(channel, key, name)
        await self._variable(channel, "feed/velocity", "FeedRate", 0.0, DOUBLE)
        spindle = await self._object(monitoring, "Spindle_1")
        await self._variable(spindle, "spindle/is_rotating", "IsRotating", False, BOOLEAN)
        await self._override(spindle, "spindle/override", "Override")
        await self._variable(spindle, "spindle/speed", "RotationSpeed", 0.0, DOUBLE)
        axes = await self._object(monitoring, "Axes")
        for index, letter in enumerate(self.info["coordinates"] or "XYZ"):
            axis = await self._object(axes, letter)
            await self._variable(axis, f"position/{letter}", "ActualPosition", 0.0, DOUBLE)
            await self._variable(axis, f"work_position/{letter}", "WorkPosition", 0.0, DOUBLE)
            await self._variable(axis, f"homed/{index}", "IsHomed", False, BOOLEAN)

    async def _override(self, parent: Any, key: str, name: str) -> None:
        """An override in percent, which an authenticated user may write."""
        node = await self._variable(parent, key, name, 100.0, DOUBLE)
        await node.set_writable()
        self.writable[node.nodeid] = key

    # ------------------------------------------------------------ machine -> nodes
    def node_values(self, changed: dict[str, Any]) -> dict[str, Any]:
        """Our variables' new values from the machine's changed values."""
        values: dict[str, Any] = {}
        for key, value in changed.items():
            if key in ("position", "work_position"):
                values.update({f"{key}/{letter}": v for letter, v in value.items()})
            elif key == "homed":
                values.update({f"homed/{i}": bool(h) for i, h in enumerate(value)})
            elif key in ("feed/override", "feed/rapid_override", "spindle/override"):
                values[key] = None if value is None else round(value * 100.0, 4)
            elif key == "program/state":
                values[key] = PROGRAM_STATES.get(value, "Ended")
                values["channel_state"] = CHANNEL_STATES.get(value, 2)
            elif key == "mode":
                values[key] = value
                values["channel_mode"] = CHANNEL_MODES.get(value, 7)
                values["operation_mode"] = "Processing" if value == "AUTO" else "Setup"
            elif key == "spindle/speed":
                values[key] = value
                values["spindle/is_rotating"] = bool(value)
            else:
                values[key] = value
        state = self.view.values
        if {"state", "program/state"} & changed.keys():
            values["item_state"] = item_state(state.get("state"), state.get("program/state"))
        return values

    async def update(self, changed: dict[str, Any]) -> None:
        for key, value in self.node_values(changed).items():
            found = self.nodes.get(key)
            if found is None or value is None:
                continue
            node, kind = found
            await node.write_value(ua.Variant(value, kind))

    async def publish_messages(self) -> None:
        for message in self.view.messages():
            for generator in self.events:
                generator.event.Severity = SEVERITIES.get(message.kind, 700)
                generator.event.Kind = message.kind
                await generator.trigger(message=message.text)

    # ------------------------------------------------------------ clients -> machine
    async def _on_write(self, event: Any, _dispatcher: Any) -> None:
        """A client's accepted write of an override: carried out on the machine.

        The bridge's own writes (the machine's values, each poll) call this too; they must
        never go back to the machine: a poll that still saw the old override would undo
        the client's."""
        if not event.is_external:
            return
        for write, result in zip(
            event.request_params.NodesToWrite, event.response_params, strict=False
        ):
            key = self.writable.get(write.NodeId)
            if key is None or not result.is_good():
                continue
            percent = float(write.Value.Value.Value)
            loop = asyncio.get_running_loop()
            await loop.run_in_executor(None, self._set_override, key, percent / 100.0)
            # the machine's value (task may clamp it) comes back with the next poll
            self.view.values.pop(key, None)

    def _set_override(self, key: str, scale: float) -> None:
        if self.command is None:
            self.command = cnc.command(self.ini_path)
        try:
            if key == "feed/override":
                self.command.feedrate(scale)
            elif key == "feed/rapid_override":
                self.command.rapidrate(scale)
            else:
                self.command.spindleoverride(scale)
        except (cnc.error, ValueError) as exc:
            say(f"cannot set {key}: {exc}")

    # ------------------------------------------------------------ running
    async def run(self) -> None:
        await self.setup()
        async with self.server:
            endpoint = f"opc.tcp://{self.settings.host}:{self.settings.port}/cnc/"
            say(f"serving {self.settings.name} at {endpoint}")
            loop = asyncio.get_running_loop()
            for signum in (signal.SIGTERM, signal.SIGINT):
                loop.add_signal_handler(signum, self.stopping.set)
            while not self.stopping.is_set():
                await self.update(self.view.poll())
                await self.publish_messages()
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self.stopping.wait(), self.settings.cycle_time)
        self.view.close()


STRING, DOUBLE, BOOLEAN = ua.VariantType.String, ua.VariantType.Double, ua.VariantType.Boolean


def item_state(state: str | None, program: str | None) -> str:
    """OPC 40001-1's MachineryItemState from the task state and the program's."""
    if state in (None, OFFLINE):
        return "NotAvailable"
    if state == fmt.TASK_STATES[cnc.STATE_ESTOP]:
        return "OutOfService"
    return "Executing" if state == "ON" and program == "RUNNING" else "NotExecuting"


def say(text: str) -> None:
    print(f"cnc bridge opcua: {text}", file=sys.stderr, flush=True)


def main(argv: list[str]) -> int:
    if len(argv) != 1 or argv[0].startswith("-"):
        print("usage: cnc bridge opcua INI", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.ERROR)  # asyncua's INFO lines are for debugging it
    try:
        bridge = OpcuaBridge(argv[0], load_config(argv[0]))
    except (OpcuaConfigError, IniError) as exc:  # (IniError: cnc run would not start either)
        say(str(exc))
        return 1
    asyncio.run(bridge.run())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
