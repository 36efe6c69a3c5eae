#!/usr/bin/env python3
"""API benchmarks (JSON): the Python API's ``cnc.stat().poll()``, and a no-op command's
round trip through the web server's JSON-RPC API against the Python API's.

    python scripts/bench/api_bench.py [--polls N] [--calls N] [--no-rpc]

Poll: creates the controller's buffers (configs/common/cnc.nml) in a private instance,
writes one EMC_STAT, then times ``poll()`` (which copies the status and nothing else) and,
for reference, reading one tuple attribute after a poll. Keys: poll_us_median,
poll_us_p99, poll_and_position_us_median.

Round trips (issue 19): a real machine (``cnc run --headless`` of a copy of
tests/task/machine/mill.ini, its own instance) and ``cnc ui web`` on a free loopback port.
The no-op command is the feed override set to 100 %, which it is: task takes it and
answers DONE. Timed, one call after
the other: the Python API (``command.feedrate(1.0)`` + ``wait_complete()``), the JSON-RPC
call ``feedrate {"percent": 100}`` over the websocket and over HTTP POST (one keep-alive
connection), and ``api.version`` (answered by the server alone: the API's own cost).
Keys: ``noop_<way>_ms_median`` / ``_p99`` for python_api, rpc_ws, rpc_http, and
``version_<way>_ms_median`` / ``_p99`` for rpc_ws, rpc_http.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
os.environ["CNC_INSTANCE"] = f"apibench{os.getpid()}"

import cnc  # noqa: E402
from nml import emc  # noqa: E402
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config  # noqa: E402
from nml.ipcnames import remove_instance_objects  # noqa: E402


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def timed(action, count: int) -> list[float]:  # type: ignore[no-untyped-def]
    clock = time.perf_counter
    samples = []
    for _ in range(count):
        start = clock()
        action()
        samples.append((clock() - start) * 1e6)
    return samples


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--polls", type=int, default=20000)
    parser.add_argument("--calls", type=int, default=2000, help="round trips per way")
    parser.add_argument("--no-rpc", action="store_true", help="only the poll figures")
    args = parser.parse_args()
    try:
        with Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
            status = emc.EMC_STAT()
            status.motion.traj.position.tran.x = 1.0
            nml[EMC_STATUS].write(status)
            s = cnc.stat()
            timed(s.poll, 1000)  # warm up
            polls = timed(s.poll, args.polls)
            with_position = timed(lambda: (s.poll(), s.position), args.polls // 4)
            s.close()
    finally:
        remove_instance_objects()
    result = {
        "poll_us_median": round(statistics.median(polls), 3),
        "poll_us_p99": round(percentile(polls, 0.99), 3),
        "poll_and_position_us_median": round(statistics.median(with_position), 3),
    }
    if not args.no_rpc:
        result |= round_trips(args.calls)
    print(json.dumps(result))
    return 0


# ------------------------------------------------------------------ JSON-RPC round trips
SERVER_MAIN = "import sys; from cnc.ui.web.server import main; sys.exit(main(sys.argv[1:]))"


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def summary(name: str, samples_s: list[float]) -> dict[str, float]:
    ms = [sample * 1000 for sample in samples_s]
    return {
        f"{name}_ms_median": round(statistics.median(ms), 3),
        f"{name}_ms_p99": round(percentile(ms, 0.99), 3),
    }


def round_trips(calls: int) -> dict[str, float]:
    """The machine and the server, each its own process, for the time of the timings."""
    os.environ["CNC_INSTANCE"] = f"apibenchrpc{os.getpid()}"
    folder = Path(tempfile.mkdtemp(prefix="api_bench_")) / "machine"
    shutil.copytree(REPO / "tests" / "task" / "machine", folder)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    machine = subprocess.Popen(
        [sys.executable, "-m", "cnc", "run", "--headless", "mill.ini"],
        cwd=folder, env=env, **quiet,  # type: ignore[call-overload]
    )  # fmt: skip
    server = None
    try:
        wait_until(_is_up, machine, "the machine did not start")
        command = cnc.command()
        port = free_port()
        server = subprocess.Popen(
            [sys.executable, "-c", SERVER_MAIN, "web", "mill.ini", "--port", str(port)],
            cwd=folder, env=env, **quiet,  # type: ignore[call-overload]
        )  # fmt: skip
        wait_until(lambda: _answers(port), server, "the server did not start")

        def python_api() -> None:
            command.feedrate(1.0)
            if command.wait_complete(5) != cnc.RCS_DONE:
                raise SystemExit("the controller did not take the feed override")

        timed(python_api, calls // 10)  # warm up
        found = summary("noop_python_api", [t / 1e6 for t in timed(python_api, calls)])
        found |= asyncio.run(rpc_round_trips(port, calls))
        return found
    finally:
        for proc in (server, machine):
            if proc is not None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(30)
                except subprocess.TimeoutExpired:
                    proc.kill()
        shutil.rmtree(folder.parent, ignore_errors=True)


def _is_up() -> bool:
    try:
        stat = cnc.stat()
        stat.poll()
    except cnc.error:
        return False
    stat.close()
    return True


def _answers(port: int) -> bool:
    with socket.socket() as probe:
        return probe.connect_ex(("127.0.0.1", port)) == 0


def wait_until(test, proc: subprocess.Popen[bytes], failure: str) -> None:  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + 60
    while not test():
        if proc.poll() is not None or time.monotonic() > deadline:
            raise SystemExit(f"api_bench: {failure}")
        time.sleep(0.02)


async def rpc_round_trips(port: int, calls: int) -> dict[str, float]:
    import aiohttp

    noop = {"jsonrpc": "2.0", "id": 1, "method": "feedrate", "params": {"percent": 100}}
    version = {"jsonrpc": "2.0", "id": 1, "method": "api.version"}
    found: dict[str, float] = {}
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(f"http://127.0.0.1:{port}/api/v1/ws") as ws:

            async def over_ws(call: dict[str, object]) -> None:
                await ws.send_json(call)
                if "error" in await ws.receive_json():
                    raise SystemExit(f"api_bench: {call['method']} refused")

            for name, call in (("noop", noop), ("version", version)):
                await timed_async(over_ws, call, calls // 10)
                found |= summary(f"{name}_rpc_ws", await timed_async(over_ws, call, calls))

        async def over_http(call: dict[str, object]) -> None:
            url = f"http://127.0.0.1:{port}/api/v1/rpc"
            async with session.post(url, json=call) as answer:
                if "error" in await answer.json():
                    raise SystemExit(f"api_bench: {call['method']} refused")

        for name, call in (("noop", noop), ("version", version)):
            await timed_async(over_http, call, calls // 10)
            found |= summary(f"{name}_rpc_http", await timed_async(over_http, call, calls))
    return found


async def timed_async(action, argument, count: int) -> list[float]:  # type: ignore[no-untyped-def]
    samples = []
    for _ in range(count):
        start = time.perf_counter()
        await action(argument)
        samples.append(time.perf_counter() - start)
    return samples


if __name__ == "__main__":
    sys.exit(main())
