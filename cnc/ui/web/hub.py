"""The web UI's link to the controller: the status and messages pushed to every client, the
program's preview and time estimate, program runs, and every command of a client.

Clients speak the public API (rpc.py: JSON-RPC 2.0), which calls ``Hub.dispatch(client,
request)`` for the controller's commands: the one place where they are handled:
most are controller commands run in worker threads (``commands.py``), a few are answered in
the event loop (message dialogs, continuous jog refreshes, editor checks, probing). Stops
(E-stop, abort, the end of a jog) go to worker threads of their own, so they never queue
behind a long MDI line; nothing else in the server's process does long work (previews and
estimates run in processes of their own, ``jobs.py``), so a stop is passed on at once.

Continuous jogs are leased: a page that starts one re-sends ``{"cmd": "jog", "action":
"hold"}`` while the key or button is held (every ``JOG_HOLD_S``); the hub stops a jog whose
page has not held it for ``JOG_LEASE_S``, and every jog of a page that disconnects, so a
page that hangs, loses its network or is closed never leaves the machine jogging.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
import time
import traceback
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cnc
from cnc.api import safety
from cnc.apikeys import OPERATE, Identity
from cnc.ui.controller import Controller
from cnc.ui.formatting import MESSAGE_KINDS
from cnc.ui.web import probing
from cnc.ui.web.commands import CommandError, Commands, tool_comments
from cnc.ui.web.job import JobTracker
from cnc.ui.web.jobs import ProgramJobs
from cnc.ui.web.messages import UserMessages
from cnc.ui.web.notices import Notices
from cnc.ui.web.offsets import offsets_table, read_parameters
from cnc.ui.web.priority import raise_worker_priority
from cnc.ui.web.rpc import EVENT_OF_TYPE, Rpc, notification
from cnc.ui.web.settings import Settings
from cnc.ui.web.status import DISCONNECTED, FIELDS, diff, snapshot
from hal.core import HalError
from nml.commands import Handlers, Refused, handler

WORKERS = 8  # commands waiting for the controller at once
URGENT_WORKERS = 2  # for stops, which must never queue behind long MDI lines
JOG_HOLD_S = 0.1  # how often a page re-sends "hold" while a continuous jog is held
JOG_LEASE_S = 0.3  # a continuous jog not held for this long is stopped
JOG_CHECK_S = 0.05
PROBE_TIMEOUT_S = 600.0  # one probing step (a slow search may take minutes)
# Commands that go through even when the status says the controller is offline: they must
# never wait for a status poll to notice that it is back.
ALWAYS_SENT = ("estop", "abort")


@dataclass
class JogLease:
    """A continuous jog a client holds: what it moves (``Commands.jog_target``: its stop
    must name the same) and when the client last held it (monotonic)."""

    target: tuple[bool, int]
    held: float


def jog_name(request: dict[str, Any]) -> str:
    """What a client calls a jog: an axis letter or "joint N"."""
    if "joint" in request:
        return f"joint {request['joint']}"
    return str(request.get("axis", "")).upper()


@dataclass(eq=False)
class Client:
    """One API client: a websocket (a page, a script), or one HTTP call (no socket)."""

    socket: Any  # web.WebSocketResponse (or anything with send_str, closed), None for HTTP
    identity: Identity
    # What it subscribed to (rpc.py): status fields, event kinds; nothing at first.
    status_fields: frozenset[str] = frozenset()
    events: frozenset[str] = frozenset()
    jogs: dict[str, JogLease] = field(default_factory=dict)  # by jog_name()
    jog_lock: asyncio.Lock = field(default_factory=asyncio.Lock)  # jogs run in order
    # Commands of one kind from one page run in the order it sent them (a slider's 40 %
    # then its reset to 100 % must not be swapped by the worker threads); kinds differ
    # freely (an override while a long MDI line runs), stops are never held.
    order_locks: dict[str, asyncio.Lock] = field(default_factory=dict)

    def order_lock(self, name: str) -> asyncio.Lock:
        return self.order_locks.setdefault(name, asyncio.Lock())

    @property
    def is_control(self) -> bool:
        return self.identity.allows(OPERATE)

    def wants(self, message: dict[str, Any]) -> dict[str, Any] | None:
        """What of a hub message this client subscribed to (None: nothing)."""
        kind = message["type"]
        if kind == "status":
            if message["data"].keys() <= self.status_fields:
                return message  # all of it (the page): encoded once for all such clients
            data = {k: v for k, v in message["data"].items() if k in self.status_fields}
            return {"type": "status", "data": data} if data else None
        return message if EVENT_OF_TYPE.get(kind) in self.events else None


def is_urgent(request: dict[str, Any]) -> bool:
    """Whether a command stops something: E-stop, abort, the end of a jog."""
    name = request.get("cmd")
    return name in ("abort", "estop") or (name == "jog" and request.get("action") == "stop")


def on_the_safety_board(request: dict[str, Any]) -> dict[str, Any]:
    """An abort or E-stop goes on the machine's safety board at once, here in the event
    loop (a lock-free write: motion and task act on it within a period), before a worker
    thread sends the command, which carries its stamp ("board_stamp") so that task acts
    once. Worker threads can be slow to start while the server is busy (up to 45 ms seen
    under load); the board never waits for them."""
    name = request.get("cmd")
    stamp = 0
    if name == "abort":
        stamp = safety.request_abort()
    elif name == "estop" and request.get("on") is True:
        stamp = safety.request_estop()
    return request | {"board_stamp": stamp} if name in ("abort", "estop") else request


async def send(client: Client, text: str) -> None:
    """Send to a client; one that went away is dropped, never an error of the server."""
    if client.socket is None or client.socket.closed:
        return
    with contextlib.suppress(ConnectionError, RuntimeError):
        await client.socket.send_str(text)


@dataclass
class ProbeState:
    """The probing helper running or last run, as every page shows it."""

    kind: str = ""
    steps: list[str] = field(default_factory=list)
    current: int = -1
    state: str = "idle"  # running, done, failed
    message: str = ""
    result: dict[str, Any] | None = None

    def message_for_pages(self) -> dict[str, Any]:
        return {"type": "probe", **self.__dict__}


class Hub:
    """The controller's status and messages, pushed to every connected page."""

    def __init__(self, settings: Settings, source: str | None) -> None:
        self.settings = settings
        self.controller = Controller(source)
        self.commands = Commands(settings, source)
        self.executor = ThreadPoolExecutor(
            WORKERS, thread_name_prefix="cnc-web", initializer=raise_worker_priority
        )
        self.urgent_executor = ThreadPoolExecutor(
            URGENT_WORKERS, thread_name_prefix="cnc-stop", initializer=raise_worker_priority
        )
        self.clients: set[Client] = set()
        self.status: dict[str, Any] = dict(DISCONNECTED)
        self.notices = Notices()
        self.jobs = ProgramJobs(settings)
        self.tracker = JobTracker(settings.job_history_file)
        self.probe = ProbeState()
        self.tool_setter_reference_z: float | None = None  # see probing.py (kept in memory)
        self.messages = UserMessages(settings.message_pins)  # [DISPLAY] MESSAGE_* dialogs
        self.problems = list(settings.problems)  # shown to every page that connects
        self._loops: list[asyncio.Task[None]] = []
        self._tasks: set[asyncio.Task[Any]] = set()
        self._position: list[float] | None = None  # machine position of the last poll
        self.rpc = Rpc(self)  # the public API: every client's requests come through it
        self.handlers = Handlers(self)  # the commands answered here (@handler below)

    # ---------------------------------------------------------------- status
    def poll(self) -> list[dict[str, Any]]:
        """Read status and messages once; the messages for the pages (status diff first)."""
        now = time.monotonic()
        try:
            stat = self.controller.poll()
            new = snapshot(stat, self.settings)
            self._position = list(stat.position)
            messages = self.controller.read_messages()
        except cnc.error:
            self.controller.reset()  # the next poll finds a restarted controller
            new, messages = dict(DISCONNECTED), []
        notices: list[dict[str, Any]] = []
        for message in messages:
            kind = MESSAGE_KINDS.get(message.kind, "text")
            if kind == "error":
                self.tracker.note_error()
            notices += self.notices.add(kind, message.text, now)
        notices += self.notices.due(now)
        job, job_messages = self.tracker.update(new, self.jobs.current, now)
        new["job"] = job
        outgoing = []
        changed = diff(self.status, new)
        if changed:
            self.status.update(changed)
            outgoing.append({"type": "status", "data": changed})
        return outgoing + notices + job_messages + self.messages.poll()

    async def _poll_forever(self) -> None:
        """Poll every cycle_time_s, on a fixed schedule (a late cycle does not shift the
        next ones; cycles missed altogether are skipped)."""
        loop = asyncio.get_running_loop()
        period = self.settings.cycle_time_s
        due = loop.time()
        while True:
            try:
                for message in self.poll():
                    await self.broadcast(message)
                await self._follow_program()
            except Exception:  # a bug must not end the status: said, and on with it
                traceback.print_exc(file=sys.stderr)
            due = max(due + period, loop.time())
            await asyncio.sleep(due - loop.time())

    async def _follow_program(self) -> None:
        """Analyse the program task has open when it changes; tell the pages what the
        analysis found since the last look."""
        if not self.status.get("is_connected"):
            return
        file = self.status.get("file") or ""
        if self.jobs.needs_analysis(file):
            await self.jobs.analyse(file, self._position)
        # (in a worker thread: a finished estimate of a long program is megabytes to load)
        state = await asyncio.get_running_loop().run_in_executor(self.executor, self.jobs.poll)
        if state is not None:
            await self.broadcast({"type": "program", **self.program_state(state)})

    def program_state(self, state: dict[str, Any]) -> dict[str, Any]:
        """An analysis state with the program's name within PROGRAM_PREFIX (None if it is
        elsewhere), which the page's file list selects."""
        prefix = self.settings.program_prefix
        name = None
        if prefix is not None and state["file"]:
            with contextlib.suppress(ValueError):
                name = Path(state["file"]).resolve().relative_to(prefix.resolve()).as_posix()
        return state | {"name_in_prefix": name}

    async def _watch_jogs(self) -> None:
        """Stop the continuous jogs their pages stopped holding."""
        while True:
            await asyncio.sleep(JOG_CHECK_S)
            now = time.monotonic()
            for client in list(self.clients):
                for name, lease in list(client.jogs.items()):
                    if now - lease.held > JOG_LEASE_S:
                        self.keep(asyncio.create_task(self._stop_jog(client, name)))

    async def broadcast(self, message: dict[str, Any]) -> None:
        """A hub message, to every client as far as it subscribed to it."""
        whole = None  # the text for clients that take all of it, made once
        for client in list(self.clients):
            wanted = client.wants(message)
            if wanted is None:
                continue
            if wanted is message:
                whole = whole or json.dumps(notification(message))
                await send(client, whole)
            else:
                await send(client, json.dumps(notification(wanted)))

    async def notify(self, client: Client, message: dict[str, Any]) -> None:
        """A hub message to one client, as a notification."""
        await send(client, json.dumps(notification(message)))

    async def start(self, _app: Any = None) -> None:
        if self.messages.pins:
            try:
                self.messages.open()
            except HalError as exc:
                self.problems.append(f"[DISPLAY] MESSAGE_* pins not created: {exc}")
        for problem in self.problems:
            print(f"cnc ui web: {problem}", file=sys.stderr, flush=True)
        # (run_in_executor(None, ...) of the server and aiohttp: workers as the hub's)
        asyncio.get_running_loop().set_default_executor(
            ThreadPoolExecutor(thread_name_prefix="cnc-web-io", initializer=raise_worker_priority)
        )
        self._loops = [
            asyncio.create_task(self._poll_forever()),
            asyncio.create_task(self._watch_jogs()),
        ]

    async def stop(self, _app: Any = None) -> None:
        for loop in self._loops:
            loop.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await loop
        self.tracker.close()
        self.commands.is_stopping.set()
        for client in list(self.clients):
            await client.socket.close()
        for executor in (self.executor, self.urgent_executor):
            executor.shutdown(wait=False, cancel_futures=True)
        await self.jobs.close()
        self.controller.close()
        self.messages.close()

    # ---------------------------------------------------------------- requests
    async def dispatch(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """Run one command ``{"cmd": NAME, ...arguments}`` of a client whose scope rpc.py
        checked; its outcome ``{"status": "DONE"|"ERROR", "message", ...}``. A refusal
        (``Refused``, a ``CommandError``) is the ERROR outcome, here only; an unexpected
        exception goes on to rpc.py, which answers it as an internal error."""
        name = request.get("cmd")
        try:
            outcome = await self._dispatch(client, name, request)
        except Refused as refusal:
            outcome = {"status": "ERROR", "message": refusal.reason,
                       "is_reported": refusal.is_quiet}  # fmt: skip
        if name in ("mdi", "macro"):
            await self.broadcast({"type": "history", "lines": list(self.commands.mdi_history)})
        return outcome

    async def _dispatch(self, client: Client, name: Any, request: dict[str, Any]) -> dict[str, Any]:
        handler = self.handlers.get(name) if isinstance(name, str) else None
        if handler is not None:
            return await handler(client, request)
        if not self.status.get("is_connected") and name not in ALWAYS_SENT:
            raise Refused(f"{name}: refused, the controller is offline (not running)")
        if name == "run" and isinstance(request.get("line", 0), int):
            self.tracker.expect_start(request.get("line", 0), time.monotonic())
        if is_urgent(request):
            return await self._execute(on_the_safety_board(request))
        async with client.order_lock(str(name)):
            return await self._execute(request)

    async def _execute(self, request: dict[str, Any]) -> dict[str, Any]:
        """A controller command (commands.py), in a worker thread; CommandError."""
        loop = asyncio.get_running_loop()
        executor = self.urgent_executor if is_urgent(request) else self.executor
        message = await loop.run_in_executor(executor, self.commands.run, request)
        return {"status": "DONE", "message": message}

    @handler("answer")
    async def _answer_dialog(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """{"cmd": "answer", "name": pin name, "is_yes": bool}: close the dialog everywhere."""
        try:
            closing = self.messages.answer(request.get("name"), request.get("is_yes"))
        except ValueError as exc:
            raise Refused(f"answer: {exc}") from None
        await self.broadcast(closing)
        return {"status": "DONE", "message": "DONE"}

    # ---------------------------------------------------------------- jogs
    @handler("jog")
    async def _jog(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """Jogs: "hold" refreshes a continuous jog's lease here; the others go to the
        controller, in the order the page sent them (a stop never overtakes its start)."""
        action = request.get("action")
        name = jog_name(request)
        if action == "hold":
            lease = client.jogs.get(name)
            if lease is None:
                raise Refused("jog: no continuous jog to hold")
            lease.held = time.monotonic()
            return {"status": "DONE", "message": "DONE"}
        if not self.status.get("is_connected") and action != "stop":
            raise Refused("jog: refused, the controller is offline")
        async with client.jog_lock:
            lease = client.jogs.pop(name, None)
            if lease is not None:  # a stop (or a new start) names what the start moved
                request = request | {"target": lease.target}
            elif action == "start":
                try:
                    target = await asyncio.get_running_loop().run_in_executor(
                        self.executor, self.commands.jog_target, request
                    )
                except CommandError as exc:
                    raise Refused(f"jog: {exc}") from None
                request = request | {"target": target}
            if action == "start":
                client.jogs[name] = JogLease(request["target"], time.monotonic())
            try:
                return await self._execute(request)
            except Exception:
                if action == "start":
                    client.jogs.pop(name, None)
                raise

    async def _stop_jog(self, client: Client, name: str) -> None:
        lease = client.jogs.pop(name, None)
        if lease is None:
            return  # stopped already
        async with client.jog_lock:
            stop = {"cmd": "jog", "action": "stop", "target": lease.target}
            with contextlib.suppress(CommandError):  # (said on the error channel, or offline)
                await self._execute(stop)
        if not client.socket.closed:
            text = "jog stopped: the page stopped holding it (a key or button released late?)"
            await self.notify(client, {"type": "notice", "kind": "error", "text": text})

    async def disconnected(self, client: Client) -> None:
        self.clients.discard(client)
        for name in sorted(client.jogs):
            await self._stop_jog(client, name)

    # ---------------------------------------------------------------- editor
    @handler("check_program")
    async def _check_program(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """{"cmd": "check_program", "text": ...}: the preview interpreter's errors."""
        text = request.get("text")
        if not isinstance(text, str):
            raise Refused("check_program: 'text' must be a text")
        try:
            found = await self.jobs.check(text)
        except RuntimeError as exc:
            raise Refused(f"check_program: {exc}") from None
        return {"status": "DONE", "message": "DONE", "errors": found["errors"],
                "points": found["points"]}  # fmt: skip

    # ---------------------------------------------------------------- probing
    @handler("probe")
    async def _start_probe(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """{"cmd": "probe", "kind": ..., "params": {...}}: a probing helper, run step by
        step in a worker thread; every page sees its steps ("probe" messages)."""
        if self.probe.state == "running":
            raise Refused("probe: a probing helper runs already")
        if not self.status.get("is_connected"):
            raise Refused("probe: refused, the controller is offline")
        params = request.get("params", {})
        loop = asyncio.get_running_loop()
        try:
            scale = await loop.run_in_executor(self.executor, self.commands.program_scale)
            plan = probing.make_plan(
                str(request.get("kind")), params if isinstance(params, dict) else {}, scale,
                self.settings.tool_sensor,
            )  # fmt: skip
        except (probing.ProbeError, cnc.error) as exc:
            raise Refused(f"probe: {exc}") from None
        plan.is_incremental = "G91" in str(self.status.get("gcodes", "")).split()
        self.probe = ProbeState(plan.kind, [step.text for step in plan.steps], 0, "running")
        await self.broadcast(self.probe.message_for_pages())
        self.keep(asyncio.create_task(self._run_probe(plan, loop)))
        return {"status": "DONE", "message": "started"}

    async def _run_probe(self, plan: probing.ProbePlan, loop: asyncio.AbstractEventLoop) -> None:
        def report(index: int) -> None:
            self.probe.current = index
            loop.call_soon_threadsafe(
                lambda: self.keep(
                    asyncio.create_task(self.broadcast(self.probe.message_for_pages()))
                )
            )

        def mdi(line: str) -> None:
            self.commands.run({"cmd": "mdi_line", "text": line, "timeout": PROBE_TIMEOUT_S})

        def status() -> Any:
            return self.commands.stat

        try:
            result = await loop.run_in_executor(
                self.executor, probing.run_plan, plan, mdi, status, report
            )
        except (CommandError, probing.ProbeError, cnc.error) as exc:
            self.probe.state, self.probe.message = "failed", str(exc)
        else:
            self.probe.state, self.probe.result = "done", result
            self.probe.current = len(plan.steps)
        await self.broadcast(self.probe.message_for_pages())

    @handler("probe_confirm")
    async def _confirm_probe(self, client: Client, request: dict[str, Any]) -> dict[str, Any]:
        """{"cmd": "probe_confirm", "system": "G54", "values": {"X": 0}} (a position),
        {"tool": n} or {"is_reference": true} (a tool length): set what was probed."""
        result = self.probe.result
        if self.probe.state != "done" or result is None:
            raise Refused("probe_confirm: nothing probed to confirm")
        if result["kind"] == "tool_length" and request.get("is_reference"):
            self.tool_setter_reference_z = result["touch_z"]
            self.probe.state = "confirmed"
            await self.broadcast(self.probe.message_for_pages())
            return {"status": "DONE", "message": "reference kept"}
        loop = asyncio.get_running_loop()

        def set_it() -> None:
            stat = self.commands.stat
            scale = self.commands.program_scale()
            reference = self.tool_setter_reference_z
            for line in probing.confirm_lines(result, request, stat, scale, reference):
                self.commands.run({"cmd": "mdi_line", "text": line})

        try:
            await loop.run_in_executor(self.executor, set_it)
        except (CommandError, probing.ProbeError, cnc.error) as exc:
            raise Refused(f"probe_confirm: {exc}") from None
        self.probe.state = "confirmed"
        await self.broadcast(self.probe.message_for_pages())
        return {"status": "DONE", "message": "DONE"}

    # ---------------------------------------------------------------- helpers
    def keep(self, task: asyncio.Task[Any]) -> None:
        """Hold a reference to a task until it is done (else it may be collected)."""
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def page_config(self, client_is_control: bool) -> dict[str, Any]:
        return self.settings.page_config() | {
            "is_control": client_is_control,
            "mdi_history": list(self.commands.mdi_history),
            "jog_hold_s": JOG_HOLD_S,
        }

    def status_fields(self) -> frozenset[str]:
        """The names of every status field (status.py's snapshot, and the job)."""
        return frozenset(FIELDS) | {"job"}

    def event_state(self, kinds: frozenset[str]) -> list[dict[str, Any]]:
        """What a client that subscribes to these event kinds gets at once: the state
        they describe now (the server's problems as notices)."""
        found: list[dict[str, Any]] = []
        if "jobs" in kinds:
            found.append({"type": "jobs", "jobs": self.tracker.history})
        if "program" in kinds and self.jobs.current is not None:
            found.append({"type": "program", **self.program_state(self.jobs.current.state())})
        if "probe" in kinds and self.probe.state != "idle":
            found.append(self.probe.message_for_pages())
        if "notice" in kinds:
            found += [{"type": "notice", "kind": "error", "text": text} for text in self.problems]
        if "dialog" in kinds:
            found += self.messages.open_dialogs()
        return found

    async def in_worker(self, function: Callable[..., Any], *args: Any) -> Any:
        """``function(*args)`` in a worker thread (file and controller access)."""
        return await asyncio.get_running_loop().run_in_executor(self.executor, function, *args)

    async def tools(self) -> dict[str, Any]:
        """The tool table (iocontrol's, through stat.tool_table; index 0 is the spindle),
        with the comments of the tool table file."""
        try:
            table = self.controller.poll().tool_table
        except cnc.error:
            table = ()
        settings = self.settings
        comments = await self.in_worker(
            tool_comments, settings.tool_table, settings.is_random_toolchanger
        )
        entries = [
            {"tool": entry.id, "index": index, "z": entry.zoffset, "x": entry.xoffset,
             "diameter": entry.diameter, "comment": comments.get(entry.id, "")}
            for index, entry in enumerate(table)
            if entry.id > 0 and (index > 0 or settings.is_random_toolchanger)  # 0: the spindle
        ]  # fmt: skip
        return {"tools": entries}

    async def offsets(self) -> dict[str, Any]:
        """The work offsets table (offsets.py)."""
        try:
            stat = self.controller.poll()
        except cnc.error:
            stat = None
        parameters = await self.in_worker(read_parameters, self.settings.parameter_file)
        return offsets_table(parameters, stat, self.settings.axes)
