"""The public API's dispatcher (cnc/ui/web/rpc.py) on its own: JSON-RPC 2.0's errors,
batches and notifications, parameter checks, scopes, and what reaches the hub."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest

from cnc.apikeys import CONFIGURE, OPERATE, READ, Identity
from cnc.ui.web.hub import Client
from cnc.ui.web.rpc import METHODS, Rpc

pytestmark = pytest.mark.asyncio


class StubHub:
    """What Rpc needs of a hub: commands are recorded, and refused when they say so."""

    def __init__(self) -> None:
        self.commands: list[dict[str, Any]] = []
        self.status = {"is_connected": True, "task_state": "ON", "work": [1.0, 2.0, 3.0]}

    async def dispatch(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        self.commands.append(request)
        if request.get("text") == "refuse me":
            return {"status": "ERROR", "message": "mdi: the controller refused mdi",
                    "is_reported": True}  # fmt: skip
        return {"status": "DONE", "message": "DONE"}

    def status_fields(self) -> frozenset[str]:
        return frozenset(self.status)


def client(*scopes: str, has_socket: bool = True) -> Client:
    return Client(object() if has_socket else None, Identity("test", frozenset(scopes)))


def call(method: str, id_: Any = 1, **params: Any) -> dict[str, Any]:
    return {"jsonrpc": "2.0", "id": id_, "method": method, "params": params}


async def ask(rpc: Rpc, who: Client, request: Any) -> Any:
    reply = await rpc.handle(who, json.dumps(request) if not isinstance(request, str) else request)
    return None if reply is None else json.loads(reply)


def error(id_: Any, code: int, message: str, data: Any = None) -> dict[str, Any]:
    found = {"code": code, "message": message} | ({"data": data} if data else {})
    return {"jsonrpc": "2.0", "id": id_, "error": found}


@pytest.fixture
def hub() -> StubHub:
    return StubHub()


async def test_a_command_reaches_the_hub_and_its_result_comes_back(hub: StubHub) -> None:
    rpc = Rpc(hub)  # type: ignore[arg-type]
    answer = await ask(rpc, client(OPERATE), call("mdi", 7, text="G0 X1"))
    assert answer == {"jsonrpc": "2.0", "id": 7, "result": {"message": "DONE"}}
    assert hub.commands == [{"text": "G0 X1", "cmd": "mdi"}]
    answer = await ask(rpc, client(OPERATE), call("files.put", "a", file="x.ngc", text="M2"))
    assert answer["error"]["code"] == -32001  # configure, which operate is not
    assert hub.commands[-1]["cmd"] == "mdi"


@pytest.mark.parametrize(
    ("request_text", "expected"),
    [
        ("{not json", error(None, -32700, "parse error: ")),
        ("[]", error(None, -32600, "invalid request: an empty batch")),
        ('{"id": 1, "method": "mdi"}', error(None, -32600, "invalid request: ")),
        ('{"jsonrpc": "2.0", "id": 1}', error(1, -32600, "invalid request: 'method' ")),
        ('{"jsonrpc": "2.0", "id": true, "method": "abort"}', error(None, -32600, "invalid")),
        ('{"jsonrpc": "2.0", "id": 1, "method": "nope"}', error(1, -32601, "method not found")),
        ('{"jsonrpc": "2.0", "id": 1, "method": "mdi", "params": ["G0"]}',
         error(1, -32602, "mdi: params must be an object (by name)")),
        ('{"jsonrpc": "2.0", "id": 1, "method": "mdi", "params": {"text": 5}}',
         error(1, -32602, "mdi: 'text' must be of kind text")),
        ('{"jsonrpc": "2.0", "id": "m", "method": "mdi", "params": {"text": "refuse me"}}',
         error("m", -32000, "mdi: the controller refused mdi", {"is_reported": True})),
    ],
)  # fmt: skip
async def test_errors_are_json_rpcs(hub: StubHub, request_text: str, expected: dict) -> None:
    answer = await ask(Rpc(hub), client(OPERATE), request_text)  # type: ignore[arg-type]
    message = answer["error"].pop("message")
    expected_message = expected["error"].pop("message")
    assert message.startswith(expected_message)
    assert answer == expected


async def test_a_batch_answers_each_call_and_nothing_for_its_notifications(hub: StubHub) -> None:
    rpc = Rpc(hub)  # type: ignore[arg-type]
    batch = [
        call("flood", 1, on=True),
        {"jsonrpc": "2.0", "method": "mist", "params": {"on": True}},  # a notification
        call("nope", 2),
        5,
        call("api.version", 3),
    ]
    answers = await ask(rpc, client(OPERATE), batch)
    assert sorted(answers, key=lambda a: str(a["id"])) == [
        {"jsonrpc": "2.0", "id": 1, "result": {"message": "DONE"}},
        {"jsonrpc": "2.0", "id": 2,
         "error": {"code": -32601, "message": "method not found: 'nope'"}},
        {"jsonrpc": "2.0", "id": 3,
         "result": {"api": "v1", "version": "1.0", "server": "cnc ui web"}},
        {"jsonrpc": "2.0", "id": None, "error": {
            "code": -32600, "message": "invalid request: expected {\"jsonrpc\": \"2.0\", ...}"}},
    ]  # fmt: skip
    assert [c["cmd"] for c in hub.commands] == ["flood", "mist"]
    only_notifications = [{"jsonrpc": "2.0", "method": "abort"}] * 2
    assert await ask(rpc, client(OPERATE), only_notifications) is None
    assert await ask(rpc, client(OPERATE), {"jsonrpc": "2.0", "method": "nope"}) is None


async def test_a_batchs_stop_does_not_wait_for_a_slow_call_before_it(hub: StubHub) -> None:
    """A batch's calls run side by side, as separate messages do."""
    is_released = asyncio.Event()
    order: list[str] = []

    async def dispatch(client: Client, request: dict[str, Any]) -> dict[str, Any]:
        if request["cmd"] == "mdi":
            await is_released.wait()
        order.append(request["cmd"])
        if request["cmd"] == "abort":
            is_released.set()
        return {"status": "DONE", "message": "DONE"}

    hub.dispatch = dispatch  # type: ignore[method-assign]
    batch = [call("mdi", 1, text="G4 P100"), call("abort", 2)]
    answers = await asyncio.wait_for(ask(Rpc(hub), client(OPERATE), batch), 5)  # type: ignore[arg-type]
    assert order == ["abort", "mdi"] and len(answers) == 2


@pytest.mark.parametrize(
    ("scopes", "allowed"),
    [
        ((READ,), {"status.get", "api.version", "files.list", "tools.list"}),
        ((OPERATE,), {"status.get", "mdi", "estop", "jog", "touch_off"}),
        ((CONFIGURE,), {"status.get", "tool_set", "files.put", "files.delete", "offset_set"}),
    ],
)
async def test_each_scope_allows_its_methods_only(
    hub: StubHub, scopes: tuple[str, ...], allowed: set[str]
) -> None:
    """read reads; operate commands; configure writes tables and files (both read)."""
    who = client(*scopes)
    for name, method in METHODS.items():
        assert who.identity.allows(method.scope) is (
            method.scope == READ or method.scope in scopes
        ), name
    for name in allowed:
        assert who.identity.allows(METHODS[name].scope), name
    rpc = Rpc(hub)  # type: ignore[arg-type]
    refused = await ask(rpc, who, call("machine", on=True))
    if OPERATE in scopes:
        assert "result" in refused
    else:
        assert refused["error"] == {
            "code": -32001, "message": "machine: needs the operate scope (test has not)"
        }  # fmt: skip


async def test_the_method_table_names_real_commands_and_services(hub: StubHub) -> None:
    from cnc.ui.web.commands import HANDLERS

    rpc = Rpc(hub)  # type: ignore[arg-type]
    hub_handlers = {"answer", "jog", "check_program", "probe", "probe_confirm"}  # Hub.handlers
    for name, method in METHODS.items():
        if method.command is None:
            assert name in rpc.services, name
        else:
            assert method.command in HANDLERS or method.command in hub_handlers, name
    assert "mdi_line" not in {m.command for m in METHODS.values()}  # the server's own


async def test_over_http_subscriptions_and_continuous_jogs_are_refused(hub: StubHub) -> None:
    rpc = Rpc(hub)  # type: ignore[arg-type]
    one_shot = client(OPERATE, has_socket=False)
    answer = await ask(rpc, one_shot, call("status.subscribe"))
    assert answer["error"]["message"] == "status.subscribe: only over the websocket (/api/v1/ws)"
    answer = await ask(rpc, one_shot, call("jog", action="start", axis="X", direction=1, speed=6))
    assert answer["error"]["code"] == -32000 and hub.commands == []
    answer = await ask(rpc, one_shot, call("jog", action="stop", axis="X"))
    assert answer["result"] == {"message": "DONE"}  # a stop goes through anywhere


async def test_status_get_and_subscribe_take_known_fields(hub: StubHub) -> None:
    rpc = Rpc(hub)  # type: ignore[arg-type]
    who = client(READ)
    answer = await ask(rpc, who, call("status.get", fields=["work"]))
    assert answer["result"] == {"work": [1.0, 2.0, 3.0]}
    answer = await ask(rpc, who, call("status.subscribe", fields=["task_state", "work"]))
    assert answer["result"] == {"task_state": "ON", "work": [1.0, 2.0, 3.0]}
    assert who.status_fields == {"task_state", "work"}
    changed = {"type": "status", "data": {"work": [0, 0, 0], "is_connected": False}}
    assert who.wants(changed) == {"type": "status", "data": {"work": [0, 0, 0]}}
    assert who.wants({"type": "status", "data": {"is_connected": False}}) is None
    assert who.wants({"type": "notice", "kind": "error", "text": "x"}) is None
    answer = await ask(rpc, who, call("status.subscribe", fields=["colour"]))
    assert answer["error"] == {"code": -32602, "message": "unknown status field 'colour'"}
