"""Hardware drivers benchmark: a Mesa card's read + write per servo period, Modbus throughput.

    .venv/bin/python scripts/bench/hw_bench.py [--seconds S] [--no-lcnc]

Prints one JSON object:

- ``hm2``: the realtime host's 1 kHz servo thread running ``hm2_7i96s.0.read`` and
  ``.write`` against the simulated 7I96S (``hal.hm2.sim``, its own process, on loopback):
  the time of read + write each period (``period_time``: p50/p99/p99.9/max in µs, which
  includes waiting for the card's answer), the lateness of the periods, ``overruns`` and
  ``packet_errors`` (the watchdog timeout and packet error limit are raised, so that a
  stall on a busy machine does not stop the card and leave nothing to measure).
  ``other_rt_threads`` lists realtime threads of other processes on
  the same CPU (they delay ours: the figures mean little then).
- ``hm2_lcnc`` (as root, with LinuxCNC installed): LinuxCNC's own hm2_eth against the same
  simulated card, in two network namespaces (its driver needs a real interface):
  ``read``/``write`` ``tmax`` and last ``time`` in µs (all LinuxCNC exposes) and its packet
  errors.
- ``modbus``: Huanyang status reads (hy_vfd's exchange) per second over a pseudo-terminal
  against the simulated VFD, which answers at the pace of the baud rate, at 115200 and 19200
  baud, with ``wire_limit_per_s`` the most the line allows (frames back to back).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from hal.api import set_shared_hal  # noqa: E402
from hal.core import Hal  # noqa: E402
from hal.latency import other_rt_threads, period_starts, summary  # noqa: E402
from hal.modbus import huanyang as hy  # noqa: E402
from hal.modbus.rtu import RtuLink  # noqa: E402
from hal.modbus.vfd_sim import PtyPort, SimVfd, serve  # noqa: E402
from hal.rtapi_app import Host, host_options_from_env  # noqa: E402
from nml.ipcnames import INSTANCE_ENV  # noqa: E402

PERIOD_NS = 1_000_000
BOARD_IP = "127.77.0.1"
# what a period costs is measured, not how the card copes with a stalled host: on a busy
# machine a stall would otherwise make the watchdog bite or stop the link (io_error) and
# leave read and write with nothing to do
RELAXED = (("watchdog.timeout_ns", 200_000_000), ("packet-error-limit", 1_000_000))


def measure_hm2(seconds: float) -> dict[str, Any]:
    sim = subprocess.Popen(
        [sys.executable, "-m", "hal.hm2.sim", "--ip", BOARD_IP], cwd=REPO,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    time.sleep(1.0)
    hal = Hal()
    host = Host(hal, **host_options_from_env())
    try:
        host.prepare()
        host.loadrt("hostmot2", [])
        host.loadrt("hm2_eth", [f"board_ip={BOARD_IP}", "config=num_encoders=1 num_stepgens=5"])
        thread = host.new_thread("servo-thread", PERIOD_NS)
        for funct in ("hm2_7i96s.0.read", "hm2_7i96s.0.write"):
            hal.add_funct(funct, "servo-thread")
        for name, value in RELAXED:
            found = hal.find_param(f"hm2_7i96s.0.{name}")
            assert found is not None
            hal.write_slot(found[1]["type"], found[1]["slot"], value)
        for n in range(3):  # three moving axes, as a machine has
            for name, value in (("enable", 1), ("control-type", 1), ("velocity-cmd", 50.0)):
                found = hal.find_pin(f"hm2_7i96s.0.stepgen.{n:02d}.{name}")
                assert found is not None
                hal.write_slot(found[1]["type"], hal.ptr[found[1]["slot"]], value)
        hal.set_running(True)
        time.sleep(0.5)
        competitors = other_rt_threads(thread.cpu)
        errors_slot = hal.ptr[hal.find_pin("hm2_7i96s.0.packet-error-total")[1]["slot"]]
        errors_before = hal.u[errors_slot]
        thread.timing_log = log = []
        time.sleep(seconds)
        thread.timing_log = None
        errors = hal.u[errors_slot] - errors_before
        ran = [(deadline, start) for deadline, start, _ in log]
        all_periods = period_starts(ran, PERIOD_NS)
        overruns = len(all_periods) - len(ran)
        return {
            "period_time": summary([end - start for _, start, end in log], overruns),
            "lateness": summary([s - d for d, s in all_periods], overruns),
            "overruns": overruns,
            "packet_errors": int(errors),
            "other_rt_threads": competitors,
        }
    finally:
        host.unload_all()
        host.release_cpu()
        set_shared_hal(None)
        hal.destroy()
        hal.close()
        sim.terminate()
        sim.wait(5)


def measure_hm2_lcnc(seconds: float) -> dict[str, Any] | None:
    """LinuxCNC's hm2_eth on the same simulated card (root and LinuxCNC needed)."""
    if os.geteuid() != 0 or shutil.which("halrun") is None:
        return None
    sys.path.insert(0, str(REPO / "tests" / "hw"))
    import record_linuxcnc as rec

    rec.teardown()
    rec.setup()
    sim = subprocess.Popen(
        ["ip", "netns", "exec", rec.BOARD_NS, sys.executable, "-m", "hal.hm2.sim",
         "--ip", rec.BOARD_IP], cwd=REPO, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        time.sleep(1.0)
        hal_text = (
            f"loadrt hostmot2\nloadrt hm2_eth board_ip={rec.BOARD_IP} "
            'config="num_encoders=1 num_stepgens=5"\n'
            "loadrt threads name1=servo-thread period1=1000000\n"
            "addf hm2_7i96s.0.read servo-thread\naddf hm2_7i96s.0.write servo-thread\n"
            + "".join(f"setp hm2_7i96s.0.{name} {value}\n" for name, value in RELAXED)
            + "start\nloadusr -w sleep 1\nsetp hm2_7i96s.0.read.tmax 0\n"
            "setp hm2_7i96s.0.write.tmax 0\n"
            f"loadusr -w sleep {seconds}\n"
            "getp hm2_7i96s.0.read.tmax\ngetp hm2_7i96s.0.write.tmax\n"
            "getp hm2_7i96s.0.read.time\ngetp hm2_7i96s.0.write.time\n"
            "getp hm2_7i96s.0.packet-error-total\n"
        )
        with tempfile.NamedTemporaryFile("w", suffix=".hal", delete=False) as file:
            file.write(hal_text)
        Path(file.name).chmod(0o644)
        for _ in range(5):  # LinuxCNC's start-up waits 1.6 ms per answer: retry a busy moment
            run = subprocess.run(
                ["ip", "netns", "exec", rec.HOST_NS, "su", "cnc", "-c", f"halrun -f {file.name}"],
                capture_output=True, text=True, cwd="/tmp", check=False,
            )  # fmt: skip
            if run.returncode == 0:
                break
        else:
            return {"error": run.stderr.strip().splitlines()[-1:]}
        words = run.stdout.split()
        read_tmax, write_tmax, read_time, write_time = (int(w) / 1000 for w in words[:4])
        return {
            "read_tmax_us": read_tmax,
            "write_tmax_us": write_tmax,
            "read_time_us": read_time,
            "write_time_us": write_time,
            "packet_errors": int(words[4], 0),
        }
    finally:
        sim.terminate()
        sim.wait(5)
        rec.teardown()


def measure_modbus(baud: int, seconds: float, folder: str) -> dict[str, Any]:
    vfd = SimVfd(1, baud)
    port = PtyPort(str(Path(folder) / f"vfd-{baud}.tty"))
    stopping = []
    server = threading.Thread(target=serve, args=(vfd, port, lambda: bool(stopping)), daemon=True)
    server.start()
    link = RtuLink(port.link, baud, 8, "none", 1)
    request = hy.request(1, hy.READ_STATUS, value=hy.STATUS_OUTF)
    answer_bytes = hy.ANSWER_BYTES[hy.READ_STATUS]
    try:
        count, errors = 0, 0
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                link.transact(request, answer_bytes, 0.5, 0.5)
                count += 1
            except Exception:
                errors += 1
        wire = (len(request) + answer_bytes) * vfd.bits_per_char / baud
        return {
            "transactions_per_s": round(count / seconds, 1),
            "errors": errors,
            "wire_limit_per_s": round(1 / wire, 1),
        }
    finally:
        stopping.append(1)
        server.join(2)
        link.close()
        port.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--no-lcnc", action="store_true", help="skip LinuxCNC's hm2_eth")
    args = parser.parse_args()
    os.environ.setdefault(INSTANCE_ENV, f"hwbench{os.getpid()}")
    # the drivers' messages (loading, boards found) go to stderr: stdout is the JSON alone
    with contextlib.redirect_stdout(sys.stderr):
        result: dict[str, Any] = {"hm2": measure_hm2(args.seconds)}
        if not args.no_lcnc:
            result["hm2_lcnc"] = measure_hm2_lcnc(args.seconds)
        with tempfile.TemporaryDirectory() as folder:
            result["modbus"] = {
                str(baud): measure_modbus(baud, args.seconds / 2, folder)
                for baud in (115200, 19200)
            }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
