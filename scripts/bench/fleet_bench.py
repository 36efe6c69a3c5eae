#!/usr/bin/env python3
"""Fleet benchmark (JSON): five simulated machines on one Mosquitto and each served over
OPC UA; status-change-to-subscriber latency and CPU per machine.

    python scripts/bench/fleet_bench.py [--machines 5] [--changes 20] [--seconds 5]

Starts a Mosquitto broker (password authentication, free loopback port; needs
scripts/install-mosquitto) and N copies of configs/sim/mill.ini with ``cnc run
--headless``, each with its own ``CNC_INSTANCE``, ``[MQTT]ENABLE = 1`` (machine name
``fleet-<i>``) and ``[OPCUA]ENABLE = 1`` on its own port, both bridges at their default
``CYCLE_TIME`` (0.1 s). One MQTT subscriber (``cnc/+/feed/override``) and one asyncua
client per machine (a data-change subscription on ``Monitoring/Channel_1/FeedOverride``,
10 ms publishing interval) listen.

Latency: per machine, ``--changes`` feed-override changes, one machine after another; for
each the time the new value is first seen in the machine's status (``stat.poll`` spinning
right after the command) to its arrival at the MQTT subscriber and at the OPC UA client.
Both include the wait for the bridge's next poll (half a cycle on average).
Keys: ``mqtt_latency_ms`` and ``opcua_latency_ms`` with ``median``, ``p99``, ``n``.

CPU: user+system time of each machine's processes (the launcher and all its descendants,
bridges included) and of each bridge over a ``--seconds`` window, in percent of one core,
averaged over the machines: ``idle`` (nothing moves) and ``moving`` (every machine runs
back-and-forth G1 moves, so positions change every bridge cycle). ``load_average`` says
how busy the computer was.

``jsonrpc_round_trip_ms``: after the fleet has stopped, a no-op command's round trip
through the web server's JSON-RPC API (websocket and HTTP POST) beside the Python API's,
on one more machine with its own web server (api_bench.py's ``round_trips``, ``--calls``
of each): ``python_api``, ``rpc_ws``, ``rpc_http`` with ``median`` and ``p99``.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import queue
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

import cnc  # noqa: E402
from cnc.runtime import read_runtime_info  # noqa: E402
from nml.ipcnames import INSTANCE_ENV, remove_instance_objects  # noqa: E402

WAIT_S = 600.0  # start-up on a loaded computer (asyncua builds its address space in seconds)
USER, PASSWORD = "fleet", "fleet-secret"
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
SEEN_S = 5.0  # a feed override change not in the status by then is left out


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_for_port(port: int) -> None:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.5):
            return
        time.sleep(0.1)
    raise RuntimeError(f"nothing listens on port {port}")


@contextlib.contextmanager
def broker(folder: Path) -> Iterator[int]:
    mosquitto = shutil.which("mosquitto") or shutil.which("mosquitto", path="/usr/sbin")
    if mosquitto is None:
        raise SystemExit("fleet_bench: no mosquitto (scripts/install-mosquitto)")
    passwords = folder / "passwd"
    passwords.touch(mode=0o600)
    subprocess.run(["mosquitto_passwd", "-b", str(passwords), USER, PASSWORD], check=True)
    port = free_port()
    lines = [f"listener {port} 127.0.0.1", "allow_anonymous false", f"password_file {passwords}"]
    lines += ["persistence false", "log_dest stderr", "log_type error"]
    if os.geteuid() == 0:
        lines.append("user root")
    (folder / "mosquitto.conf").write_text("\n".join(lines) + "\n")
    proc = subprocess.Popen([mosquitto, "-c", str(folder / "mosquitto.conf")])
    try:
        wait_for_port(port)
        yield port
    finally:
        proc.terminate()
        proc.wait(10)


class Machine:
    def __init__(self, index: int, folder: Path, mqtt_port: int) -> None:
        self.index = index
        self.name = f"fleet-{index}"
        self.instance = f"fleet{os.getpid()}-{index}"
        self.folder = folder / self.name
        self.opcua_port = free_port()
        shutil.copytree(REPO / "configs" / "sim", self.folder)
        ini = self.folder / "mill.ini"
        ini.write_text(
            ini.read_text() + f"\n[MQTT]\nENABLE = 1\nBROKER = 127.0.0.1\nPORT = {mqtt_port}\n"
            f"USERNAME = {USER}\nPASSWORD = {PASSWORD}\nMACHINE_NAME = {self.name}\n"
            f"\n[OPCUA]\nENABLE = 1\nPORT = {self.opcua_port}\nMACHINE_NAME = {self.name}\n"
            "SECURITY = None\n"
        )
        env = dict(os.environ, **{INSTANCE_ENV: self.instance})
        self.launcher = subprocess.Popen(
            [sys.executable, "-m", "cnc", "run", "--headless", "mill.ini"],
            cwd=self.folder,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )

    @contextlib.contextmanager
    def selected(self) -> Iterator[None]:
        """This machine's instance for the API objects made (and used) meanwhile."""
        before = os.environ.get(INSTANCE_ENV)
        os.environ[INSTANCE_ENV] = self.instance
        try:
            yield
        finally:
            if before is None:
                os.environ.pop(INSTANCE_ENV)
            else:
                os.environ[INSTANCE_ENV] = before

    def wait_ready(self) -> None:
        deadline = time.monotonic() + WAIT_S
        with self.selected():
            while (info := read_runtime_info()) is None or info.pid != self.launcher.pid:
                if self.launcher.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"{self.name} did not start")
                time.sleep(0.1)
            self.stat, self.command = cnc.stat(), cnc.command()
        wait_for_port(self.opcua_port)

    def prepare(self) -> None:
        """On, homed, in MDI mode."""
        with self.selected():
            c = self.command
            c.state(cnc.STATE_ESTOP_RESET)
            c.state(cnc.STATE_ON)
            c.home(-1)
            c.wait_complete()
            deadline = time.monotonic() + WAIT_S
            while True:
                self.stat.poll()
                if all(self.stat.homed[: self.stat.joints]):
                    break
                if time.monotonic() > deadline:
                    raise RuntimeError(f"{self.name} did not home")
                time.sleep(0.05)
            c.mode(cnc.MODE_MDI)
            c.wait_complete()

    def change_feed_override(self, scale: float) -> float | None:
        """Set the feed override; the time (monotonic) the status first shows it, None if
        it does not within SEEN_S (counted in the result as ``unseen_changes``)."""
        with self.selected():
            self.command.feedrate(scale)
            deadline = time.monotonic() + SEEN_S
            while time.monotonic() < deadline:
                self.stat.poll()
                if abs(self.stat.feedrate - scale) < 1e-9:
                    return time.monotonic()
        return None

    def processes(self) -> dict[str, int]:
        """pid of the launcher, each descendant, by role: launcher, mqtt, opcua, other."""
        pids = {self.launcher.pid: "machine"}
        for pid in descendants(self.launcher.pid):
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
            pids[pid] = (
                "mqtt_bridge"
                if b"cnc.bridges.mqtt\0" in cmdline
                else "opcua_bridge"
                if b"cnc.bridges.opcua" in cmdline
                else "machine"
            )
        return pids

    def stop(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            self.launcher.send_signal(signal.SIGTERM)
        try:
            self.launcher.wait(60)
        except subprocess.TimeoutExpired:
            os.killpg(self.launcher.pid, signal.SIGKILL)
            self.launcher.wait()
        remove_instance_objects(self.instance)


def descendants(pid: int) -> list[int]:
    found = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with contextlib.suppress(OSError):
            for child in map(int, (task / "children").read_text().split()):
                found += [child, *descendants(child)]
    return found


def cpu_seconds(pid: int) -> float:
    with contextlib.suppress(OSError):
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS  # utime + stime
    return 0.0


def cpu_window(machines: list[Machine], seconds: float) -> dict[str, float]:
    """Mean CPU per machine over ``seconds``: percent of one core, by role and in all."""
    roles = [m.processes() for m in machines]
    before = [{pid: cpu_seconds(pid) for pid in r} for r in roles]
    start = time.monotonic()
    time.sleep(seconds)
    wall = time.monotonic() - start
    totals: dict[str, float] = {"machine_total": 0.0, "mqtt_bridge": 0.0, "opcua_bridge": 0.0}
    for role_of, used in zip(roles, before, strict=True):
        for pid, was in used.items():
            percent = 100.0 * (cpu_seconds(pid) - was) / wall
            totals["machine_total"] += percent
            if role_of[pid] != "machine":
                totals[role_of[pid]] += percent
    return {key: round(value / len(machines), 2) for key, value in totals.items()}


def mqtt_listener(port: int, arrivals: queue.Queue[tuple[str, float, float]]) -> Any:
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    client.username_pw_set(USER, PASSWORD)
    connected = threading.Event()

    def on_connect(c: Any, _d: Any, _f: Any, reason: Any, _p: Any) -> None:
        c.subscribe("cnc/+/feed/override", qos=1)
        connected.set()

    def on_message(_c: Any, _d: Any, message: Any) -> None:
        now = time.monotonic()
        arrivals.put((message.topic.split("/")[1], json.loads(message.payload), now))

    client.on_connect = on_connect
    client.on_message = on_message
    client.connect("127.0.0.1", port)
    client.loop_start()
    connected.wait(WAIT_S)
    return client


class OpcuaListeners:
    """One asyncua client per machine, in a thread of its own, noting FeedOverride changes."""

    def __init__(self, machines: list[Machine], arrivals: queue.Queue) -> None:
        self.machines = machines
        self.arrivals = arrivals
        self.loop = asyncio.new_event_loop()
        self.ready = threading.Event()
        self.stopping: asyncio.Event | None = None
        self.thread = threading.Thread(target=self.loop.run_until_complete, args=(self.main(),))
        self.thread.start()
        if not self.ready.wait(WAIT_S):
            raise RuntimeError("the OPC UA clients did not connect")

    async def main(self) -> None:
        from asyncua import Client, ua

        self.stopping = asyncio.Event()
        clients = []
        for machine in self.machines:
            client = Client(f"opc.tcp://127.0.0.1:{machine.opcua_port}/cnc/", timeout=30)
            await client.connect()
            clients.append(client)
            ns = await client.get_namespace_index("urn:cnc:machine-tool")
            node = client.get_node(
                ua.NodeId(f"{machine.name}.Monitoring.Channel_1.FeedOverride", ns)
            )
            handler = _Changes(machine.name, self.arrivals)
            subscription = await client.create_subscription(10, handler)
            await subscription.subscribe_data_change(node)
        self.ready.set()
        await self.stopping.wait()
        for client in clients:
            await client.disconnect()

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.stopping.set)
        self.thread.join(30)


class _Changes:
    def __init__(self, name: str, arrivals: queue.Queue) -> None:
        self.name = name
        self.arrivals = arrivals

    def datachange_notification(self, _node: Any, value: Any, _data: Any) -> None:
        self.arrivals.put((self.name, value / 100.0, time.monotonic()))


def latencies(
    changes: list[tuple[str, float, float]], arrivals: queue.Queue, timeout: float = 10.0
) -> list[float]:
    """Per change (machine, value, seen in the status at), ms until it arrived."""
    arrived: dict[tuple[str, float], float] = {}
    deadline = time.monotonic() + timeout
    wanted = {(name, round(value, 4)) for name, value, _ in changes}
    while not wanted <= arrived.keys() and time.monotonic() < deadline:
        with contextlib.suppress(queue.Empty):
            name, value, at = arrivals.get(timeout=0.1)
            arrived.setdefault((name, round(value, 4)), at)
    return [
        1000.0 * (arrived[(name, round(value, 4))] - seen)
        for name, value, seen in changes
        if (name, round(value, 4)) in arrived
    ]


def summary(values: list[float]) -> dict[str, Any]:
    if not values:
        return {"median": None, "p99": None, "n": 0}
    ordered = sorted(values)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]
    return {"median": round(statistics.median(ordered), 2), "p99": round(p99, 2), "n": len(values)}


def move_back_and_forth(machines: list[Machine], stop: threading.Event) -> None:
    while not stop.is_set():
        for machine in machines:
            with machine.selected():
                status = machine.stat
                status.poll()
                if status.interp_state == cnc.INTERP_IDLE:
                    x = 50.0 if status.position[0] < 25.0 else 0.0
                    machine.command.mdi(f"G1 X{x} F6000")
        time.sleep(0.05)


def jsonrpc_round_trips(calls: int) -> dict[str, dict[str, float]]:
    """A no-op command through the web server's JSON-RPC API against the Python API's."""
    from api_bench import round_trips  # (this folder: scripts/bench)

    found = round_trips(calls)
    return {
        way: {"median": found[f"noop_{way}_ms_median"], "p99": found[f"noop_{way}_ms_p99"]}
        for way in ("python_api", "rpc_ws", "rpc_http")
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--machines", type=int, default=5)
    parser.add_argument("--changes", type=int, default=20, help="per machine")
    parser.add_argument("--seconds", type=float, default=5.0, help="each CPU window")
    parser.add_argument("--calls", type=int, default=200, help="JSON-RPC round trips")
    args = parser.parse_args(argv)
    result: dict[str, Any] = {"machines": args.machines}
    with (
        tempfile.TemporaryDirectory(prefix="fleet-bench-") as scratch,
        broker(Path(scratch)) as port,
    ):
        machines: list[Machine] = []
        opcua = mqtt_client = None
        try:
            for index in range(1, args.machines + 1):
                machines.append(Machine(index, Path(scratch), port))
            for machine in machines:
                machine.wait_ready()
                machine.prepare()
            mqtt_arrivals: queue.Queue = queue.Queue()
            opcua_arrivals: queue.Queue = queue.Queue()
            mqtt_client = mqtt_listener(port, mqtt_arrivals)
            opcua = OpcuaListeners(machines, opcua_arrivals)
            time.sleep(1.0)  # the retained and initial values go by
            for arrivals in (mqtt_arrivals, opcua_arrivals):
                with contextlib.suppress(queue.Empty):
                    while True:
                        arrivals.get_nowait()
            changes = []
            for step in range(args.changes):
                scale = round(0.5 + 0.02 * step + 0.001, 4)  # new each time, never 1.0
                for machine in machines:
                    seen = machine.change_feed_override(scale)
                    if seen is None:
                        result["unseen_changes"] = result.get("unseen_changes", 0) + 1
                    else:
                        changes.append((machine.name, scale, seen))
                    time.sleep(0.03)
            result["mqtt_latency_ms"] = summary(latencies(changes, mqtt_arrivals))
            result["opcua_latency_ms"] = summary(latencies(changes, opcua_arrivals))
            result["bridge_cycle_time_s"] = 0.1
            result["cpu_percent_per_machine"] = {"idle": cpu_window(machines, args.seconds)}
            stop = threading.Event()
            mover = threading.Thread(target=move_back_and_forth, args=(machines, stop))
            mover.start()
            time.sleep(1.0)
            result["cpu_percent_per_machine"]["moving"] = cpu_window(machines, args.seconds)
            stop.set()
            mover.join()
            result["load_average"] = [round(x, 2) for x in os.getloadavg()]
        finally:
            if opcua is not None:
                opcua.stop()
            if mqtt_client is not None:
                mqtt_client.disconnect()
                mqtt_client.loop_stop()
            for machine in machines:
                machine.stop()
    result["jsonrpc_round_trip_ms"] = jsonrpc_round_trips(args.calls)
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
