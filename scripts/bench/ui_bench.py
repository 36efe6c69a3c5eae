#!/usr/bin/env python3
"""Web UI benchmark (JSON): status-to-browser latency and server CPU with 1, 5, 20
clients, HAL-pin-to-dialog latency; on a real machine, program listing and preview load
times for 20k, 200k and 1M lines, STOP-to-rest with the preview on screen during a run,
and the run time estimate's error on the shared benchmark programs.

    python scripts/bench/ui_bench.py [--parts status,load,stop,estimate] [--seconds S]
        [--clients 1,5,20] [--cycle-ms MS] [--dialogs N] [--sizes 20000,200000,1000000]
        [--stops N] [--programs circle_g64 ...]

Part "status" (the first part of this text is about it):

Creates the controller's buffers (configs/common/cnc.nml) in a private instance, starts
``cnc ui web`` (a real process) on a free loopback port, and connects N websocket clients.
A writer thread publishes an EMC_STAT whose X position changes every 1.5 to 3 display
cycles (so that every change is sent); each client notes when each new X arrives. Latency =
arrival - write (both in this process), so it includes the wait for the server's next
[DISPLAY]CYCLE_TIME poll (default 100 ms: about half of it on average).
Server CPU = its user+system time over the run / the run's wall time, in percent of a core.
Keys per client count: latency_ms_median, latency_ms_p99, updates_per_client, cpu_percent.
Dialogs: a HAL of the private instance, a [DISPLAY] MESSAGE_* okdialog on pin
web.messages.bench, driven by a component of this process; latency = rising edge written ->
"dialog" message at one client (again bounded below by the server's poll cycle), N times,
answered each time. Keys: dialog_ms_median, dialog_ms_max.

The other parts start our machine (``cnc run --headless`` on scripts/bench/axis_mm.ini,
LinuxCNC's sim limits, as motion_bench.py) and the server on it; "load" and "stop" drive
the page in Debian's chromium through Playwright (skipped without them):

- "load", per program size (a Lissajous of short feeds): ``listing_s`` from pressing
  Open to every line known to the listing; ``preview_s`` to every toolpath point on the
  graphics card (the preview's own interpreter run included); ``longest_task_ms``, the
  longest stretch the page's thread was busy meanwhile (PerformanceObserver "longtask",
  over 50 ms only: 0 means none); ``estimate_s`` to the run time estimated (the server's
  job, at lower priority than the page); ``turn``: while the view turns for 2 s after the
  estimate (the mouse's button down on the preview, then one pointer move each frame of
  the page), the frames the preview drew (``fps``), the page's own frames (``page_fps``)
  with the longest gap between two (``page_gap_ms_max``), the browser's CPU time per
  frame, all its processes (``cpu_ms_per_frame``), the 8 busiest threads of the browser
  and processes of the rest (``cpu_ms_per_frame_busiest``, per frame: the card's work is
  the GPU process's, SwiftShader's threads without a GPU), and the points of the level of
  detail drawn (``lod_points``); ``turn_while_estimating``, the same, turned as soon as
  the preview is whole, if the estimate was still running (it competes for the CPU).
- "stop": the 200,000-line program (``--stop-lines``) runs with listing and preview on
  screen; after 1 to 3 s, STOP is pressed (mouse down on it, as a hand would);
  ``rest_ms``: until the machine is at rest (stat.current_vel 0, polled every 0.5 ms), N
  times: median and max, beside
  ``braking_ms``, what braking from the speed of the moment takes at the machine's
  acceleration (the rest is the command's way there); ``taken_ms``, from the press until
  task took the abort (its interpreter idle), and ``page_wait_ms_max``, how long a press
  waited for the page's thread (the event's time to its handler), and
  ``running_longest_task_ms``, the page's longest busy stretch while the program ran;
  ``event_to_motion_rest_ms``, ``event_to_rest_ms`` and ``event_to_board_ms``: from the
  browser's pointerdown event (its time stamp on the system clock) to motion at rest (its
  HAL pin motion.current-vel 0), to the status saying so (task publishes it, late while it
  reads ahead) and to the abort on the safety board (motion takes it within a period):
  the product's part, without
  ``press_to_event_ms``, the harness's way to the browser (Playwright's driver, CDP).
- "estimate", per shared program (../shared/reference/programs): the estimate
  (cnc/ui/estimate.py, from X0 Y0 Z10 as the runner starts) beside the run time on our
  machine (program_runner.run_program: RUN to idle and in position), and the error in
  percent; ``compute_s`` is what the estimate cost.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import itertools
import json
import math
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(HERE))
os.environ["CNC_INSTANCE"] = f"uibench{os.getpid()}"

import aiohttp  # noqa: E402
from program_runner import machine_on_and_homed, run_program, wait_for  # noqa: E402

from hal.api import HAL_BIT, HAL_OUT, component  # noqa: E402
from hal.core import Hal  # noqa: E402
from nml import emc  # noqa: E402
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config  # noqa: E402
from nml.ipcnames import remove_instance_objects  # noqa: E402
from nml.safety import SafetyBoard  # noqa: E402

# The status changes every 1.5 to 3 display cycles (at random, so that the changes do not
# fall at one phase of the server's cycle): every change is seen.
WRITE_PERIODS = 1.5
SERVER_MAIN = "import sys; from cnc.ui.web.server import main; sys.exit(main(sys.argv[1:]))"
MESSAGE = "MESSAGE_TEXT = bench\nMESSAGE_TYPE = okdialog\nMESSAGE_PINNAME = bench\n"


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))] if ordered else 0.0


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def cpu_seconds(pid: int | str) -> float:
    """User + system time of a process (or a thread: "PID/task/TID"), from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Writer(threading.Thread):
    """Publishes a status with a new X position every ``period`` s; remembers when."""

    def __init__(self, buffer, period: float) -> None:  # type: ignore[no-untyped-def]
        super().__init__(daemon=True)
        self.buffer = buffer
        self.period = period
        self.written: dict[float, float] = {}  # X -> perf_counter() when written
        self.is_running = True

    def run(self) -> None:
        status = emc.EMC_STAT()
        traj = status.motion.traj
        traj.axis_mask, traj.joints, traj.linearUnits = 0b111, 3, 1.0
        step = 0
        while self.is_running:
            step += 1
            x = round(step * 0.001, 4)
            traj.position.tran.x = traj.actualPosition.tran.x = x
            self.written[x] = time.perf_counter()
            self.buffer.write(status)
            time.sleep(self.period * (1 + random.random()))


async def subscribe(ws: aiohttp.ClientWebSocketResponse) -> None:
    """As the page does: every status field and every event (JSON-RPC, API.md)."""
    for method in ("status.subscribe", "events.subscribe"):
        await ws.send_json({"jsonrpc": "2.0", "id": method, "method": method})


async def measure(url: str, clients: int, seconds: float, writer: Writer) -> dict[str, float]:
    latencies: list[float] = []
    counts = [0] * clients

    async def client(number: int, session: aiohttp.ClientSession) -> None:
        async with session.ws_connect(url) as ws:
            await subscribe(ws)
            deadline = time.perf_counter() + seconds
            while (left := deadline - time.perf_counter()) > 0:
                try:
                    message = await ws.receive_json(timeout=left)
                except TimeoutError:
                    break
                is_status = message.get("method") == "notify.status"
                machine = message["params"].get("machine") if is_status else None
                if machine and machine[0] in writer.written:
                    latencies.append((time.perf_counter() - writer.written[machine[0]]) * 1000)
                    counts[number] += 1

    async with aiohttp.ClientSession() as session:
        await asyncio.gather(*(client(number, session) for number in range(clients)))
    return {
        "latency_ms_median": round(percentile(latencies, 0.5), 2),
        "latency_ms_p99": round(percentile(latencies, 0.99), 2),
        "updates_per_client": round(sum(counts) / clients, 1),
    }


async def dialog_latency(url: str, driver: component, count: int, period: float) -> dict:
    """Raise the message pin ``count`` times (at a random phase of the server's cycle); the
    time until the dialog reaches the page, each answered before the next."""
    latencies: list[float] = []

    async def until(ws: aiohttp.ClientWebSocketResponse, kind: str) -> None:
        while (await ws.receive_json(timeout=10)).get("method") != f"notify.{kind}":
            pass

    async with aiohttp.ClientSession() as session, session.ws_connect(url) as ws:
        await subscribe(ws)
        for number in range(count):
            driver["out"] = True
            start = time.perf_counter()
            await until(ws, "dialog")
            latencies.append((time.perf_counter() - start) * 1000)
            driver["out"] = False
            answer = {"name": "bench", "is_yes": True}
            await ws.send_json(
                {"jsonrpc": "2.0", "id": number, "method": "answer", "params": answer}
            )
            await until(ws, "dialog_close")
            await asyncio.sleep(period * (1.5 + random.random()))  # the server sees it low
    return {
        "dialog_ms_median": round(percentile(latencies, 0.5), 2),
        "dialog_ms_max": round(max(latencies, default=0.0), 2),
    }


def wait_for_server(port: int, proc: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise SystemExit("the server ended at start")
        with socket.socket() as probe:
            if probe.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.05)
    raise SystemExit("the server did not start")


def status_part(args: argparse.Namespace) -> dict[str, object]:
    results: dict[str, object] = {"cycle_ms": args.cycle_ms}
    with tempfile.TemporaryDirectory() as folder:
        ini = Path(folder) / "bench.ini"
        nml_file = REPO / "configs" / "common" / "cnc.nml"
        ini.write_text(
            f"[EMC]\nNML_FILE = {nml_file}\n[DISPLAY]\nCYCLE_TIME = {args.cycle_ms}\n{MESSAGE}"
        )
        hal = Hal()  # the server's message pins need a HAL, as on a running machine
        try:
            with Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
                writer = Writer(nml[EMC_STATUS], args.cycle_ms / 1000 * WRITE_PERIODS)
                writer.start()
                port = free_port()
                env = dict(os.environ, PYTHONPATH=str(REPO))
                server = subprocess.Popen(
                    [sys.executable, "-c", SERVER_MAIN, "web", str(ini), "--port", str(port)],
                    env=env,
                    stdout=subprocess.DEVNULL,
                    start_new_session=True,
                )
                try:
                    wait_for_server(port, server)
                    for clients in [int(word) for word in args.clients.split(",")]:
                        before, start = cpu_seconds(server.pid), time.perf_counter()
                        found = asyncio.run(
                            measure(
                                f"http://127.0.0.1:{port}/api/v1/ws", clients, args.seconds, writer
                            )
                        )
                        wall = time.perf_counter() - start
                        used = cpu_seconds(server.pid) - before
                        found["cpu_percent"] = round(100 * used / wall, 1)
                        results[f"clients_{clients}"] = found
                    driver = component("driver", hal=hal)
                    driver.newpin("out", HAL_BIT, HAL_OUT)
                    hal.new_signal("bench", HAL_BIT)
                    hal.link("driver.out", "bench")
                    hal.link("web.messages.bench", "bench")
                    url = f"http://127.0.0.1:{port}/api/v1/ws"
                    period = args.cycle_ms / 1000
                    results["dialogs"] = asyncio.run(
                        dialog_latency(url, driver, args.dialogs, period)
                    )
                    driver.exit()
                finally:
                    server.send_signal(signal.SIGTERM)
                    try:
                        server.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        server.kill()
                    writer.is_running = False
                    writer.join()
        finally:
            hal.close()
            remove_instance_objects(os.environ["CNC_INSTANCE"])
    return results


# ------------------------------------------------------------------ on a real machine
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless=new",
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-dev-shm-usage",
    "--no-first-run",
]
PROGRAMS = (
    next(
        (folder for folder in (REPO.parent / "shared", Path("/work/shared")) if folder.is_dir()),
        REPO.parent / "shared",
    )
    / "reference"
    / "programs"
)  # ../shared beside the checkout (a worktree: /work/shared)
START = [0.0, 0.0, 10.0]  # program_runner's START_MDI
WAIT_MS = 600_000
LONGEST_TASK = """() => {
  window.benchLongest = 0;
  new PerformanceObserver((list) => {
    for (const entry of list.getEntries()) {
      window.benchLongest = Math.max(window.benchLongest, entry.duration);
    }
  }).observe({ type: "longtask" });
}"""
TURN = """([seconds, x, y]) => new Promise((done) => {
  // one pointer move a frame on the preview (the mouse's button is down: a drag turns it)
  const canvas = document.getElementById("preview");
  const times = [];
  const start = performance.now(), end = start + seconds * 1000;
  const firstFrame = Number(canvas.dataset.frames);
  const tick = (time) => {
    times.push(time);
    const clientX = x + 40 * Math.sin((time - start) / 300);
    const move = { pointerId: 1, clientX, clientY: y, bubbles: true };
    canvas.dispatchEvent(new PointerEvent("pointermove", move));
    if (time < end) requestAnimationFrame(tick);
    else done({ times, frames: Number(canvas.dataset.frames) - firstFrame,
      seconds: (performance.now() - start) / 1000 });
  };
  requestAnimationFrame(tick);
})"""


def started_processes() -> list[tuple[int, list[bytes]]]:
    """Every process below this one (the machine, the server, its jobs, the browser) with
    its command's words (Chromium's processes rewrite theirs into one: split again)."""
    found, todo = [], [os.getpid()]
    while todo:
        pid = todo.pop()
        for task in Path(f"/proc/{pid}/task").glob("*"):
            with contextlib.suppress(OSError):
                todo.extend(int(child) for child in (task / "children").read_text().split())
        if pid != os.getpid():
            with contextlib.suppress(OSError):
                words = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").split()
                found.append((pid, words))
    return found


def is_browser(words: list[bytes]) -> bool:
    return bool(words) and b"chrom" in Path(words[0].decode()).name.encode()


def browser_cpu_s() -> float:
    """CPU time (user + system) of the browser's processes."""
    total = 0.0
    for pid, words in started_processes():
        if is_browser(words):
            with contextlib.suppress(OSError):
                total += cpu_seconds(pid)
    return total


def cpu_by_thread_s() -> dict[str, float]:
    """CPU time (user + system) of each of the browser's threads, keyed "<process
    type>/<thread name>" (Chromium's --type=..., "browser" for its first), and of each
    other process started, keyed by its command (the machine, the server, its jobs)."""
    found: dict[str, float] = {}
    for pid, words in started_processes():
        if not is_browser(words):
            with contextlib.suppress(OSError):
                name = " ".join(w.decode(errors="replace") for w in words[1:4])
                found[name[:60]] = found.get(name[:60], 0.0) + cpu_seconds(pid)
            continue
        kind = next((w[7:].decode() for w in words if w.startswith(b"--type=")), "browser")
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                key = f"{kind}/{(task / 'comm').read_text().strip()}"
                found[key] = found.get(key, 0.0) + cpu_seconds(f"{pid}/task/{task.name}")
            except OSError:
                continue
    return found


def turn_view(page, x: float, y: float) -> dict[str, object]:  # type: ignore[no-untyped-def]
    """Turn the preview for 2 s (a drag); the frames drawn, and what drew them."""
    page.mouse.move(x, y)
    page.mouse.down()
    cpu_before, threads_before = browser_cpu_s(), cpu_by_thread_s()
    turn = page.evaluate(TURN, [2.0, x, y])
    cpu_s = browser_cpu_s() - cpu_before
    threads = cpu_by_thread_s()
    page.mouse.up()
    frames = max(turn["frames"], 1)
    busiest = sorted(
        ((t - threads_before.get(k, 0.0), k) for k, t in threads.items()), reverse=True
    )[:8]
    times = turn["times"]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    return {
        "fps": round(turn["frames"] / turn["seconds"], 1),
        "page_fps": round(len(gaps) / max((times[-1] - times[0]) / 1000, 1e-9), 1),
        "page_gap_ms_max": round(max(gaps, default=0.0), 1),
        "cpu_ms_per_frame": round(cpu_s * 1000 / frames, 1),
        "cpu_ms_per_frame_busiest": {
            name: round(seconds * 1000 / frames, 1) for seconds, name in busiest if seconds
        },
        "lod_points": int(page.locator("#preview").get_attribute("data-turning-lod") or 0),
    }


def big_program(path: Path, lines: int) -> None:
    """A Lissajous of ``lines`` short feeds at 3000 mm/min (as tests/web/test_browser.py)."""
    out = ["G21 G90 G64 F3000", "G0 Z1", "G0 X0 Y9", "G1 Z-0.5 F600", "F3000"]
    loops = max(lines // 2000, 1)
    for n in range(lines):
        t = n / lines * 2 * math.pi * loops
        out.append(f"G1 X{40 * math.sin(3 * t):.4f} Y{30 * math.sin(2 * t + 0.3):.4f}")
    path.write_text("\n".join([*out, "G0 Z5", "M2"]) + "\n")


def open_program(page, name: str) -> float:  # type: ignore[no-untyped-def]
    """Open ``name`` from the page; the seconds until its listing is whole."""
    page.click("#program-refresh")  # the list as the folder is now
    page.wait_for_selector(f'#program-list option[value="{name}"]', state="attached")
    page.evaluate(LONGEST_TASK)
    start = time.perf_counter()
    page.select_option("#program-list", name)
    page.click("#program-open")
    page.wait_for_function(
        f"document.getElementById('program-file').textContent.endsWith('{name}')"
        " && Number(document.getElementById('listing').dataset.lines) > 0",
        timeout=WAIT_MS, polling=20,
    )  # fmt: skip
    return time.perf_counter() - start


def load_part(page, folder: Path, sizes: list[int]) -> dict[str, object]:  # type: ignore[no-untyped-def]
    found: dict[str, object] = {}
    for size in sizes:
        name = f"lissajous_{size}.ngc"
        big_program(folder / name, size)
        start = time.perf_counter()
        listing_s = open_program(page, name)
        page.wait_for_function(
            "(() => { const p = document.getElementById('preview').dataset;"
            " return !document.getElementById('analysis').textContent.includes('reading')"
            " && Number(p.points) > 0 && p.drawn === p.points; })()",
            timeout=WAIT_MS, polling=50,
        )  # fmt: skip
        preview_s = time.perf_counter() - start
        longest = page.evaluate("window.benchLongest")
        box = page.locator("#preview").bounding_box()
        x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        is_estimating = "estimating" in page.locator("#analysis").text_content()
        turn_estimating = turn_view(page, x, y) if is_estimating else None
        page.wait_for_function(
            "document.getElementById('analysis').textContent.includes('estimated run time')",
            timeout=WAIT_MS * 10, polling=100,
        )  # fmt: skip
        estimate_s = time.perf_counter() - start
        found[str(size)] = {
            "listing_s": round(listing_s, 2),
            "preview_s": round(preview_s, 2),
            "estimate_s": round(estimate_s, 2),
            "points": int(page.locator("#preview").get_attribute("data-points")),
            "lod_points": int(page.locator("#preview").get_attribute("data-lod") or 0),
            "longest_task_ms": round(longest, 1),
            "turn": turn_view(page, x, y),
            "turn_while_estimating": turn_estimating,
        }
    return found


def _until_zero(hal: Hal, pin: dict, timeout: float = 30) -> float:
    """Poll a float pin every 0.1 ms until it reads 0; the epoch time (s) it did."""
    deadline = time.monotonic() + timeout
    while hal.pin_value(pin) != 0 and time.monotonic() < deadline:
        time.sleep(0.0001)
    return time.time()


def stop_part(page, folder: Path, count: int, max_acc: float, lines: int) -> dict[str, object]:  # type: ignore[no-untyped-def]
    import cnc

    name = f"lissajous_{lines}.ngc"
    if not (folder / name).exists():
        big_program(folder / name, lines)
    open_program(page, name)
    page.wait_for_function(
        "(() => { const p = document.getElementById('preview').dataset;"
        " return Number(p.points) > 0 && p.drawn === p.points; })()",
        timeout=WAIT_MS, polling=50,
    )  # fmt: skip
    # how long the press waited for the page's thread (event time to the handler)
    # and when the browser made the event (epoch ms: the system clock, which this process
    # reads too), so the product's part is told from the harness's way to the browser
    page.evaluate(
        "() => { window.stopWaits = []; window.stopEvents = [];"
        " document.getElementById('abort').addEventListener('pointerdown', (e) => {"
        " window.stopWaits.push(performance.now() - e.timeStamp);"
        " window.stopEvents.push(performance.timeOrigin + e.timeStamp); },"
        " { capture: true }); }"
    )
    page.evaluate(LONGEST_TASK)  # the longest stretch the page's thread is busy while running
    s = cnc.stat()
    board = SafetyBoard.attach()
    # motion's own speed (its HAL pin), beside the status task publishes: task may publish
    # late while it reads ahead, motion's rest is what the machine does
    hal = Hal(is_creating=False)
    _name, vel_pin = hal.find_pin("motion.current-vel")
    epoch_minus_monotonic_ms = (time.time() - time.monotonic()) * 1000
    rests, brakings, takens = [], [], []
    presses, rested, boarded = [], [], []  # epoch ms: the press, at rest, on the board
    motion_rested = []  # epoch ms: motion's speed 0
    with contextlib.suppress(OSError):  # the clock must not wait behind the browser's drawing
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
    for _ in range(count):
        page.click("#run")
        wait_for(s, lambda s: s.current_vel > 0, 60)
        time.sleep(1 + 2 * random.random())
        box = page.locator("#abort").bounding_box()
        page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        s.poll()
        speed = s.current_vel
        start = time.perf_counter()
        presses.append(time.time() * 1000)
        page.mouse.down()
        motion_rested.append(_until_zero(hal, vel_pin) * 1000)
        wait_for(s, lambda s: s.interp_state == cnc.INTERP_IDLE or s.current_vel == 0, 30, 0.0005)
        takens.append((time.perf_counter() - start) * 1000)
        wait_for(s, lambda s: s.current_vel == 0, 30, 0.0005)
        rests.append((time.perf_counter() - start) * 1000)
        rested.append(time.time() * 1000)
        if board is not None:
            boarded.append(board.abort_stamp() / 1e6 + epoch_minus_monotonic_ms)
        page.mouse.up()
        brakings.append(speed / max_acc * 1000)
        wait_for(s, lambda s: s.interp_state == cnc.INTERP_IDLE, 30)
    events = page.evaluate("window.stopEvents")
    hal.close()
    if board is not None:
        board.close()
    event_to_motion_rest = [r - e for r, e in zip(motion_rested, events, strict=True)]
    # the browser's event to the machine at rest: what the product takes
    event_to_rest = [r - e for r, e in zip(rested, events, strict=True)]
    event_to_board = [b - e for b, e in zip(boarded, events, strict=False)]
    return {
        "preview_points": int(page.locator("#preview").get_attribute("data-points")),
        "event_to_motion_rest_ms_median": round(percentile(event_to_motion_rest, 0.5), 1),
        "event_to_motion_rest_ms_max": round(max(event_to_motion_rest), 1),
        "event_to_rest_ms_median": round(percentile(event_to_rest, 0.5), 1),
        "event_to_rest_ms_max": round(max(event_to_rest), 1),
        "event_to_board_ms_median": round(percentile(event_to_board, 0.5), 1)
        if event_to_board
        else None,
        "event_to_board_ms_max": round(max(event_to_board), 1) if event_to_board else None,
        "press_to_event_ms_max": round(max(e - p for e, p in zip(events, presses, strict=True)), 1),
        "rest_ms_median": round(percentile(rests, 0.5), 1),
        "rest_ms_max": round(max(rests), 1),
        "braking_ms_median": round(percentile(brakings, 0.5), 1),
        # from the press to task having taken the abort (its interpreter idle), and the
        # part of that the press waited for the page's thread
        "taken_ms_median": round(percentile(takens, 0.5), 1),
        "taken_ms_max": round(max(takens), 1),
        "page_wait_ms_max": round(max(page.evaluate("window.stopWaits")), 1),
        "running_longest_task_ms": round(page.evaluate("window.benchLongest"), 1),
        "rest_ms_all": [round(r) for r in rests],
        "event_to_motion_rest_ms_all": [round(r) for r in event_to_motion_rest],
        "event_to_rest_ms_all": [round(r) for r in event_to_rest],
        "event_to_board_ms_all": [round(b) for b in event_to_board],
        "taken_ms_all": [round(t) for t in takens],
        "runs": count,
    }


def estimate_part(folder: Path, names: list[str]) -> dict[str, object]:
    import cnc
    from cnc.ui.estimate import estimate

    class NoRecorder:
        def start(self) -> None: ...

        def stop(self) -> None: ...

    found: dict[str, object] = {}
    for name in names:
        program = PROGRAMS / f"{name}.ngc"
        start = time.perf_counter()
        guess = estimate(str(program), str(folder / "axis_mm.ini"), start=START)
        compute_s = time.perf_counter() - start
        run = run_program(cnc, str(program), NoRecorder(), timeout=600)
        actual = run["cycle_s"]
        found[name] = {
            "estimate_s": round(guess.total_s, 3),
            "actual_s": actual,
            "error_percent": round((guess.total_s - actual) / actual * 100, 2),
            "compute_s": round(compute_s, 2),
            "is_ok": run["is_ok"],
        }
    return found


def machine_parts(args: argparse.Namespace, parts: set[str]) -> dict[str, object]:
    from motion_bench import our_machine

    import cnc

    results: dict[str, object] = {}
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        with our_machine(folder, f"uibenchm{os.getpid()}") as env:
            machine_on_and_homed(cnc)
            if "estimate" in parts:
                results["estimate"] = estimate_part(folder, args.programs)
            browser_parts = parts & {"load", "stop"}
            if not browser_parts:
                return results
            try:
                from playwright.sync_api import sync_playwright
            except ImportError:
                return results | {"browser": "skipped: no playwright"}
            if not CHROMIUM.exists():
                return results | {"browser": f"skipped: no {CHROMIUM}"}
            port = free_port()
            server = subprocess.Popen(
                [sys.executable, "-c", SERVER_MAIN, "web", "axis_mm.ini", "--port", str(port)],
                cwd=folder, env=dict(env, PYTHONPATH=str(REPO)), stdout=subprocess.DEVNULL,
                start_new_session=True,
            )  # fmt: skip
            try:
                wait_for_server(port, server)
                with sync_playwright() as playwright:
                    browser = playwright.chromium.launch(
                        executable_path=str(CHROMIUM), args=CHROMIUM_ARGS
                    )
                    page = browser.new_page(viewport={"width": 1280, "height": 800})
                    page.set_default_timeout(WAIT_MS)
                    page.goto(f"http://127.0.0.1:{port}/")
                    page.wait_for_function(
                        "document.getElementById('state').textContent === 'READY'"
                    )
                    page.wait_for_function("document.getElementById('preview').dataset.renderer")
                    results["renderer"] = page.locator("#preview").get_attribute("data-renderer")
                    if "load" in parts:
                        results["load"] = load_part(page, folder, args.sizes)
                    if "stop" in parts:
                        results["stop"] = stop_part(
                            page, folder, args.stops, 508.0, args.stop_lines
                        )
                    browser.close()
            finally:
                server.send_signal(signal.SIGTERM)
                try:
                    server.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    server.kill()
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default="status,load,stop,estimate")
    parser.add_argument("--seconds", type=float, default=3.0, help="per client count")
    parser.add_argument("--clients", default="1,5,20")
    parser.add_argument("--cycle-ms", type=float, default=100.0, help="[DISPLAY]CYCLE_TIME")
    parser.add_argument("--dialogs", type=int, default=20, help="message dialogs to time")
    parser.add_argument("--sizes", default="20000,200000,1000000", help="program lines")
    parser.add_argument("--stops", type=int, default=5, help="STOP presses to time")
    parser.add_argument("--stop-lines", type=int, default=200_000, help="the program's lines")
    parser.add_argument(
        "--programs", nargs="*",
        default=sorted(path.stem for path in PROGRAMS.glob("*.ngc")),
        help="shared benchmark programs for the estimate",
    )  # fmt: skip
    args = parser.parse_args()
    args.sizes = [int(word) for word in args.sizes.split(",") if word]
    parts = {word.strip() for word in args.parts.split(",")}
    results: dict[str, object] = {}
    if "status" in parts:
        results["status"] = status_part(args)
    if parts & {"load", "stop", "estimate"}:
        results |= machine_parts(args, parts)
    print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
