"""How late the realtime host's threads start their periods: the measuring shared by
``cnc latency-test`` and ``scripts/bench/hal_bench.py``.

A thread's *lateness* is how long after its absolute deadline a period starts (a period
skipped after an overrun counts as late as the next start); its *jitter* is |time between
two period starts - period|, what LinuxCNC's latency-test reports as "max jitter".
"""

from __future__ import annotations

import gc
import itertools
import multiprocessing
import os
import time
from pathlib import Path
from typing import Any


def summary(lateness_ns: list[int], overruns: int) -> dict[str, Any]:
    """p50/p99/p99.9/max in µs of a list of ns values, with the overruns and periods."""
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


def period_starts(starts: list[tuple[int, int]], period: int) -> list[tuple[int, int]]:
    """(deadline, start) of every period, from those of the periods that ran. A period
    skipped after an overrun is included, started at the next start: it did not run at all,
    so it counts as that late."""
    periods = []
    previous = None
    for deadline, start in starts:
        if previous is not None:
            periods += [(missed, start) for missed in range(previous + period, deadline, period)]
        periods.append((deadline, start))
        previous = deadline
    return periods


def _busy(cpu: int) -> None:
    os.sched_setaffinity(0, {cpu})
    while True:
        pass


def start_load(rt_cpu: int) -> list[multiprocessing.Process]:
    """One busy process on every CPU but the realtime one."""
    cpus = [cpu for cpu in range(os.cpu_count() or 1) if cpu != rt_cpu] or [rt_cpu]
    procs = [multiprocessing.Process(target=_busy, args=(cpu,), daemon=True) for cpu in cpus]
    for proc in procs:
        proc.start()
    return procs


def stop_load(procs: list[multiprocessing.Process]) -> None:
    for proc in procs:
        proc.terminate()
        proc.join()


def steal_ticks(cpu: int) -> int:
    """Time the hypervisor ran something else on ``cpu``'s vCPU, in USER_HZ ticks (10 ms)."""
    for line in Path("/proc/stat").read_text().splitlines():
        fields = line.split()
        if fields[0] == f"cpu{cpu}":
            return int(fields[8])
    return 0


def other_rt_threads(cpu: int) -> list[str]:
    """SCHED_FIFO/RR threads of other processes last seen on ``cpu`` ("pid:name prio").

    Other realtime hosts on the same CPU (other machines, tests) delay ours whenever their
    priority is the same or higher: the figures mean little then.
    """
    found = []
    for stat in Path("/proc").glob("[0-9]*/task/[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        name = text[text.index("(") + 1 : text.rindex(")")]
        fields = text[text.rindex(")") + 2 :].split()
        # fields from 3 (state) on: processor is field 39, rt_priority 40, policy 41
        processor, rt_priority, policy = int(fields[36]), int(fields[37]), int(fields[38])
        pid, is_kernel = int(stat.parts[2]), fields[1] in ("0", "2")  # parent: kthreadd
        if policy in (1, 2) and processor == cpu and pid != os.getpid() and not is_kernel:
            found.append(f"{pid}:{name} {rt_priority}")
    return sorted(set(found))


def measure_threads(
    periods_ns: list[int], seconds: float, *, is_loaded: bool, host_options: dict[str, Any]
) -> dict[str, Any]:
    """Run a realtime host with one empty thread per period (fastest first) for
    ``seconds``, with one busy process on every other CPU when ``is_loaded``; returns
    per thread (``base-thread``, ``servo-thread``) its lateness and jitter summaries."""
    from hal.api import set_shared_hal
    from hal.core import Hal
    from hal.rtapi_app import Host

    hal = Hal()
    host = Host(hal, **host_options)
    names = ["base-thread", "servo-thread"][-len(periods_ns) :]
    try:
        host.prepare()
        threads = [
            host.new_thread(name, period)
            for name, period in zip(names, sorted(periods_ns), strict=True)
        ]
        load = start_load(threads[0].cpu) if is_loaded else []
        try:
            time.sleep(0.3)  # let the load settle
            hal.set_running(True)
            time.sleep(0.2)
            competitors = other_rt_threads(threads[0].cpu)
            logs: list[list[tuple[int, int, int]]] = []
            for thread in threads:
                thread.timing_log = []
                logs.append(thread.timing_log)
            time.sleep(seconds)
            for thread in threads:
                thread.timing_log = None
        finally:
            stop_load(load)
        result: dict[str, Any] = {"other_rt_threads": competitors}
        for thread, log in zip(threads, logs, strict=True):
            ran = [(deadline, start) for deadline, start, _ in log]
            lateness = [s - d for d, s in period_starts(ran, thread.period)]
            starts = [start for _, start, _ in log]
            jitter = [abs(b - a - thread.period) for a, b in itertools.pairwise(starts)]
            overruns = len(period_starts(ran, thread.period)) - len(ran)
            result[thread.hal_name] = {
                "period_ns": thread.period,
                "lateness": summary(lateness, overruns),
                "jitter": summary(jitter, overruns),
            }
        return result
    finally:
        host.unload_all()
        host.release_cpu()
        set_shared_hal(None)
        hal.destroy()
        hal.close()
        gc.enable()
