"""HAL benchmark: 1 kHz thread lateness with 20 typical components, idle and with load.

    .venv/bin/python scripts/bench/hal_bench.py [--seconds S] [--repeat N] [--no-lcnc]
        [--no-c] [--spin-us N] [--awake 0|1] [--cpu N] [--priority N]

The host runs with its defaults and ``$CNC_HAL_*`` settings (hal/README.md), changed by the
options; ``host`` in the report says which. Prints one JSON object:

- ``idle`` / ``loaded``: lateness of each period's start after its absolute deadline
  (p50/p99/p99.9/max in µs; a period skipped after an overrun counts as late as the next
  start), ``overruns`` (periods whose functions ran past the next deadline), ``periods``,
  ``thread_time`` (how long the functions took), ``steal_ms`` (time the hypervisor gave the
  vCPU to others), ``other_rt_threads`` (realtime threads of other processes on the CPU:
  other hosts at the same priority delay ours); ``interval_jitter`` has the statistics of
  |time between two period starts - period|, the metric measured for LinuxCNC. ``loaded``
  runs one busy process on every other CPU. With ``--repeat N`` (ours and the C loop
  alternate) each is the run with the median p99.9, ``*_runs`` lists all N and
  ``*_spread`` gives [min, max] over them.
- ``c_idle`` / ``c_loaded``: the same loop in C (hal_latency.c, built with gcc when there is
  one) with the same CPU, priority, spin and keep-awake settings: what the machine allows.
- ``pin_rw_ns``: cost of one pin access (read or write) from a component's function.
- ``lcnc`` (when LinuxCNC's halrun is installed): LinuxCNC's 1 ms thread on the same CPU,
  measured with its ``timedelta`` component and ``halsampler`` (|interval - period|, the
  only per-period timing LinuxCNC exposes), idle; ``lcnc_loaded`` the same with load.
"""

from __future__ import annotations

import argparse
import gc
import itertools
import json
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
from hal.latency import (  # the measuring shared with cnc latency-test
    other_rt_threads,
    start_load,
    steal_ticks,
    stop_load,
    summary,
)
from hal.latency import period_starts as _period_starts
from hal.rtapi_app import Host, default_rt_cpu, host_options_from_env
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


def c_command(
    binary: str, seconds: float, host_options: dict[str, Any], priority: int
) -> list[str]:
    """The C loop (hal_latency.c) with the host's CPU, spin and keep-awake settings."""
    return [
        binary,
        str(PERIOD_NS),
        str(seconds),
        str(rt_cpu(host_options)),
        str(priority if host_options.get("is_rt", True) else 0),
        str(host_options.get("spin_us", 0)),
        "1" if host_options.get("is_cpu_kept_awake") else "0",
    ]


def period_starts(starts: list[tuple[int, int]], period: int = PERIOD_NS) -> list[tuple[int, int]]:
    return _period_starts(starts, period)


def rt_cpu(host_options: dict[str, Any]) -> int:
    cpu = host_options.get("cpu")
    return default_rt_cpu() if cpu is None else cpu


def parse_c_output(text: str) -> dict[int, int]:
    """hal_latency's lines ``deadline lateness`` as {deadline: lateness} (ns)."""
    pairs = (line.split() for line in text.splitlines())
    return {int(words[0]): int(words[1]) for words in pairs if len(words) == 2}


def measure_ours(seconds: float, is_loaded: bool, host_options: dict[str, Any]) -> dict[str, Any]:
    """Our realtime host's 1 kHz thread with the 20 components (``Host(**host_options)``)."""
    hal = Hal()
    host = Host(hal, **host_options)
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
        load = start_load(thread.cpu) if is_loaded else []
        try:
            time.sleep(0.5)  # let the load settle
            hal.set_running(True)
            time.sleep(0.2)
            params = hal.meta["params"]
            overrun_slot = hal.meta["threads"]["servo-thread"]["overruns_slot"]
            tmax_slot = params["servo-thread.tmax"]["slot"]
            competitors = other_rt_threads(thread.cpu)
            before = hal.q[overrun_slot]
            hal.q[tmax_slot] = 0
            steal_before = steal_ticks(thread.cpu)
            thread.timing_log = log = []
            time.sleep(seconds)  # nothing else runs in this process meanwhile (GIL)
            thread.timing_log = None
            overruns = hal.q[overrun_slot] - before
            tmax = hal.q[tmax_slot]
            steal = steal_ticks(thread.cpu) - steal_before
        finally:
            stop_load(load)
        ran = [(deadline, start) for deadline, start, _ in log]
        lateness = [start - deadline for deadline, start in period_starts(ran)]
        starts = [start for _, start, _ in log]
        busy = [end - start for _, start, end in log]
        jitter = [abs(b - a - PERIOD_NS) for a, b in itertools.pairwise(starts)]
        return {
            **summary(lateness, int(overruns)),
            "thread_tmax_us": round(tmax / 1000, 1),
            # time the functions took each period (their start is the lateness above)
            "thread_time": summary(busy, int(overruns)),
            "steal_ms": steal * 10,
            "other_rt_threads": competitors,
            # the metric measured for LinuxCNC below, for a like-for-like comparison
            "interval_jitter": summary(jitter, int(overruns)),
        }
    finally:
        host.unload_all()
        host.release_cpu()
        set_shared_hal(None)
        hal.destroy()
        hal.close()
        gc.enable()


def build_c_check(folder: str) -> str | None:
    """Compile hal_latency.c (the same period loop in C); None without a C compiler."""
    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        return None
    binary = str(Path(folder) / "hal_latency")
    source = str(Path(__file__).with_name("hal_latency.c"))
    result = subprocess.run([compiler, "-O2", "-o", binary, source], capture_output=True)
    return binary if result.returncode == 0 else None


def measure_c(
    binary: str, seconds: float, is_loaded: bool, host_options: dict[str, Any]
) -> dict[str, Any] | None:
    """The C loop alone with the host's settings: what the machine itself allows."""
    cpu = rt_cpu(host_options)
    load = start_load(cpu) if is_loaded else []
    try:
        time.sleep(0.5 if is_loaded else 0)
        steal_before = steal_ticks(cpu)
        command = c_command(binary, seconds, host_options, host_options["priority"])
        result = subprocess.run(command, capture_output=True, text=True, timeout=seconds + 30)
        steal = steal_ticks(cpu) - steal_before
    finally:
        stop_load(load)
    ran = [(deadline, deadline + late) for deadline, late in parse_c_output(result.stdout).items()]
    lateness = [start - deadline for deadline, start in period_starts(ran)]
    if not lateness:
        return None
    # as the host counts them: a period that ended past the next deadline, which the loop
    # then skipped
    overruns = sum(1 for (a, _), (b, _) in itertools.pairwise(ran) if b - a > PERIOD_NS)
    return {**summary(lateness, overruns), "steal_ms": steal * 10}


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


def measure_lcnc(seconds: float, is_loaded: bool, cpu: int) -> dict[str, Any] | None:
    """LinuxCNC's servo thread on ``cpu``: |interval - period| of each period (timedelta)."""
    if not shutil.which("halrun"):
        return None
    samples = int(seconds * 1e9 / PERIOD_NS)
    with tempfile.TemporaryDirectory() as folder:
        os.chmod(folder, 0o777)
        path = Path(folder) / "lat.hal"
        path.write_text(LCNC_HAL.format(period=PERIOD_NS, samples=samples))
        os.chmod(path, 0o644)
        command = ["env", f"RTAPI_CPU_NUMBER={cpu}", "halrun", "-f", str(path)]
        if os.geteuid() == 0:  # LinuxCNC refuses to run as root
            shell = f"cd {folder} && RTAPI_CPU_NUMBER={cpu} halrun -f {path}"
            command = ["su", "cnc", "-c", shell]
        load = start_load(cpu) if is_loaded else []
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=seconds + 60)
        except (OSError, subprocess.TimeoutExpired):
            return None
        finally:
            stop_load(load)
    intervals = [
        int(line.split()[0]) for line in result.stdout.splitlines() if line.strip().isdigit()
    ][1:]
    if not intervals:  # e.g. another LinuxCNC session holds its (machine-wide) realtime
        lines = result.stderr.strip().splitlines()
        return {"error": lines[-1] if lines else f"halrun exited with {result.returncode}"}
    jitter = [abs(value - PERIOD_NS) for value in intervals]
    overruns = sum(1 for value in intervals if value > 2 * PERIOD_NS)
    return summary(jitter, overruns)


def spread(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """[min, max] over repeated runs of the figures that matter."""
    keys = ("p50_us", "p99_us", "p999_us", "max_us", "overruns")
    return {
        key: [min(r[key] for r in runs), max(r[key] for r in runs)]
        for key in keys
        if runs and all(r.get(key) is not None for r in runs)
    }


def median_run(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The run whose p99.9 is the median of the runs' (the upper one of an even number):
    one VM stall in a run decides its tail, so a single run says little."""
    return sorted(runs, key=lambda run: run["p999_us"])[len(runs) // 2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="per measurement")
    parser.add_argument("--repeat", type=int, default=1, help="measure idle/loaded N times")
    parser.add_argument("--no-lcnc", action="store_true", help="skip LinuxCNC")
    parser.add_argument("--no-c", action="store_true", help="skip the C loop (hal_latency.c)")
    parser.add_argument("--spin-us", type=int, help="host busy-wait margin (µs)")
    parser.add_argument("--cpu", type=int, help="CPU of the realtime thread")
    parser.add_argument("--priority", type=int, help="SCHED_FIFO priority of the thread")
    parser.add_argument(
        "--awake", type=int, choices=(0, 1), help="hold /dev/cpu_dma_latency at 0 (1) or not (0)"
    )
    opts = parser.parse_args()
    os.environ[INSTANCE_ENV] = f"bench{os.getpid()}"
    host_options = host_options_from_env()  # the host's defaults and $CNC_HAL_* knobs
    if opts.spin_us is not None:
        host_options["spin_us"] = opts.spin_us
    if opts.cpu is not None:
        host_options["cpu"] = opts.cpu
    if opts.awake is not None:
        host_options["is_cpu_kept_awake"] = bool(opts.awake)
    if opts.priority is not None:
        host_options["priority"] = opts.priority
    report: dict[str, Any] = {
        "period_us": PERIOD_NS / 1000,
        "components": len(FUNCTS),
        "host": host_options,
        "pin_rw_ns": measure_pin_rw(),
    }
    with tempfile.TemporaryDirectory() as folder:
        binary = None if opts.no_c else build_c_check(folder)
        runs: dict[str, list[dict[str, Any]]] = {}
        for _ in range(opts.repeat):
            for is_loaded in (False, True):
                label = "loaded" if is_loaded else "idle"
                runs.setdefault(label, []).append(
                    measure_ours(opts.seconds, is_loaded, host_options)
                )
                if binary is None:
                    continue
                result = measure_c(binary, opts.seconds, is_loaded, host_options)
                if result is not None:
                    runs.setdefault(f"c_{label}", []).append(result)
    for label, results in runs.items():
        report[label] = median_run(results)
        if len(results) > 1:
            report[f"{label}_runs"] = results
            report[f"{label}_spread"] = spread(results)
    if not opts.no_lcnc:
        cpu = rt_cpu(host_options)
        lcnc = measure_lcnc(opts.seconds, is_loaded=False, cpu=cpu)
        if lcnc is not None:
            report["lcnc"] = lcnc
            report["lcnc_loaded"] = measure_lcnc(opts.seconds, is_loaded=True, cpu=cpu)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
