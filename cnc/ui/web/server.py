"""``cnc ui web [INI] [--host H] [--port P] [--token T] [--read-only-token R]``: the operator
UI in the browser (issue 7, issue 18, GUI-*) and the public API (issue 19, API.md).

One process attaches to the controller like any UI (``cnc.stat``, ``cnc.command``,
``cnc.error_channel``) and serves the page (``static/``) and the API, JSON-RPC 2.0
(rpc.py), which the page uses too:

- ``/api/v1/ws``: a websocket; calls in, their responses and the notifications a client
  subscribed to out (``notify.status``: the status fields that changed, every
  [DISPLAY]CYCLE_TIME; ``notify.notice``: the error channel; ...).
- ``POST /api/v1/rpc``: one call or a batch per request (``application/json``).

HTTP for the page's bulk data: ``/`` the page, ``/static/*`` its assets, ``/api/config``
what the page offers (from the INI), ``/api/files`` the programs of PROGRAM_PREFIX,
``/api/program/text`` the open program's text, ``/api/preview/data`` its toolpath (binary,
preview.RECORD), both for the program ``number`` the "program" notification names,
``/api/tools`` the tool table, ``/api/offsets`` the work offsets, ``/api/editor?file=`` a
program's text for the editor, ``POST /api/upload`` a program into PROGRAM_PREFIX.

Access: each request is someone (apikeys.Identity) with scopes. A server bound to a
loopback address (127.0.0.1 by default) lets requests without a key in with every scope;
any other address needs a key for every request. A key is a named API key of the keys
file next to the INI (``cnc api-key``), or one of the two tokens of the command line
(``--token``/$CNC_WEB_TOKEN: every scope; ``--read-only-token``/$CNC_WEB_READ_ONLY_TOKEN:
read), given as ``Authorization: Bearer KEY``, ``?token=KEY`` or the cookie the server
sets on the first request that had it; a wrong key gets 401 anywhere. Websockets, uploads
and API calls from another site's page (Origin not this server) are refused. A request
whose Host is not the address the server is bound to, ``localhost`` or a name of
[DISPLAY]WEB_ALLOWED_HOSTS is refused (421): a page of another site that re-binds its own
name to 127.0.0.1 (DNS rebinding) would otherwise be "same origin" and could drive the
machine.
"""

from __future__ import annotations

import argparse
import asyncio
import hmac
import ipaddress
import os
import sys
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, replace
from pathlib import Path
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

import cnc
from cnc.apikeys import (
    CONFIGURE,
    LOOPBACK,
    OPERATE,
    READ,
    ApiKeyError,
    Identity,
    KeyStore,
    keys_file_for,
)
from cnc.ini import IniError
from cnc.ui.controller import running_ini
from cnc.ui.web.hub import Client, Hub, send
from cnc.ui.web.jobs import RECORD_SIZE
from cnc.ui.web.priority import raise_loop_priority, watch_jobs_without_threads
from cnc.ui.web.settings import Settings

STATIC = Path(__file__).with_name("static")
DEFAULT_HOST, DEFAULT_PORT = "127.0.0.1", 8750
TOKEN_ENV, READ_ONLY_TOKEN_ENV = "CNC_WEB_TOKEN", "CNC_WEB_READ_ONLY_TOKEN"
COOKIE = "cnc_token"
MAX_UPLOAD_BYTES = 200_000_000  # a program of millions of lines
MAX_EDITOR_BYTES = 2_000_000  # the editor takes programs up to this size
MAX_PREVIEW_CHUNK = 65_536  # toolpath records per /api/preview/data answer (1 MB)
WEBSOCKET_MAX_MESSAGE = 8_000_000  # an editor's text, saved or checked
HUB = web.AppKey("hub", Hub)
IDENTITY = web.RequestKey("identity", Identity)  # who the request is, with which scopes


# ------------------------------------------------------------------ access
@dataclass(frozen=True)
class Access:
    """Who may come in: with ``is_open`` (a loopback server) anyone without a key; with a
    key, the command line's tokens (``token``: every scope, ``read_only_token``: read)
    and the named keys of ``keys`` (the keys file)."""

    token: str | None = None
    read_only_token: str | None = None
    keys: KeyStore | None = None
    is_open: bool = True

    @property
    def is_required(self) -> bool:
        return not self.is_open or bool(self.token or self.read_only_token)

    def cached(self, given: str | None) -> Identity | bool | None:
        """The identity of a request bringing ``given`` when it is known at once; False
        when only the keys file can tell (``identify``, in a worker: scrypt is slow)."""
        if not given:
            return None if self.is_required else LOOPBACK
        if self.token and hmac.compare_digest(given, self.token):
            return Identity("token", LOOPBACK.scopes)
        if self.read_only_token and hmac.compare_digest(given, self.read_only_token):
            return Identity("read-only-token", frozenset({READ}))
        if self.keys is None:
            return None
        return self.keys.checked(given) or False

    def identify(self, given: str) -> Identity | None:
        return self.keys.identify(given) if self.keys is not None else None


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


@dataclass(frozen=True)
class HostCheck:
    """Which Host headers the server answers: its bound address, ``localhost``, and the
    names of [DISPLAY]WEB_ALLOWED_HOSTS. A server bound to every address (0.0.0.0, ::)
    also answers any IP address: an address cannot be re-bound by another site's DNS."""

    bound: str = DEFAULT_HOST
    names: tuple[str, ...] = ()

    def is_allowed(self, host_header: str) -> bool:
        name = _host_name(host_header)
        if name is None:
            return False
        if name == "localhost" or name in self.names:
            return True
        try:
            address = ipaddress.ip_address(name)
        except ValueError:
            return False  # a DNS name nobody configured
        try:
            bound = ipaddress.ip_address(self.bound)
        except ValueError:  # bound by name (e.g. "localhost"): its loopback addresses
            return address.is_loopback
        return bound.is_unspecified or address == bound


def _host_name(header: str) -> str | None:
    """The name of a Host header, lower case, without port or IPv6 brackets."""
    text = header.strip().lower()
    if not text:
        return None
    if text.startswith("["):  # [::1]:8750
        end = text.find("]")
        return text[1:end] if end > 0 else None
    name, _, port = text.rpartition(":") if text.count(":") == 1 else (text, "", "")
    if port and not port.isdigit():
        return None
    return name.rstrip(".")


def access_middleware(
    access: Access, hosts: HostCheck
) -> Callable[..., Awaitable[web.StreamResponse]]:
    @web.middleware
    async def check(
        request: web.Request, handler: Callable[[web.Request], Awaitable[web.StreamResponse]]
    ) -> web.StreamResponse:
        if not hosts.is_allowed(request.headers.get("Host", "")):
            return web.Response(
                status=421,
                text="421: this server does not answer that host name (add it to "
                "[DISPLAY]WEB_ALLOWED_HOSTS to reach the machine by it)\n",
            )
        token, is_explicit = given_token(request)
        identity = access.cached(token)
        if identity is False:
            loop = asyncio.get_running_loop()
            identity = await loop.run_in_executor(None, access.identify, token)
        if not isinstance(identity, Identity):
            return web.Response(status=401, text="401: a valid key is required\n")
        request[IDENTITY] = identity
        response = await handler(request)
        if is_explicit and token and not response.prepared:
            response.set_cookie(COOKIE, token, httponly=True, samesite="Strict")
        return response

    return check


# ------------------------------------------------------------------ routes
async def index(request: web.Request) -> web.StreamResponse:
    return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-cache"})


async def config(request: web.Request) -> web.Response:
    return web.json_response(request.app[HUB].page_config(request[IDENTITY].allows(OPERATE)))


async def files(request: web.Request) -> web.Response:
    hub = request.app[HUB]
    loop = asyncio.get_running_loop()
    names = await loop.run_in_executor(hub.executor, hub.commands.program_files)
    return web.json_response({"files": names})


def _analysis(request: web.Request):  # type: ignore[no-untyped-def]
    """The analysis of the open program the request names (``number``), or 409."""
    current = request.app[HUB].jobs.current
    if current is None or request.query.get("number") != str(current.number):
        raise web.HTTPConflict(text="409: that program is no longer the open one\n")
    return current


async def program_text(request: web.Request) -> web.StreamResponse:
    """The text of the open program, as it is on disk (the page splits it into lines):
    sent by the operating system, the server's loop never reads it."""
    analysis = _analysis(request)
    return web.FileResponse(
        analysis.path,
        headers={"Cache-Control": "no-store", "Content-Type": "text/plain; charset=utf-8"},
    )


async def preview_data(request: web.Request) -> web.Response:
    """The open program's toolpath from record ``from`` on: what the preview job has
    written so far (whole records, at most MAX_PREVIEW_CHUNK)."""
    analysis = _analysis(request)
    try:
        first = max(int(request.query.get("from", "0")), 0)
    except ValueError:
        raise web.HTTPBadRequest(text="400: 'from' must be a whole number\n") from None
    count = min(analysis.preview_points - first, MAX_PREVIEW_CHUNK)
    if count <= 0:
        return web.Response(body=b"", content_type="application/octet-stream")
    loop = asyncio.get_running_loop()
    path = analysis.folder / "preview.bin"
    data = await loop.run_in_executor(
        request.app[HUB].executor, read_range, path, first * RECORD_SIZE, count * RECORD_SIZE
    )
    return web.Response(
        body=data, content_type="application/octet-stream", headers={"Cache-Control": "no-store"}
    )


def read_range(path: Path, start: int, size: int) -> bytes:
    with open(path, "rb") as file:
        file.seek(start)
        return file.read(size)


async def tools(request: web.Request) -> web.Response:
    return web.json_response(await request.app[HUB].tools())


async def offsets(request: web.Request) -> web.Response:
    return web.json_response(await request.app[HUB].offsets())


async def editor_text(request: web.Request) -> web.Response:
    """A program under PROGRAM_PREFIX (``file``), for the editor."""
    hub = request.app[HUB]
    try:
        path = hub.commands.program_path(request.query.get("file", ""))
    except Exception as exc:  # CommandError: no such program
        raise web.HTTPNotFound(text=f"404: {exc}\n") from None
    if path.stat().st_size > MAX_EDITOR_BYTES:
        raise web.HTTPRequestEntityTooLarge(
            MAX_EDITOR_BYTES, path.stat().st_size, text="413: too large for the editor\n"
        )
    loop = asyncio.get_running_loop()
    data = await loop.run_in_executor(hub.executor, path.read_bytes)
    return web.json_response(
        {"file": request.query["file"], "text": data.decode("utf-8", "replace")}
    )


async def upload(request: web.Request) -> web.Response:
    """A program sent by the page (multipart field "file"), saved in PROGRAM_PREFIX."""
    if not request[IDENTITY].allows(CONFIGURE):
        raise web.HTTPForbidden(text="403: an upload needs the configure scope\n")
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
    """``/api/v1/ws``: JSON-RPC 2.0 both ways (rpc.py); each message is answered in a task
    of its own, so a stop never waits for the answer to an earlier call."""
    if not is_same_origin(request):
        raise web.HTTPForbidden(text="403: websocket from another site\n")
    hub = request.app[HUB]
    socket = web.WebSocketResponse(heartbeat=20, max_msg_size=WEBSOCKET_MAX_MESSAGE)
    await socket.prepare(request)
    client = Client(socket, request[IDENTITY])
    hub.clients.add(client)
    tasks: set[asyncio.Task[None]] = set()
    try:
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
    reply = await hub.rpc.handle(client, text)
    if reply is not None:
        await send(client, reply)


async def rpc_post(request: web.Request) -> web.Response:
    """``POST /api/v1/rpc``: one call or a batch; 204 when all were notifications. Only
    ``application/json`` (a browser cannot send that to another site without asking it
    first, CORS), and never from another site's page."""
    if not is_same_origin(request):
        raise web.HTTPForbidden(text="403: API call from another site\n")
    if request.content_type != "application/json":
        raise web.HTTPUnsupportedMediaType(text="415: send application/json\n")
    hub = request.app[HUB]
    reply = await hub.rpc.handle(Client(None, request[IDENTITY]), await request.read())
    if reply is None:
        return web.Response(status=204)
    return web.Response(text=reply, content_type="application/json")


def make_app(
    settings: Settings,
    source: str | None = None,
    access: Access = Access(),
    hosts: HostCheck | None = None,
) -> web.Application:
    """The web application for one controller (``source``: INI/NML file or None), bound
    to ``hosts.bound`` (default 127.0.0.1; its allowed names from the settings)."""
    hosts = hosts or HostCheck(DEFAULT_HOST, settings.allowed_hosts)
    if access.keys is None and settings.ini_file is not None:
        access = replace(access, keys=KeyStore(keys_file_for(settings.ini_file)))
    app = web.Application(
        middlewares=[access_middleware(access, hosts)], client_max_size=MAX_UPLOAD_BYTES
    )
    hub = Hub(settings, source)
    app[HUB] = hub
    app.on_startup.append(hub.start)
    app.on_cleanup.append(hub.stop)
    app.router.add_get("/", index)
    app.router.add_get("/api/v1/ws", websocket)
    app.router.add_post("/api/v1/rpc", rpc_post)
    app.router.add_get("/api/config", config)
    app.router.add_get("/api/files", files)
    app.router.add_get("/api/program/text", program_text)
    app.router.add_get("/api/preview/data", preview_data)
    app.router.add_get("/api/tools", tools)
    app.router.add_get("/api/offsets", offsets)
    app.router.add_get("/api/editor", editor_text)
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


def main(argv: list[str]) -> int:
    """``cnc ui web ...``: ``argv`` starts with "web"."""
    if not argv or argv[0] != "web":
        print("usage: cnc ui web [INI] [--host H] [--port P] [--token T]", file=sys.stderr)
        return 2
    args = _parser().parse_args(argv[1:])
    try:
        ini = args.ini or running_ini()
        settings = Settings.load(ini) if ini else Settings()
        keys = KeyStore(keys_file_for(ini)) if ini else None
        has_keys = keys is not None and keys.has_keys()
    except (cnc.error, IniError, ApiKeyError) as exc:  # "file:line: cause"
        print(f"cnc ui web: {exc}", file=sys.stderr)
        return 2
    is_open = is_loopback(args.host)
    if not is_open and not (args.token or has_keys):
        print(
            f"cnc ui web: refusing to serve on {args.host} without a key: create one "
            f"(cnc api-key create NAME --scope operate), give --token or set ${TOKEN_ENV} "
            "(only a loopback address may go without one)",
            file=sys.stderr,
        )
        return 2
    problem = raise_loop_priority()  # (before any thread starts)
    watch_jobs_without_threads()
    if problem:
        print(f"cnc ui web: {problem}", file=sys.stderr, flush=True)
    hosts = HostCheck(args.host, settings.allowed_hosts)
    access = Access(args.token, args.read_only_token, keys, is_open)
    app = make_app(settings, args.ini, access, hosts)
    print(f"cnc ui web: serving http://{args.host}:{args.port}/", flush=True)
    # SIGINT/SIGTERM stop it; pages are closed by Hub.stop, so the shutdown need not wait.
    web.run_app(
        app, host=args.host, port=args.port, print=None, access_log=None, shutdown_timeout=1
    )
    return 0
