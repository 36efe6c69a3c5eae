#!/usr/bin/env python3
"""Web UI benchmark: status-to-browser latency and server CPU with 1, 5, 20 clients, and
HAL-pin-to-dialog latency (JSON).

    python scripts/bench/ui_bench.py [--seconds S] [--clients 1,5,20] [--cycle-ms MS]
                                     [--dialogs N]

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
"""

from __future__ import annotations

import argparse
import asyncio
import json
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
sys.path.insert(0, str(REPO))
os.environ["CNC_INSTANCE"] = f"uibench{os.getpid()}"

import aiohttp  # noqa: E402

from hal.api import HAL_BIT, HAL_OUT, component  # noqa: E402
from hal.core import Hal  # noqa: E402
from nml import emc  # noqa: E402
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config  # noqa: E402
from nml.ipcnames import remove_instance_objects  # noqa: E402

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


def cpu_seconds(pid: int) -> float:
    """User + system time of a process, from /proc."""
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


async def measure(url: str, clients: int, seconds: float, writer: Writer) -> dict[str, float]:
    latencies: list[float] = []
    counts = [0] * clients

    async def client(number: int, session: aiohttp.ClientSession) -> None:
        async with session.ws_connect(url) as ws:
            deadline = time.perf_counter() + seconds
            while (left := deadline - time.perf_counter()) > 0:
                try:
                    message = await ws.receive_json(timeout=left)
                except TimeoutError:
                    break
                machine = (
                    message.get("data", {}).get("machine") if message["type"] == "status" else None
                )
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
        while (await ws.receive_json(timeout=10))["type"] != kind:
            pass

    async with aiohttp.ClientSession() as session, session.ws_connect(url) as ws:
        for number in range(count):
            driver["out"] = True
            start = time.perf_counter()
            await until(ws, "dialog")
            latencies.append((time.perf_counter() - start) * 1000)
            driver["out"] = False
            await ws.send_json({"cmd": "answer", "name": "bench", "is_yes": True, "id": number})
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=3.0, help="per client count")
    parser.add_argument("--clients", default="1,5,20")
    parser.add_argument("--cycle-ms", type=float, default=100.0, help="[DISPLAY]CYCLE_TIME")
    parser.add_argument("--dialogs", type=int, default=20, help="message dialogs to time")
    args = parser.parse_args()
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
                            measure(f"http://127.0.0.1:{port}/ws", clients, args.seconds, writer)
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
                    url = f"http://127.0.0.1:{port}/ws"
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
    print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
