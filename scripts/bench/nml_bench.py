#!/usr/bin/env python3
"""NML benchmark: status read cost, cross-process wake-up latency, queue throughput (JSON).

    python scripts/bench/nml_bench.py [--reads N] [--wakes N] [--messages N]

Keys: status_read_us_median (fixed layout), status_read_msgpack_us_median,
wake_latency_us_median, wake_latency_us_p99, queue_msgs_per_s, and
lcnc_stat_poll_us_median when LinuxCNC's headless sim is running here (see
../shared/reference/README.md: it is read as user ``cnc`` with Debian's python3).

A status read is what a UI does to refresh: copy the latest EMC_STAT out of shared memory and
decode it (fields are converted when read, as LinuxCNC's stat object does after poll()).
Wake-up latency: a message carrying its send time goes from one process to another that sleeps
in blocking_read(); the latency is receive time - send time on the shared monotonic clock.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from nml import emc  # noqa: E402
from nml.config import parse  # noqa: E402
from nml.ipcnames import INSTANCE_ENV, remove_instance_objects  # noqa: E402
from nml.shmem import ShmBuffer  # noqa: E402

NML = """\
B stat  SHMEM localhost 32768 0 0 1 8 1
B statm SHMEM localhost 32768 1 0 2 8 2
B q     SHMEM localhost 65536 0 0 3 8 3 queue
P bench stat  LOCAL localhost RW 0 5 1 0
P bench statm LOCAL localhost RW 0 5 1 0
P bench q     LOCAL localhost RW 0 5 1 0
P peer  q     LOCAL localhost RW 0 5 0 1
"""

LCNC_POLL = """
import linuxcnc, time, statistics
s = linuxcnc.stat(); s.poll()
t = []
for _ in range(5000):
    a = time.perf_counter(); s.poll(); t.append(time.perf_counter() - a)
print(statistics.median(t) * 1e6)
"""


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def status_read_us(buffer: ShmBuffer, reader: ShmBuffer, reads: int) -> float:
    status = emc.EMC_STAT()
    status.task.mode = 1
    status.motion.traj.position.tran.x = 1.0
    buffer.write(status)
    for _ in range(200):
        reader.peek()
    samples = []
    clock = time.perf_counter
    for _ in range(reads):
        start = clock()
        reader.peek()
        samples.append(clock() - start)
    return statistics.median(samples) * 1e6


def peer_main(nml_file: str, role: str, count: int) -> None:
    """The other process: ``echo`` answers wake-up probes, ``drain`` empties the queue."""
    from nml.config import load

    cfg = load(nml_file)
    buf = ShmBuffer(cfg.buffers["q"], cfg.process("peer", "q"))
    print("ready", flush=True)
    latencies = []
    for _ in range(count):
        msg = buf.blocking_read(10)
        if msg is None:
            break
        if role == "echo":
            latencies.append((time.monotonic() - msg.delay) * 1e6)
    buf.close()
    print(json.dumps(latencies), flush=True)


def start_peer(nml_file: str, role: str, count: int) -> subprocess.Popen[str]:
    proc = subprocess.Popen(
        [sys.executable, __file__, "--peer", nml_file, role, str(count)],
        stdout=subprocess.PIPE,
        text=True,
        env=dict(os.environ),
    )
    assert proc.stdout.readline().strip() == "ready"
    return proc


def wake_latency_us(queue: ShmBuffer, nml_file: str, wakes: int) -> list[float]:
    peer = start_peer(nml_file, "echo", wakes)
    probe = emc.EMC_TRAJ_DELAY()  # its f64 field carries the send time
    for _ in range(wakes):
        time.sleep(0.001)  # let the peer go back to sleep in blocking_read
        probe.delay = time.monotonic()
        queue.write(probe)
    out, _ = peer.communicate(timeout=60)
    return json.loads(out.strip().splitlines()[-1])


def queue_throughput(queue: ShmBuffer, nml_file: str, messages: int) -> float:
    peer = start_peer(nml_file, "drain", messages)
    msg = emc.EMC_TRAJ_LINEAR_MOVE()
    start = time.perf_counter()
    for index in range(messages):
        msg.id = index
        queue.write(msg)
    peer.communicate(timeout=120)
    return messages / (time.perf_counter() - start)


def lcnc_stat_poll_us() -> float | None:
    """LinuxCNC's stat.poll() median, if its headless sim is running on this machine."""
    if not Path("/usr/bin/python3").exists():
        return None
    command = ["/usr/bin/python3", "-c", LCNC_POLL]
    if os.geteuid() == 0 and subprocess.run(["id", "cnc"], capture_output=True).returncode == 0:
        command = ["su", "cnc", "-c", f"/usr/bin/python3 -c '{LCNC_POLL}'"]
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if result.returncode != 0:
        return None
    return round(float(result.stdout.strip().splitlines()[-1]), 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reads", type=int, default=5000)
    parser.add_argument("--wakes", type=int, default=2000)
    parser.add_argument("--messages", type=int, default=50000)
    parser.add_argument("--peer", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.peer:
        peer_main(args.peer[0], args.peer[1], int(args.peer[2]))
        return
    instance = f"bench{os.getpid()}"
    os.environ[INSTANCE_ENV] = instance
    nml_file = Path(f"/tmp/nml_bench_{os.getpid()}.nml")
    nml_file.write_text(NML)
    cfg = parse(NML, str(nml_file))
    opened: list[ShmBuffer] = []
    try:
        for name in ("stat", "statm", "q"):
            opened.append(ShmBuffer(cfg.buffers[name], cfg.process("bench", name)))
        stat, statm, queue = opened
        result: dict[str, object] = {
            "emc_stat_bytes": emc.EMC_STAT.fixed_size(),
            "status_read_us_median": round(status_read_us(stat, stat, args.reads), 2),
            "status_read_msgpack_us_median": round(status_read_us(statm, statm, args.reads), 2),
        }
        latencies = wake_latency_us(queue, str(nml_file), args.wakes)
        result["wake_latency_us_median"] = round(statistics.median(latencies), 1)
        result["wake_latency_us_p99"] = round(percentile(latencies, 0.99), 1)
        result["queue_msgs_per_s"] = round(queue_throughput(queue, str(nml_file), args.messages))
        lcnc = lcnc_stat_poll_us()
        if lcnc is not None:
            result["lcnc_stat_poll_us_median"] = lcnc
        print(json.dumps(result, indent=2))
    finally:
        for buffer in opened:
            buffer.close()
        remove_instance_objects(instance)
        nml_file.unlink(missing_ok=True)


if __name__ == "__main__":
    main()
