"""``cnc ui web [INI] [--host H] [--port P] [--token T] [--read-only-token R]``: the operator
UI in the browser (issue 7, GUI-*).

One process attaches to the controller like any UI (``cnc.stat``, ``cnc.command``,
``cnc.error_channel``) and serves the page (``static/``) and a websocket, ``/ws``:

- server -> page: ``{"type": "status", "data": {...}}`` (the first one complete, then only
  the fields that changed, every [DISPLAY]CYCLE_TIME), ``{"type": "notice", "kind":
  "error"|"text"|"display", "text": ...}`` for each operator message, ``{"type": "result",
  "id": ..., "status": "DONE"|"ERROR", "message": ...}`` for each command, ``{"type":
  "history", "lines": [...]}`` when the MDI history grows, ``{"type": "dialog", "name":
  pin, "kind": "ok"|"yesno"|"none", "title", "text", "details", "icon"}`` and ``{"type":
  "dialog_close", "name": pin}`` for the [DISPLAY] message dialogs (messages.py).
- page -> server: ``{"cmd": NAME, "id": ..., ...arguments}`` (commands.py lists them;
  ``{"cmd": "answer", "name": pin, "is_yes": bool}`` answers a message dialog).

HTTP: ``/`` the page, ``/static/*`` its assets, ``/api/config`` what the page offers (from
the INI), ``/api/files`` the programs of PROGRAM_PREFIX, ``/api/program`` the lines of the
open program, ``/api/preview`` its toolpath (preview.py), ``/api/tools`` the tool table,
``POST /api/upload`` a program into PROGRAM_PREFIX.

Commands run in worker threads: the event loop never waits for the controller. A browser
that disconnects changes nothing on the machine, with one exception for safety: a
continuous jog it started and did not stop is stopped (as AXIS stops jogs on focus loss).

Access: 127.0.0.1 by default; any other address needs a token (``--token`` or
$CNC_WEB_TOKEN). With a token, every request needs it (``?token=``, ``Authorization:
Bearer``, or the cookie the server sets on the first request that had it), else 401. A
read-only token ($CNC_WEB_READ_ONLY_TOKEN) may watch; its commands are refused. Websockets
and uploads from another site's page (Origin not this server) are refused.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import hmac
import ipaddress
import json
import os
import sys
from collections.abc import Awaitable, Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

import cnc
from cnc.ini import IniError, IniFile
from cnc.ui.controller import Controller
from cnc.ui.formatting import MESSAGE_KINDS
from cnc.ui.web.commands import CommandError, Commands, tool_comments
from cnc.ui.web.messages import UserMessages
from cnc.ui.web.preview import preview
from cnc.ui.web.settings import Settings
from cnc.ui.web.status import DISCONNECTED, diff, snapshot
from hal.core import HalError

STATIC = Path(__file__).with_name("static")
DEFAULT_HOST, DEFAULT_PORT = "127.0.0.1", 8750
TOKEN_ENV, READ_ONLY_TOKEN_ENV = "CNC_WEB_TOKEN", "CNC_WEB_READ_ONLY_TOKEN"
COOKIE = "cnc_token"
WORKERS = 8  # commands waiting for the controller at once
URGENT_WORKERS = 2  # for stops, which must never queue behind long MDI lines
MAX_PROGRAM_BYTES = 20_000_000
HUB = web.AppKey("hub", "Hub")
IS_CONTROL = web.RequestKey("is_control", bool)  # the request may send commands


@dataclass(eq=False)
class Client:
    """One connected page."""

    socket: web.WebSocketResponse
    is_control: bool
    jogging: set[int] = field(default_factory=set)  # joints in a continuous jog it started
    jog_lock: asyncio.Lock = field(default_factory=asyncio.Lock)  # jogs run in order


class Hub:
    """The controller's status and messages, pushed to every connected page."""

    def __init__(self, settings: Settings, source: str | None) -> None:
        self.settings = settings
        self.controller = Controller(source)
        self.commands = Commands(settings, source)
        self.executor = ThreadPoolExecutor(WORKERS, thread_name_prefix="cnc-web")
        self.urgent_executor = ThreadPoolExecutor(URGENT_WORKERS, thread_name_prefix="cnc-stop")
        self.clients: set[Client] = set()
        self.status: dict[str, Any] = dict(DISCONNECTED)
        self._poller: asyncio.Task[None] | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self.preview_key: tuple[str, int] | None = None  # (file, mtime) of preview_result
        self.preview_result: dict[str, Any] = {}
        self.messages = UserMessages(settings.message_pins)  # [DISPLAY] MESSAGE_* dialogs
        self.problems = list(settings.problems)  # shown to every page that connects

    # ---------------------------------------------------------------- status
    def poll(self) -> list[dict[str, Any]]:
        """Read status and messages once; the messages for the pages (status diff first)."""
        try:
            new = snapshot(self.controller.poll(), self.settings)
            messages = self.controller.read_messages()
        except cnc.error:
            self.controller.reset()  # the next poll finds a restarted controller
            new, messages = dict(DISCONNECTED), []
        outgoing = []
        changed = diff(self.status, new)
        if changed:
            self.status.update(changed)
            outgoing.append({"type": "status", "data": changed})
        for message in messages:
            kind = MESSAGE_KINDS.get(message.kind, "text")
            outgoing.append({"type": "notice", "kind": kind, "text": message.text})
        return outgoing + self.messages.poll()

    async def _poll_forever(self) -> None:
        """Poll every cycle_time_s, on a fixed schedule (a late cycle does not shift the
        next ones; cycles missed altogether are skipped)."""
        loop = asyncio.get_running_loop()
        period = self.settings.cycle_time_s
        due = loop.time()
        while True:
            for message in self.poll():
                await self.broadcast(message)
            due = max(due + period, loop.time())
            await asyncio.sleep(due - loop.time())

    async def broadcast(self, message: dict[str, Any]) -> None:
        text = json.dumps(message)
        for client in list(self.clients):
            await send(client, text)

    async def start(self, _app: web.Application) -> None:
        if self.messages.pins:
            try:
                self.messages.open()
            except HalError as exc:
                self.problems.append(f"[DISPLAY] MESSAGE_* pins not created: {exc}")
        for problem in self.problems:
            print(f"cnc ui web: {problem}", file=sys.stderr, flush=True)
        self._poller = asyncio.create_task(self._poll_forever())

    async def stop(self, _app: web.Application) -> None:
        if self._poller is not None:
            self._poller.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._poller
        self.commands.is_stopping.set()
        for client in list(self.clients):
            await client.socket.close()
        for executor in (self.executor, self.urgent_executor):
            executor.shutdown(wait=False, cancel_futures=True)
        self.controller.close()
        self.messages.close()

    # ---------------------------------------------------------------- commands
    async def run(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """Run one command of a page; the result message."""
        answer: dict[str, Any] = {"type": "result", "id": request.get("id")}
        if not client.is_control:
            return answer | {"status": "ERROR", "message": "read-only access: command refused"}
        name = request.get("cmd")
        if name == "answer":  # a message dialog: answered here, in the event loop
            return answer | await self._answer_dialog(request)
        if name == "jog":
            async with client.jog_lock:  # a stop must never overtake its start
                self._track_jog(client, request)
                outcome = await self._execute(request)
        else:
            outcome = await self._execute(request)
        if name in ("mdi", "macro"):
            await self.broadcast({"type": "history", "lines": list(self.commands.mdi_history)})
        return answer | outcome

    async def _answer_dialog(self, request: dict[str, Any]) -> dict[str, Any]:
        """{"cmd": "answer", "name": pin name, "is_yes": bool}: close the dialog everywhere."""
        try:
            closing = self.messages.answer(request.get("name"), request.get("is_yes"))
        except ValueError as exc:
            return {"status": "ERROR", "message": f"answer: {exc}"}
        await self.broadcast(closing)
        return {"status": "DONE", "message": "DONE"}

    async def _execute(self, request: dict[str, Any]) -> dict[str, Any]:
        loop = asyncio.get_running_loop()
        executor = self.urgent_executor if is_urgent(request) else self.executor
        try:
            message = await loop.run_in_executor(executor, self.commands.run, request)
        except CommandError as exc:
            return {"status": "ERROR", "message": str(exc), "is_reported": exc.is_reported}
        return {"status": "DONE", "message": message}

    def _track_jog(self, client: Client, request: dict[str, Any]) -> None:
        """Remember the continuous jogs a page started, to stop them if it goes away."""
        try:
            joint = self.commands.joint_of(request)
        except CommandError:
            return
        if request.get("action") == "start":
            client.jogging.add(joint)
        else:
            client.jogging.discard(joint)

    async def disconnected(self, client: Client) -> None:
        self.clients.discard(client)
        for joint in sorted(client.jogging):
            async with client.jog_lock:
                await self._execute({"cmd": "jog", "action": "stop", "joint": joint})

    def make_preview(self, program: str) -> dict[str, Any]:
        """Run ``program`` through a preview interpreter of its own (in a worker thread)."""
        settings = self.settings
        ini = None
        if settings.ini_file:
            with contextlib.suppress(IniError):
                ini = IniFile.load(settings.ini_file)
        return preview(
            program,
            units_per_mm=settings.units_per_mm,
            parameter_file=str(settings.parameter_file or ""),
            tool_table=str(settings.tool_table) if settings.tool_table else None,
            ini=ini,
        )

    def keep(self, task: asyncio.Task[Any]) -> None:
        """Hold a reference to a task until it is done (else it may be collected)."""
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def page_config(self, client_is_control: bool) -> dict[str, Any]:
        return self.settings.page_config() | {
            "is_control": client_is_control,
            "mdi_history": list(self.commands.mdi_history),
        }


def is_urgent(request: dict[str, Any]) -> bool:
    """Whether a command stops something: E-stop, abort, the end of a jog."""
    name = request.get("cmd")
    return name in ("abort", "estop") or (name == "jog" and request.get("action") == "stop")


async def send(client: Client, text: str) -> None:
    """Send to a page; a page that went away is dropped, never an error of the server."""
    if client.socket.closed:
        return
    with contextlib.suppress(ConnectionError, RuntimeError):
        await client.socket.send_str(text)


# ------------------------------------------------------------------ access
@dataclass(frozen=True)
class Access:
    """The tokens: none (everyone may control), or control and/or read-only ones."""

    token: str | None = None
    read_only_token: str | None = None

    @property
    def is_required(self) -> bool:
        return bool(self.token or self.read_only_token)

    def role(self, given: str | None) -> str | None:
        """ "control", "watch" or None (refused) for a request bringing ``given``."""
        if not self.is_required:
            return "control"
        if given and self.token and hmac.compare_digest(given, self.token):
            return "control"
        if given and self.read_only_token and hmac.compare_digest(given, self.read_only_token):
            return "watch"
        return None


def given_token(request: web.Request) -> tuple[str | None, bool]:
    """The token a request brings, and whether it came in the URL or header (so the
    server sets the cookie for the page's own asset requests)."""
    header = request.headers.get("Authorization", "")
    if header.startswith("Bearer "):
        return header[len("Bearer ") :].strip(), True
    if "token" in request.query:
        return request.query["token"], True
    return request.cookies.get(COOKIE), False


def is_same_origin(request: web.Request) -> bool:
    """Whether a browser request comes from this server's page (no Origin: not a browser
    page, e.g. a script, which the token guards)."""
    origin = request.headers.get("Origin")
    return origin is None or urlsplit(origin).netloc == request.host


def access_middleware(access: Access) -> Callable[..., Awaitable[web.StreamResponse]]:
    @web.middleware
    async def check(
        request: web.Request, handler: Callable[[web.Request], Awaitable[web.StreamResponse]]
    ) -> web.StreamResponse:
        token, is_explicit = given_token(request)
        role = access.role(token)
        if role is None:
            return web.Response(status=401, text="401: a valid token is required\n")
        request[IS_CONTROL] = role == "control"
        response = await handler(request)
        if access.is_required and is_explicit and token and not response.prepared:
            response.set_cookie(COOKIE, token, httponly=True, samesite="Strict")
        return response

    return check


# ------------------------------------------------------------------ routes
async def index(request: web.Request) -> web.StreamResponse:
    return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-cache"})


async def config(request: web.Request) -> web.Response:
    return web.json_response(request.app[HUB].page_config(request[IS_CONTROL]))


async def files(request: web.Request) -> web.Response:
    hub = request.app[HUB]
    loop = asyncio.get_running_loop()
    names = await loop.run_in_executor(hub.executor, hub.commands.program_files)
    return web.json_response({"files": names})


async def program(request: web.Request) -> web.Response:
    """The text of the program task has open (stat.file)."""
    name = request.app[HUB].status.get("file") or ""
    path = Path(name)
    if not name or not path.is_file():
        return web.json_response({"file": name, "lines": []})
    loop = asyncio.get_running_loop()
    lines = await loop.run_in_executor(request.app[HUB].executor, read_lines, path)
    return web.json_response({"file": name, "lines": lines})


def read_lines(path: Path) -> list[str]:
    """The lines of a program (at most MAX_PROGRAM_BYTES of it), whatever its encoding."""
    with open(path, "rb") as file:
        data = file.read(MAX_PROGRAM_BYTES)
    return data.decode("utf-8", errors="replace").splitlines()


async def toolpath(request: web.Request) -> web.Response:
    """The preview of the program task has open (computed once per file version)."""
    hub = request.app[HUB]
    name = hub.status.get("file") or ""
    path = Path(name)
    if not name or not path.is_file():
        return web.json_response({"file": name, "points": [], "error": None})
    key = (name, path.stat().st_mtime_ns)
    if hub.preview_key != key:
        loop = asyncio.get_running_loop()
        hub.preview_result = await loop.run_in_executor(hub.executor, hub.make_preview, name)
        hub.preview_key = key
    return web.json_response({"file": name} | hub.preview_result)


async def tools(request: web.Request) -> web.Response:
    """The tool table (iocontrol's, through stat.tool_table; index 0 is the spindle), with
    the comments of the tool table file."""
    hub = request.app[HUB]
    try:
        table = hub.controller.poll().tool_table
    except cnc.error:
        table = ()
    settings = hub.settings
    loop = asyncio.get_running_loop()
    comments = await loop.run_in_executor(
        hub.executor, tool_comments, settings.tool_table, settings.is_random_toolchanger
    )
    entries = [
        {"tool": entry.id, "index": index, "z": entry.zoffset, "x": entry.xoffset,
         "diameter": entry.diameter, "comment": comments.get(entry.id, "")}
        for index, entry in enumerate(table)
        if entry.id > 0 and (index > 0 or settings.is_random_toolchanger)  # 0: the spindle
    ]  # fmt: skip
    return web.json_response({"tools": entries})


async def upload(request: web.Request) -> web.Response:
    """A program sent by the page (multipart field "file"), saved in PROGRAM_PREFIX."""
    if not request[IS_CONTROL]:
        raise web.HTTPForbidden(text="403: read-only access\n")
    if not is_same_origin(request):
        raise web.HTTPForbidden(text="403: upload from another site\n")
    settings = request.app[HUB].settings
    reader = await request.multipart()
    part = await reader.next()
    if part is None or part.name != "file" or not part.filename:  # type: ignore[union-attr]
        raise web.HTTPBadRequest(text="400: expected a file in the field 'file'\n")
    name = Path(part.filename).name  # type: ignore[union-attr]
    if Path(name).suffix.lower() not in settings.extensions or settings.program_prefix is None:
        allowed = ", ".join(settings.extensions)
        raise web.HTTPBadRequest(text=f"400: {name}: not a program file ({allowed})\n")
    data = await part.read()  # type: ignore[union-attr]
    loop = asyncio.get_running_loop()
    target = settings.program_prefix / name
    await loop.run_in_executor(request.app[HUB].executor, save_whole, target, data)
    return web.json_response({"file": name})


def save_whole(target: Path, data: bytes) -> None:
    """Write a file whole or not at all (task may be reading the old one)."""
    partial = target.with_name(f".{target.name}.part")
    partial.write_bytes(data)
    partial.replace(target)


async def websocket(request: web.Request) -> web.WebSocketResponse:
    if not is_same_origin(request):
        raise web.HTTPForbidden(text="403: websocket from another site\n")
    hub = request.app[HUB]
    socket = web.WebSocketResponse(heartbeat=20)
    await socket.prepare(request)
    client = Client(socket, request[IS_CONTROL])
    hub.clients.add(client)
    tasks: set[asyncio.Task[None]] = set()
    try:
        await send(
            client, json.dumps({"type": "config", "data": hub.page_config(client.is_control)})
        )
        await send(client, json.dumps({"type": "status", "data": hub.status}))
        for problem in hub.problems:
            await send(client, json.dumps({"type": "notice", "kind": "error", "text": problem}))
        for dialog in hub.messages.open_dialogs():
            await send(client, json.dumps(dialog))
        async for message in socket:
            if message.type != WSMsgType.TEXT:
                continue
            task = asyncio.create_task(_answer(hub, client, message.data))
            tasks.add(task)  # kept until done, so it is not garbage collected
            task.add_done_callback(tasks.discard)
    finally:
        # A task of its own: the handler may be cancelled when the connection drops.
        hub.keep(asyncio.create_task(hub.disconnected(client)))
    return socket


async def _answer(hub: Hub, client: Client, text: str) -> None:
    """Parse and run one command; a bad one gets an ERROR result, never a crash."""
    try:
        request = json.loads(text)
    except ValueError as exc:
        request, problem = {}, f"bad request: not JSON ({exc})"
    else:
        problem = None if isinstance(request, dict) else "bad request: expected a JSON object"
    if problem is not None:
        reply = {"type": "result", "id": None, "status": "ERROR", "message": problem}
    else:
        reply = await hub.run(client, request)
    await send(client, json.dumps(reply))


def make_app(
    settings: Settings, source: str | None = None, access: Access = Access()
) -> web.Application:
    """The web application for one controller (``source``: INI/NML file or None)."""
    app = web.Application(
        middlewares=[access_middleware(access)], client_max_size=MAX_PROGRAM_BYTES
    )
    hub = Hub(settings, source)
    app[HUB] = hub
    app.on_startup.append(hub.start)
    app.on_cleanup.append(hub.stop)
    app.router.add_get("/", index)
    app.router.add_get("/ws", websocket)
    app.router.add_get("/api/config", config)
    app.router.add_get("/api/files", files)
    app.router.add_get("/api/program", program)
    app.router.add_get("/api/preview", toolpath)
    app.router.add_get("/api/tools", tools)
    app.router.add_post("/api/upload", upload)
    app.router.add_static("/static/", STATIC)
    return app


# ------------------------------------------------------------------ command line
def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cnc ui web", description="Operator UI in the browser, attached to the controller."
    )
    parser.add_argument("ini", nargs="?", help="the machine's INI file (default: the running one)")
    parser.add_argument("--host", default=DEFAULT_HOST, help=f"address (default {DEFAULT_HOST})")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="port (default 8750)")
    parser.add_argument(
        "--token",
        default=os.environ.get(TOKEN_ENV) or None,
        help=f"token needed for access (default ${TOKEN_ENV})",
    )
    parser.add_argument(
        "--read-only-token",
        default=os.environ.get(READ_ONLY_TOKEN_ENV) or None,
        help=f"token that may only watch (default ${READ_ONLY_TOKEN_ENV})",
    )
    return parser


def running_ini() -> str | None:
    """The INI file of the running machine (stat.ini_filename), or None."""
    probe = Controller()
    try:
        return probe.ini_file()
    finally:
        probe.close()


def main(argv: list[str]) -> int:
    """``cnc ui web ...``: ``argv`` starts with "web"."""
    if not argv or argv[0] != "web":
        print("usage: cnc ui web [INI] [--host H] [--port P] [--token T]", file=sys.stderr)
        return 2
    args = _parser().parse_args(argv[1:])
    if not is_loopback(args.host) and not args.token:
        print(
            f"cnc ui web: refusing to serve on {args.host} without a token: give --token or "
            f"set ${TOKEN_ENV} (only 127.0.0.1 may go without one)",
            file=sys.stderr,
        )
        return 2
    try:
        ini = args.ini or running_ini()
        settings = Settings.load(ini) if ini else Settings()
    except (cnc.error, IniError) as exc:  # IniError: "file:line: cause"
        print(f"cnc ui web: {exc}", file=sys.stderr)
        return 2
    app = make_app(settings, args.ini, Access(args.token, args.read_only_token))
    print(f"cnc ui web: serving http://{args.host}:{args.port}/", flush=True)
    # SIGINT/SIGTERM stop it; pages are closed by Hub.stop, so the shutdown need not wait.
    web.run_app(
        app, host=args.host, port=args.port, print=None, access_log=None, shutdown_timeout=1
    )
    return 0
