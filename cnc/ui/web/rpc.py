"""The public API, version 1: JSON-RPC 2.0 over the websocket ``/api/v1/ws`` and over HTTP
``POST /api/v1/rpc`` (API.md documents it method by method; the page uses it too).

``METHODS`` is the API: every method's scope (apikeys.py: read, operate, configure), its
parameters and what it does. A method with a ``command`` is one of the controller's
commands and runs through ``Hub.dispatch`` (hub.py, commands.py: the same path the page's
buttons take, stops never queued); the others are the API's own services (status and
subscriptions, events, files, tools, offsets), answered here.

``Rpc.handle(client, text)`` takes one websocket message or HTTP body (a call or a batch)
and returns the reply text (None when there is nothing to answer: notifications only).
Errors are JSON-RPC's (-32700 parse error, -32600 invalid request, -32601 method not
found, -32602 invalid params, -32603 internal error) and the API's: -32000 refused (the
controller's or the server's reason in ``message``; ``data.is_reported`` when the error
channel said it already), -32001 forbidden (the key's scopes do not allow the method).

Server pushes are notifications ``{"jsonrpc": "2.0", "method": "notify.KIND", "params"}``
(``notification``): ``notify.status`` carries the subscribed status fields that changed.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from cnc.apikeys import CONFIGURE, OPERATE, READ
from cnc.ui.web.commands import CommandError
from nml.commands import Handlers, Refused, handler, internal_error

if TYPE_CHECKING:
    from cnc.ui.web.hub import Client, Hub

API_VERSION = "1.0"  # major.minor: the major is the URL's v1; minors only add
PARSE_ERROR, INVALID_REQUEST, METHOD_NOT_FOUND = -32700, -32600, -32601
INVALID_PARAMS, INTERNAL_ERROR = -32602, -32603
REFUSED, FORBIDDEN = -32000, -32001
# Event kinds a client may subscribe to (events.subscribe), and what each carries.
EVENTS = {
    "notice": "operator messages: the error channel, one notice per event",
    "history": "the MDI history after each MDI line",
    "program": "the open program's analysis: preview points, load error, time estimate",
    "jobs": "the run history, after each run",
    "probe": "a probing helper's steps and result",
    "dialog": "[DISPLAY] MESSAGE_* dialogs opening and closing (dialog, dialog_close)",
}
# A message type -> the event kind it belongs to
EVENT_OF_TYPE = {kind: kind for kind in EVENTS} | {"dialog_close": "dialog"}


class RpcError(Exception):
    def __init__(self, code: int, message: str, data: Any = None) -> None:
        super().__init__(message)
        self.code, self.message, self.data = code, message, data


# ------------------------------------------------------------------ the method table
KINDS: dict[str, Callable[[Any], bool]] = {
    "bool": lambda v: isinstance(v, bool),
    "int": lambda v: isinstance(v, int) and not isinstance(v, bool),
    # a number: JSON's, or text with ',' or '.' as decimal separator (GUI-003)
    "number": lambda v: isinstance(v, int | float | str) and not isinstance(v, bool),
    "text": lambda v: isinstance(v, str),
    "texts": lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
    "object": lambda v: isinstance(v, dict),
}


@dataclass(frozen=True)
class Param:
    kind: str  # a key of KINDS
    is_required: bool = False


@dataclass(frozen=True)
class Method:
    scope: str
    summary: str
    params: dict[str, Param] = field(default_factory=dict)
    command: str | None = None  # the hub's command (commands.py @handler, hub handlers)
    needs_socket: bool = False  # only over the websocket (subscriptions, jog leases)


def _req(kind: str) -> Param:
    return Param(kind, True)


def _opt(kind: str) -> Param:
    return Param(kind)


def _command(scope: str, summary: str, command: str, /, **params: Param) -> Method:
    return Method(scope, summary, params, command=command)


ON = {"on": _req("bool")}
PERCENT = {"percent": _req("number")}
METHODS: dict[str, Method] = {
    # ---------------------------------------------------------------- the API itself
    "api.version": Method(READ, "the API's version, and the server's"),
    "api.methods": Method(READ, "every method: its scope, parameters and summary"),
    "api.identity": Method(READ, "who the caller is: the key's name and scopes"),
    # ---------------------------------------------------------------- status
    "status.get": Method(READ, "the status fields named (all if none)", {"fields": _opt("texts")}),
    "status.subscribe": Method(
        READ,
        "the fields named (all if none) now, then notify.status with those that change; "
        "replaces an earlier subscription",
        {"fields": _opt("texts")},
        needs_socket=True,
    ),
    "status.unsubscribe": Method(READ, "no more notify.status", needs_socket=True),
    "events.subscribe": Method(
        READ,
        "notify.KIND for these event kinds (all if none; see EVENTS); the current state of "
        "each (run history, open program, probing, open dialogs) is sent at once",
        {"events": _opt("texts")},
        needs_socket=True,
    ),
    "events.unsubscribe": Method(READ, "no more event notifications", needs_socket=True),
    "page.config": Method(READ, "what the operator page offers, from the INI"),
    # ---------------------------------------------------------------- machine
    "estop": _command(OPERATE, "E-stop on (true) or reset (false)", "estop", **ON),
    "machine": _command(OPERATE, "machine on or off", "machine", **ON),
    "mode": _command(OPERATE, "task mode: manual, mdi or auto", "mode", mode=_req("text")),
    "home": _command(OPERATE, "home a joint (-1 or none: all)", "home", joint=_opt("int")),
    "unhome": _command(OPERATE, "unhome a joint (-1 or none: all)", "unhome", joint=_opt("int")),
    "override_limits": _command(OPERATE, "override the limit switches", "override_limits"),
    "jog": _command(
        OPERATE,
        "action start (continuous: re-send hold within 0.3 s; websocket only), hold, stop or "
        "increment, of an axis letter or a joint; speed in units per minute",
        "jog",
        action=_req("text"),
        axis=_opt("text"),
        joint=_opt("int"),
        direction=_opt("number"),
        speed=_opt("number"),
        distance=_opt("number"),
    ),
    "abort": _command(OPERATE, "stop everything: program, MDI, motion (task abort)", "abort"),
    # ---------------------------------------------------------------- MDI and programs
    "mdi": _command(
        OPERATE, "run one MDI line to its end (kept in the history)", "mdi", text=_req("text")
    ),
    "macro": _command(OPERATE, "run an [MDI_COMMAND_LIST] entry", "macro", index=_req("int")),
    "open": _command(OPERATE, "open a program of the program folder", "open", file=_req("text")),
    "run": _command(OPERATE, "run the open program (from line)", "run", line=_opt("int")),
    "pause": _command(OPERATE, "pause the running program (feed hold)", "pause"),
    "resume": _command(OPERATE, "resume a paused program", "resume"),
    "step": _command(OPERATE, "run one line of the open program", "step"),
    "optional_stop": _command(OPERATE, "honour M1", "optional_stop", **ON),
    "block_delete": _command(OPERATE, "skip lines starting with /", "block_delete", **ON),
    "check_program": _command(
        OPERATE,
        "the preview interpreter's errors for a program text",
        "check_program",
        text=_req("text"),
    ),
    # ---------------------------------------------------------------- overrides, spindle, coolant
    "feedrate": _command(OPERATE, "feed override, percent", "feedrate", **PERCENT),
    "rapidrate": _command(OPERATE, "rapid override, percent", "rapidrate", **PERCENT),
    "spindle_override": _command(
        OPERATE, "spindle override, percent", "spindle_override", **PERCENT
    ),
    "spindle": _command(
        OPERATE,
        "action forward, reverse (speed in rpm), stop, faster or slower",
        "spindle",
        action=_req("text"),
        speed=_opt("number"),
    ),
    "flood": _command(OPERATE, "flood coolant", "flood", **ON),
    "mist": _command(OPERATE, "mist coolant", "mist", **ON),
    # ---------------------------------------------------------------- offsets
    "offsets.list": Method(READ, "the work offsets table (G54..G59.3, G92, rotation)"),
    "touch_off": _command(
        OPERATE,
        "set a system's offset so the axis reads value here (G10 L20)",
        "touch_off",
        axis=_req("text"),
        value=_req("number"),
        system=_opt("text"),
    ),
    "select_system": _command(
        OPERATE, "make G54..G59.3 active", "select_system", system=_req("text")
    ),
    "offset_set": _command(
        CONFIGURE,
        "set one axis (value) or the XY rotation of a system (G10 L2)",
        "offset_set",
        system=_req("text"),
        axis=_opt("text"),
        value=_opt("number"),
        rotation=_opt("number"),
    ),
    "offset_clear": _command(
        CONFIGURE, "zero a system's offsets, or G92's", "offset_clear", system=_req("text")
    ),
    # ---------------------------------------------------------------- tools
    "tools.list": Method(READ, "the tool table (iocontrol's), with the file's comments"),
    "tool_set": _command(
        CONFIGURE,
        "edit a tool: z, diameter (x, comment)",
        "tool_set",
        tool=_req("int"),
        z=_req("number"),
        diameter=_req("number"),
        x=_opt("number"),
        comment=_opt("text"),
    ),
    "tool_add": _command(
        CONFIGURE,
        "add a tool (pocket, z, diameter, comment)",
        "tool_add",
        tool=_req("int"),
        pocket=_opt("int"),
        z=_opt("number"),
        diameter=_opt("number"),
        comment=_opt("text"),
    ),
    "tool_delete": _command(CONFIGURE, "remove a tool", "tool_delete", tool=_req("int")),
    # ---------------------------------------------------------------- files
    "files.list": Method(READ, "the programs of the program folder ([DISPLAY]PROGRAM_PREFIX)"),
    "files.get": Method(READ, "a program's text", {"file": _req("text")}),
    "files.put": _command(
        CONFIGURE,
        "write a program (whole, atomically)",
        "save_program",
        file=_req("text"),
        text=_req("text"),
    ),
    "files.delete": Method(
        CONFIGURE, "remove a program (not the open one)", {"file": _req("text")}
    ),
    # ---------------------------------------------------------------- page helpers
    "probe": _command(
        OPERATE,
        "start a probing helper (kind, params): steps come as notify.probe",
        "probe",
        kind=_req("text"),
        params=_opt("object"),
    ),
    "probe_confirm": _command(
        OPERATE,
        "set what the last probing found (system and values, tool, is_reference)",
        "probe_confirm",
        system=_opt("text"),
        values=_opt("object"),
        tool=_opt("int"),
        is_reference=_opt("bool"),
    ),
    "answer": _command(
        OPERATE,
        "answer a [DISPLAY] message dialog",
        "answer",
        name=_req("text"),
        is_yes=_opt("bool"),
    ),
}


def check_params(name: str, method: Method, params: Any) -> dict[str, Any]:
    """The call's parameters by name; RpcError(INVALID_PARAMS) saying what is wrong."""
    if params is None or params == []:
        params = {}
    if not isinstance(params, dict):
        raise RpcError(INVALID_PARAMS, f"{name}: params must be an object (by name)")
    for key, value in params.items():
        spec = method.params.get(key)
        if spec is None:
            known = ", ".join(method.params) or "none"
            raise RpcError(INVALID_PARAMS, f"{name}: unknown parameter {key!r} (takes {known})")
        if not KINDS[spec.kind](value):
            raise RpcError(INVALID_PARAMS, f"{name}: {key!r} must be of kind {spec.kind}")
    for key, spec in method.params.items():
        if spec.is_required and key not in params:
            raise RpcError(INVALID_PARAMS, f"{name}: {key!r} is required")
    return params


def notification(message: dict[str, Any]) -> dict[str, Any]:
    """A hub message ({"type": KIND, ...}) as a JSON-RPC notification ``notify.KIND``
    (a status's params are its changed fields)."""
    kind = message["type"]
    params = (
        message["data"] if kind == "status" else {k: v for k, v in message.items() if k != "type"}
    )
    return {"jsonrpc": "2.0", "method": f"notify.{kind}", "params": params}


def _error(code: int, message: str, data: Any = None, id_: Any = None) -> dict[str, Any]:
    error: dict[str, Any] = {"code": code, "message": message}
    if data is not None:
        error["data"] = data
    return {"jsonrpc": "2.0", "id": id_, "error": error}


# ------------------------------------------------------------------ the dispatcher
Service = Callable[["Client", dict[str, Any]], Awaitable[Any]]


class Rpc:
    """Answers JSON-RPC calls for one hub."""

    def __init__(self, hub: Hub) -> None:
        self.hub = hub
        self.services: dict[str, Service] = Handlers(self)  # the @handler methods below

    async def handle(self, client: Client, text: str | bytes) -> str | None:
        """One message: a call or a batch; the reply's text, or None (nothing to answer)."""
        try:
            request = json.loads(text)
        except (ValueError, UnicodeDecodeError) as exc:
            return json.dumps(_error(PARSE_ERROR, f"parse error: {exc}"))
        if isinstance(request, list):
            if not request:
                return json.dumps(_error(INVALID_REQUEST, "invalid request: an empty batch"))
            # A batch's calls run side by side, as separate messages would: a stop in it
            # never waits for a long MDI line before it.
            replies = await asyncio.gather(*(self.call(client, one) for one in request))
            found = [reply for reply in replies if reply is not None]
            return json.dumps(found) if found else None
        reply = await self.call(client, request)
        return None if reply is None else json.dumps(reply)

    async def call(self, client: Client, request: Any) -> dict[str, Any] | None:
        """One call; its response (None for a notification: a call without "id")."""
        if not isinstance(request, dict) or request.get("jsonrpc") != "2.0":
            return _error(INVALID_REQUEST, 'invalid request: expected {"jsonrpc": "2.0", ...}')
        id_ = request.get("id")
        is_notification = "id" not in request
        if not (id_ is None or isinstance(id_, str | int | float)) or isinstance(id_, bool):
            return _error(INVALID_REQUEST, "invalid request: 'id' must be a number or text")
        try:
            result = await self._run(client, request)
        except RpcError as exc:
            return None if is_notification else _error(exc.code, exc.message, exc.data, id_)
        except Refused as refusal:  # the server's or the controller's (said already)
            data = {"is_reported": True} if refusal.is_quiet else None
            return None if is_notification else _error(REFUSED, refusal.reason, data, id_)
        except Exception as exc:  # a bug: said, answered, and the server goes on
            message = internal_error("web", f"in {request.get('method')}", exc).reason
            return None if is_notification else _error(INTERNAL_ERROR, message, None, id_)
        return None if is_notification else {"jsonrpc": "2.0", "id": id_, "result": result}

    async def _run(self, client: Client, request: dict[str, Any]) -> Any:
        name = request.get("method")
        if not isinstance(name, str):
            raise RpcError(INVALID_REQUEST, "invalid request: 'method' must be a text")
        method = METHODS.get(name)
        if method is None:
            raise RpcError(METHOD_NOT_FOUND, f"method not found: {name!r}")
        if not client.identity.allows(method.scope):
            who = client.identity.name
            raise RpcError(FORBIDDEN, f"{name}: needs the {method.scope} scope ({who} has not)")
        params = check_params(name, method, request.get("params"))
        if method.needs_socket and client.socket is None:
            raise Refused(f"{name}: only over the websocket (/api/v1/ws)")
        if method.command is None:
            return await self.services[name](client, params)
        if (
            name == "jog" and params.get("action") in ("start", "hold") and client.socket is None
        ):  # a continuous jog lives while its websocket holds it
            raise Refused("jog: a continuous jog needs the websocket (/api/v1/ws)")
        outcome = await self.hub.dispatch(client, {**params, "cmd": method.command})
        if outcome["status"] != "DONE":
            raise Refused(outcome["message"], is_quiet=bool(outcome.get("is_reported")))
        return {key: value for key, value in outcome.items() if key != "status"}

    # ---------------------------------------------------------------- services
    @handler("api.version")
    async def _version(self, client: Client, params: dict[str, Any]) -> Any:
        return {"api": "v1", "version": API_VERSION, "server": "cnc ui web"}

    @handler("api.methods")
    async def _methods(self, client: Client, params: dict[str, Any]) -> Any:
        return {
            name: {"scope": m.scope, "summary": m.summary, "websocket_only": m.needs_socket,
                   "params": {k: {"kind": p.kind, "is_required": p.is_required}
                              for k, p in m.params.items()}}
            for name, m in METHODS.items()
        }  # fmt: skip

    @handler("api.identity")
    async def _identity(self, client: Client, params: dict[str, Any]) -> Any:
        identity = client.identity
        return {"name": identity.name, "scopes": sorted(identity.scopes)}

    def _fields(self, params: dict[str, Any]) -> frozenset[str] | None:
        """The status fields named (None: all); RpcError for an unknown one."""
        fields = params.get("fields")
        if not fields:
            return None
        known = self.hub.status_fields()
        unknown = [name for name in fields if name not in known]
        if unknown:
            raise RpcError(INVALID_PARAMS, f"unknown status field {unknown[0]!r}")
        return frozenset(fields)

    @handler("status.get")
    async def _status_get(self, client: Client, params: dict[str, Any]) -> Any:
        fields = self._fields(params)
        status = self.hub.status
        return dict(status) if fields is None else {k: status.get(k) for k in sorted(fields)}

    @handler("status.subscribe")
    async def _status_subscribe(self, client: Client, params: dict[str, Any]) -> Any:
        fields = self._fields(params)
        client.status_fields = fields if fields is not None else self.hub.status_fields()
        # what it is now; every change after this comes as notify.status
        return {k: self.hub.status.get(k) for k in sorted(client.status_fields)}

    @handler("status.unsubscribe")
    async def _status_unsubscribe(self, client: Client, params: dict[str, Any]) -> Any:
        client.status_fields = frozenset()
        return {}

    @handler("events.subscribe")
    async def _events_subscribe(self, client: Client, params: dict[str, Any]) -> Any:
        kinds = params.get("events") or list(EVENTS)
        unknown = [kind for kind in kinds if kind not in EVENTS]
        if unknown:
            raise RpcError(INVALID_PARAMS, f"unknown event {unknown[0]!r} ({', '.join(EVENTS)})")
        client.events = frozenset(kinds)
        for message in self.hub.event_state(client.events):
            await self.hub.notify(client, message)
        return {"events": sorted(client.events)}

    @handler("events.unsubscribe")
    async def _events_unsubscribe(self, client: Client, params: dict[str, Any]) -> Any:
        client.events = frozenset()
        return {}

    @handler("page.config")
    async def _page_config(self, client: Client, params: dict[str, Any]) -> Any:
        return self.hub.page_config(client.identity.allows(OPERATE))

    @handler("files.list")
    async def _files_list(self, client: Client, params: dict[str, Any]) -> Any:
        return {"files": await self.hub.in_worker(self.hub.commands.program_files)}

    @handler("files.get")
    async def _files_get(self, client: Client, params: dict[str, Any]) -> Any:
        try:
            return await self.hub.in_worker(self.hub.commands.program_text, params["file"])
        except CommandError as exc:
            raise Refused(f"files.get: {exc}") from None

    @handler("files.delete")
    async def _files_delete(self, client: Client, params: dict[str, Any]) -> Any:
        try:
            await self.hub.in_worker(self.hub.commands.delete_program, params["file"])
        except CommandError as exc:
            raise Refused(f"files.delete: {exc}") from None
        return {"file": params["file"]}

    @handler("offsets.list")
    async def _offsets_list(self, client: Client, params: dict[str, Any]) -> Any:
        return await self.hub.offsets()

    @handler("tools.list")
    async def _tools_list(self, client: Client, params: dict[str, Any]) -> Any:
        return await self.hub.tools()
