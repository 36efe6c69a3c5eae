"""The public API end to end (API.md): a real machine (``cnc run --headless``), ``cnc ui
web`` as its own process, and clients speaking JSON-RPC 2.0 to it: API.md's Python example
run as it is written, a subscription that sees a position change and an E-stop, the error
channel as notifications, HTTP one-shot calls, and keys (a read key's command refused, a
wrong key refused). One machine for the module's one test: a machine takes seconds."""

from __future__ import annotations

import asyncio
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from cnc.apikeys import KeyStore, keys_file_for
from tests.conftest import Processes
from tests.task.test_machine import Machine
from tests.web.conftest import free_port, start_server

API_MD = Path(__file__).parents[2] / "cnc" / "ui" / "web" / "API.md"
WAIT_S = 30.0


def example_code() -> str:
    """The Python block of API.md's "A Python client" section."""
    text = API_MD.read_text()
    section = text[text.index("## A Python client") :]
    found = re.search(r"```python\n(.*?)```", section, re.S)
    assert found is not None
    return found.group(1)


async def next_notification(
    socket: aiohttp.ClientWebSocketResponse, method: str, test: Any = lambda params: True
) -> dict[str, Any]:
    async with asyncio.timeout(WAIT_S):
        while True:
            message = await socket.receive_json()
            if message.get("method") == method and test(message["params"]):
                return message["params"]


async def call(socket: aiohttp.ClientWebSocketResponse, method: str, **params: Any) -> Any:
    """A call, its response (notifications meanwhile are dropped)."""
    await socket.send_json({"jsonrpc": "2.0", "id": method, "method": method, "params": params})
    async with asyncio.timeout(WAIT_S):
        while True:
            message = await socket.receive_json()
            if message.get("id") == method:
                return message


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_clients_drive_and_watch_a_machine_through_the_api(
    machine: Machine, procs: Processes, tmp_path: Path
) -> None:
    store = KeyStore(keys_file_for(machine.folder / "mill.ini"))
    keys = {scope: store.create(f"test-{scope}", [scope]) for scope in ("read", "operate")}
    port = free_port()
    server = start_server(procs, machine, port)
    base = f"http://127.0.0.1:{port}"
    try:
        the_documented_example_runs(base, keys["operate"], tmp_path)
        asyncio.run(a_subscriber_sees_a_move_an_error_and_an_estop(base, keys))
        asyncio.run(keys_are_checked_and_http_calls_work(base, keys))
    finally:
        server.terminate()
        server.communicate(timeout=10)


def the_documented_example_runs(base: str, key: str, folder: Path) -> None:
    script = folder / "api_example.py"
    script.write_text(example_code())
    done = subprocess.run(
        [sys.executable, str(script), f"ws://{base.removeprefix('http://')}/api/v1/ws", key],
        capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "api 1.0"
    assert "at [5.0, -2.0, 10.0]" in lines  # Z homed to HOME = 10
    assert "refused: mdi: the controller refused mdi" in lines
    assert any(line.startswith("notice: ") and "feed" in line for line in lines), lines
    assert lines[-1] == "state ESTOP"


async def a_subscriber_sees_a_move_an_error_and_an_estop(base: str, keys: dict[str, str]) -> None:
    """A read key watches (only the fields it asked for) while an operate key drives."""
    async with aiohttp.ClientSession() as session:
        watch = await session.ws_connect(f"{base}/api/v1/ws?token={keys['read']}")
        drive = await session.ws_connect(
            f"{base}/api/v1/ws", headers={"Authorization": f"Bearer {keys['operate']}"}
        )
        async with watch, drive:
            fields = ["work", "task_state", "is_all_homed"]
            now = await call(watch, "status.subscribe", fields=fields)
            assert set(now["result"]) == set(fields)
            assert now["result"]["task_state"] == "ESTOP"  # the example left it so
            assert (await call(watch, "events.subscribe", events=["notice"]))["result"] == {
                "events": ["notice"]
            }
            for method, params in [("estop", {"on": False}), ("machine", {"on": True})]:
                assert "result" in await call(drive, method, **params), method
            await next_notification(watch, "notify.status", lambda p: p.get("task_state") == "ON")
            if not now["result"]["is_all_homed"]:  # (the example homed; an E-stop may unhome)
                assert "result" in await call(drive, "home", joint=-1)
                await next_notification(watch, "notify.status", lambda p: p.get("is_all_homed"))
            assert "result" in await call(drive, "mdi", text="G0 X7 Y1")
            seen = await next_notification(
                watch, "notify.status", lambda p: p.get("work", [None])[:2] == [7.0, 1.0]
            )
            assert set(seen) <= set(fields)  # only the subscribed fields
            refused = await call(drive, "mdi", text="G999")
            assert refused["error"]["code"] == -32000 and refused["error"]["data"] == {
                "is_reported": True
            }
            notice = await next_notification(watch, "notify.notice")
            assert notice == {"kind": "error", "text": "G-code out of range"}
            assert "result" in await call(drive, "estop", on=True)
            await next_notification(
                watch, "notify.status", lambda p: p.get("task_state") == "ESTOP"
            )
            refused = await call(watch, "estop", on=False)  # a read key may not command
            assert refused["error"] == {
                "code": -32001, "message": "estop: needs the operate scope (test-read has not)"
            }  # fmt: skip


async def keys_are_checked_and_http_calls_work(base: str, keys: dict[str, str]) -> None:
    url = f"{base}/api/v1/rpc"
    async with aiohttp.ClientSession() as session:
        wrong = {"Authorization": "Bearer cnc_12345678_" + "A" * 43}
        async with session.post(url, json={"jsonrpc": "2.0", "id": 1, "method": "api.version"},
                                headers=wrong) as answer:  # fmt: skip
            assert answer.status == 401
        headers = {"Authorization": f"Bearer {keys['operate']}"}
        batch = [
            {"jsonrpc": "2.0", "id": 1, "method": "status.get", "params": {"fields": ["work"]}},
            {"jsonrpc": "2.0", "id": 2, "method": "files.list"},
            {"jsonrpc": "2.0", "id": 3, "method": "mdi", "params": {"text": "G0 X0"}},
        ]
        async with session.post(url, json=batch, headers=headers) as answer:
            assert answer.status == 200
            replies = {reply["id"]: reply for reply in json.loads(await answer.text())}
        assert replies[1]["result"] == {"work": [7.0, 1.0, 10.0]}
        assert "cut.ngc" in replies[2]["result"]["files"]
        assert replies[3]["error"]["message"].startswith("mdi: ")  # in E-stop: refused
