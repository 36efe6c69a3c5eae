"""HAL benchmark: 1 kHz thread lateness with 20 typical components, idle and with load.

    .venv/bin/python scripts/bench/hal_bench.py [--seconds S] [--no-lcnc] [--spin-us N]

Prints one JSON object:

- ``idle`` / ``loaded``: lateness of each period's start after its absolute deadline
  (p50/p99/p99.9/max in µs), ``overruns`` (periods whose functions ran past the next
  deadline) and ``periods`` measured; ``interval_jitter`` has the same statistics for
  |time between two period starts - period|, the metric measured for LinuxCNC. ``loaded``
  runs one busy process per other CPU.
- ``pin_rw_ns``: cost of one pin access (read or write) from a component's function.
- ``lcnc`` (when LinuxCNC's halrun is installed): LinuxCNC's 1 ms thread measured with its
  ``timedelta`` component and ``halsampler`` (|interval - period|, the only per-period timing
  LinuxCNC exposes), idle; ``lcnc_loaded`` the same with load.
"""

from __future__ import annotations

import argparse
import gc
import itertools
import json
import multiprocessing
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from hal.api import set_shared_hal
from hal.core import Hal
from hal.halcmd import HalCmd
from hal.rtapi_app import Host
from nml.ipcnames import INSTANCE_ENV

PERIOD_NS = 1_000_000

# 20 typical components wired like a small machine configuration
CONFIG = """\
loadrt siggen
loadrt ddt count=2
loadrt pid count=2
loadrt limit3
loadrt limit2
loadrt lowpass
loadrt scale count=2
loadrt sum2
loadrt mux2
loadrt and2
loadrt or2
loadrt not
loadrt comp
loadrt wcomp
loadrt near
loadrt timedelay
loadrt integ
net wave siggen.0.sine limit3.0.in ddt.0.in pid.0.command scale.0.in
net lim limit3.0.out limit2.0.in lowpass.0.in pid.1.command
net vel ddt.0.out ddt.1.in sum2.0.in0
net out0 pid.0.output integ.0.in
net fb integ.0.out pid.0.feedback comp.0.in0
net sq siggen.0.square wcomp.0.in mux2.0.in0 near.0.in1
net b1 comp.0.out and2.0.in0 timedelay.0.in
net b2 wcomp.0.out and2.0.in1 or2.0.in0
net b3 and2.0.out not.0.in mux2.0.sel
setp pid.0.enable 1
setp pid.1.enable 1
setp pid.0.Pgain 50
setp limit3.0.maxv 2
setp limit3.0.maxa 20
setp lowpass.0.gain 0.1
setp scale.0.gain 2
setp wcomp.0.min -0.5
setp wcomp.0.max 0.5
"""
FUNCTS = [
    "siggen.0.update",
    "ddt.0",
    "ddt.1",
    "limit3.0",
    "limit2.0",
    "lowpass.0",
    "scale.0",
    "scale.1",
    "sum2.0",
    "pid.0.do-pid-calcs",
    "pid.1.do-pid-calcs",
    "integ.0",
    "mux2.0",
    "and2.0",
    "or2.0",
    "not.0",
    "comp.0",
    "wcomp.0",
    "near.0",
    "timedelay.0",
]


def summary(lateness_ns: list[int], overruns: int) -> dict[str, Any]:
    values = sorted(lateness_ns)
    if not values:
        return {
            "p50_us": None,
            "p99_us": None,
            "p999_us": None,
            "max_us": None,
            "overruns": overruns,
            "periods": 0,
        }

    def quantile(q: float) -> float:
        return round(values[min(len(values) - 1, int(q * (len(values) - 1)))] / 1000, 1)

    return {
        "p50_us": quantile(0.5),
        "p99_us": quantile(0.99),
        "p999_us": quantile(0.999),
        "max_us": round(values[-1] / 1000, 1),
        "overruns": overruns,
        "periods": len(values),
    }


def _busy(cpu: int) -> None:
    os.sched_setaffinity(0, {cpu})
    while True:
        pass


def start_load() -> list[multiprocessing.Process]:
    """One busy process on every CPU but the last (the realtime one)."""
    count = os.cpu_count() or 1
    procs = [
        multiprocessing.Process(target=_busy, args=(cpu,), daemon=True)
        for cpu in range(max(count - 1, 1))
    ]
    for proc in procs:
        proc.start()
    return procs


def stop_load(procs: list[multiprocessing.Process]) -> None:
    for proc in procs:
        proc.terminate()
        proc.join()


def measure_ours(seconds: float, is_loaded: bool, spin_us: int) -> dict[str, Any]:
    hal = Hal()
    host = Host(hal, spin_us=spin_us)
    try:
        host.prepare()
        cmd = HalCmd(hal)
        for line in CONFIG.splitlines():
            words = line.split()
            if words[0] == "loadrt":
                host.loadrt(words[1], words[2:])
            elif not cmd.run_words(words):
                raise RuntimeError(f"bench config failed at: {line}")
        thread = host.new_thread("servo-thread", PERIOD_NS)
        for funct in FUNCTS:
            hal.add_funct(funct, "servo-thread")
        load = start_load() if is_loaded else []
        try:
            time.sleep(0.5)  # let the load settle
            hal.set_running(True)
            time.sleep(0.2)
            overrun_slot = hal.meta["params"]["servo-thread.overruns"]["slot"]
            before = hal.q[overrun_slot]
            thread.timing_log = log = []
            time.sleep(seconds)
            thread.timing_log = None
            overruns = hal.q[overrun_slot] - before
            tmax = hal.q[hal.meta["params"]["servo-thread.tmax"]["slot"]]
        finally:
            stop_load(load)
        lateness = [start - deadline for deadline, start in log]
        starts = [start for _, start in log]
        jitter = [abs(b - a - PERIOD_NS) for a, b in itertools.pairwise(starts)]
        return {
            **summary(lateness, int(overruns)),
            "thread_tmax_us": round(tmax / 1000, 1),
            # the metric measured for LinuxCNC below, for a like-for-like comparison
            "interval_jitter": summary(jitter, int(overruns)),
        }
    finally:
        host.unload_all()
        set_shared_hal(None)
        hal.destroy()
        hal.close()
        gc.enable()


def measure_pin_rw(count: int = 200_000) -> float:
    hal = Hal()
    host = Host(hal, is_rt=False)
    try:
        host.loadrt("scale", [])
        inst = host.modules["scale"].instances[0]
        start = time.perf_counter_ns()
        for _ in range(count):
            inst.out = inst.in_
        spent = time.perf_counter_ns() - start
        return round(spent / (2 * count), 1)
    finally:
        host.unload_all()
        set_shared_hal(None)
        hal.destroy()
        hal.close()


LCNC_HAL = """\
loadrt threads name1=servo-thread period1={period}
loadrt timedelta count=1
addf timedelta.0 servo-thread
loadrt sampler depth=4000 cfg=s
net td timedelta.0.out sampler.0.pin.0
addf sampler.0 servo-thread
start
loadusr -w halsampler -c 0 -n {samples}
show param servo-thread.tmax
"""


def measure_lcnc(seconds: float, is_loaded: bool) -> dict[str, Any] | None:
    """LinuxCNC's servo thread: |interval - period| of each period from timedelta."""
    if not shutil.which("halrun"):
        return None
    samples = int(seconds * 1e9 / PERIOD_NS)
    with tempfile.TemporaryDirectory() as folder:
        os.chmod(folder, 0o777)
        path = Path(folder) / "lat.hal"
        path.write_text(LCNC_HAL.format(period=PERIOD_NS, samples=samples))
        os.chmod(path, 0o644)
        command = ["halrun", "-f", str(path)]
        if os.geteuid() == 0:  # LinuxCNC refuses to run as root
            command = ["su", "cnc", "-c", f"cd {folder} && halrun -f {path}"]
        load = start_load() if is_loaded else []
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=seconds + 60)
        except (OSError, subprocess.TimeoutExpired):
            return None
        finally:
            stop_load(load)
    intervals = [
        int(line.split()[0]) for line in result.stdout.splitlines() if line.strip().isdigit()
    ][1:]
    if not intervals:
        return None
    jitter = [abs(value - PERIOD_NS) for value in intervals]
    overruns = sum(1 for value in intervals if value > 2 * PERIOD_NS)
    return summary(jitter, overruns)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="per measurement")
    parser.add_argument("--no-lcnc", action="store_true", help="skip LinuxCNC")
    parser.add_argument("--spin-us", type=int, default=0, help="host busy-wait margin (µs)")
    opts = parser.parse_args()
    os.environ[INSTANCE_ENV] = f"bench{os.getpid()}"
    report: dict[str, Any] = {
        "period_us": PERIOD_NS / 1000,
        "components": len(FUNCTS),
        "spin_us": opts.spin_us,
        "idle": measure_ours(opts.seconds, is_loaded=False, spin_us=opts.spin_us),
        "loaded": measure_ours(opts.seconds, is_loaded=True, spin_us=opts.spin_us),
        "pin_rw_ns": measure_pin_rw(),
    }
    if not opts.no_lcnc:
        lcnc = measure_lcnc(opts.seconds, is_loaded=False)
        if lcnc is not None:
            report["lcnc"] = lcnc
            report["lcnc_loaded"] = measure_lcnc(opts.seconds, is_loaded=True)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
