"""Fixtures of the web UI tests: the UI tests' buffers and fake task, the server's app, and
a real machine with the server as its own process.

``web`` starts the app (cnc/ui/web/server.py) against the fake task's buffers in
pytest-aiohttp's test server and returns its client; ``page`` connects to its API's
websocket as the page does (``PageSocket``); ``receive_until`` reads a websocket until a
wanted message arrives. ``machine`` runs ``cnc run --headless`` on a copy of
tests/task/machine/mill.ini with [DISPLAY] message keys and a program; ``page_url`` starts
``cnc ui web`` on it.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import shutil
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.request
import weakref
from collections.abc import AsyncIterator, Callable, Iterator
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from cnc.ui.web.server import Access, make_app
from cnc.ui.web.settings import Settings
from tests.conftest import Processes
from tests.task.test_machine import MACHINE, Machine, launched
from tests.ui.conftest import controller, fake_task, runtime_dir  # noqa: F401 (fixtures)

WAIT_S = 20.0  # generous: only reached when something is broken


@pytest.fixture
def web(aiohttp_client: Callable[..., Any]) -> Callable[..., Any]:
    """``await web(settings=..., access=...)``: a test client of a running server."""

    async def start(settings: Settings | None = None, access: Access | None = None) -> Any:
        app = make_app(settings or Settings(cycle_time_s=0.02), None, access or Access())
        return await aiohttp_client(app)

    return start


API_WS = "/api/v1/ws"


class PageSocket:
    """The API's websocket (JSON-RPC 2.0) as the page's transport (static/js/link.js) sees
    it, so that the page's tests read as the page's parts: ``send_json({"cmd": NAME,
    "id"?, ...params})`` is a call of method NAME (without "id": a notification), and
    ``receive_json()`` gives a response as ``{"type": "result", "id", "status":
    "DONE"|"ERROR", "message", "is_reported"?, ...result}`` and a notification
    ``notify.KIND`` as ``{"type": KIND, ...params}`` (a status as ``{"type": "status",
    "data": params}``). Connecting does what the page does: page.config (a "config"
    message), status.subscribe (the whole status) and events.subscribe."""

    PUBLIC_NAMES = {"save_program": "files.put"}  # the page's editor saves with files.put

    def __init__(self, socket: aiohttp.ClientWebSocketResponse) -> None:
        self.socket = socket
        self._numbers = itertools.count(1)

    async def start(self) -> None:
        for method in ("page.config", "status.subscribe", "events.subscribe"):
            await self.socket.send_json({"jsonrpc": "2.0", "id": method, "method": method})

    async def send_json(self, request: dict[str, Any]) -> None:
        params = {k: v for k, v in request.items() if k not in ("cmd", "id")}
        method = self.PUBLIC_NAMES.get(request["cmd"], request["cmd"])
        call = {"jsonrpc": "2.0", "method": method, "params": params}
        if "id" in request:
            call["id"] = request["id"]
        await self.socket.send_json(call)

    async def send_str(self, text: str) -> None:
        await self.socket.send_str(text)

    async def receive_json(self) -> dict[str, Any]:
        message = await self.socket.receive_json()
        method = message.get("method")
        if method is not None:
            kind = method.removeprefix("notify.")
            if kind == "status":
                return {"type": "status", "data": message["params"]}
            return {"type": kind, **message["params"]}
        if message.get("id") == "page.config":
            return {"type": "config", "data": message["result"]}
        if message.get("id") == "status.subscribe":
            return {"type": "status", "data": message["result"]}
        if "error" in message:
            error = message["error"]
            found = {"type": "result", "id": message.get("id"), "status": "ERROR",
                     "message": error["message"], "code": error["code"]}  # fmt: skip
            if (error.get("data") or {}).get("is_reported"):
                found["is_reported"] = True
            return found
        result = message["result"] if isinstance(message["result"], dict) else {}
        return {"type": "result", "id": message["id"], "status": "DONE", "message": "DONE"} | result

    async def close(self) -> None:
        await self.socket.close()

    @property
    def closed(self) -> bool:
        return self.socket.closed


@contextlib.asynccontextmanager
async def page(client: Any, url: str = API_WS, **options: Any) -> AsyncIterator[PageSocket]:
    """The API's websocket of ``client`` (a test client or an aiohttp session), connected
    as the page connects."""
    async with client.ws_connect(url, **options) as socket:
        found = PageSocket(socket)
        await found.start()
        yield found


# Messages read from a socket while waiting for another one, by socket: a status change
# may arrive before the result of the command that caused it.
_unread: weakref.WeakKeyDictionary[Any, list[dict[str, Any]]] = weakref.WeakKeyDictionary()


async def receive_until(
    socket: aiohttp.ClientWebSocketResponse, wanted: Callable[[dict[str, Any]], bool]
) -> dict[str, Any]:
    """The first message from the server, not yet taken, for which ``wanted`` is true."""
    unread = _unread.setdefault(socket, [])
    for index, message in enumerate(unread):
        if wanted(message):
            return unread.pop(index)
    try:
        async with asyncio.timeout(WAIT_S):
            while True:
                message = await socket.receive_json()
                if wanted(message):
                    return message
                unread.append(message)
    except TimeoutError:
        raise AssertionError(f"never received the wanted message; saw {unread}") from None


def is_result(number: int) -> Callable[[dict[str, Any]], bool]:
    return lambda message: message["type"] == "result" and message["id"] == number


def is_status_with(key: str, value: Any) -> Callable[[dict[str, Any]], bool]:
    return lambda message: message["type"] == "status" and message["data"].get(key) == value


# ------------------------------------------------------------------ a real machine
SERVER_MAIN = "import sys; from cnc.ui.web.server import main; sys.exit(main(sys.argv[1:]))"
# [DISPLAY] user messages of the test machine (GUI-018): pins web.messages.door...
MESSAGES = """\
MESSAGE_BOLDTEXT = Door
MESSAGE_TEXT = Is the door closed?
MESSAGE_DETAILS = The interlock switch reports it open.
MESSAGE_TYPE = yesnodialog
MESSAGE_PINNAME = door
MESSAGE_ICON = WARNING
"""
# The spindle's range ([SPINDLE_0], LinuxCNC 2.9's keys), which the page keeps to
SPINDLE = "\n[SPINDLE_0]\nMAX_FORWARD_VELOCITY = 6000\nMIN_FORWARD_VELOCITY = 0\n"
PROGRAMS = {
    "part.ngc": "G21 G90\nG0 X1 Y2\nG3 X3 Y2 I1 F600\nM2\n",  # ends at X3 Y2
    # spindle and flood on, then a 12 s feed: the interpreter reads M5 M9 ahead of it
    "cut.ngc": "G21 G90\nM3 S1000\nM8\nG1 X60 F300\nM5 M9\nG0 X0\nM2\n",
    # an M0 on line 5: the page shows that line, not the move before it
    "stop.ngc": "G21 G90\nG0 X0 Y0\nG1 X5 F600\nM3 S500\nM0\nG1 X0\nM5\nM2\n",
    "bad.ngc": "G21 G90\nG0 X1\nG1 X2 F100 Q\nM2\n",  # an error on line 3
}


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def wait_http(url: str, proc: subprocess.Popen[str], timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        try:
            with urllib.request.urlopen(url, timeout=2):
                return
        except (urllib.error.URLError, ConnectionError):
            time.sleep(0.1)
    raise AssertionError(f"{url} never answered")


@pytest.fixture
def machine(procs: Processes, tmp_path: Path, request: pytest.FixtureRequest) -> Iterator[Machine]:
    """The test mill with the programs above; with the [DISPLAY] message dialogs unless
    parametrized (indirect) with False: a server with message pins owns a HAL component
    of the machine, which the machine's shut-down stops (HAL's unload all, as LinuxCNC's)."""
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    ini = folder / "mill.ini"
    messages = MESSAGES if getattr(request, "param", True) else ""
    text = ini.read_text().replace("[DISPLAY]\n", "[DISPLAY]\n" + messages, 1) + SPINDLE
    ini.write_text(text)
    for name, program in PROGRAMS.items():
        (folder / name).write_text(program)
    with launched(procs, folder) as found:
        yield found


def start_server(procs: Processes, machine: Machine, port: int) -> subprocess.Popen[str]:
    """``cnc ui web`` on the machine, as its own process, answering on ``port``."""
    server = procs.python(
        "-c", SERVER_MAIN, "web", "mill.ini", "--port", str(port), cwd=machine.folder
    )
    wait_http(f"http://127.0.0.1:{port}/", server)
    return server


@pytest.fixture
def page_url(machine: Machine, procs: Processes) -> Iterator[str]:
    """``cnc ui web`` on the machine, as its own process; its address. Stopped before the
    machine (it removes its HAL component then)."""
    port = free_port()
    server = start_server(procs, machine, port)
    url = f"http://127.0.0.1:{port}/"
    yield url
    if server.poll() is not None:
        print(f"the server ended by itself ({server.returncode})")
    server.send_signal(signal.SIGTERM)
    try:
        _, errors = server.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        server.kill()
        _, errors = server.communicate()
    print(f"the server's stderr:\n{errors}")  # shown when the test fails
