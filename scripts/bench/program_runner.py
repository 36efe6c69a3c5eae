#!/usr/bin/env python3
"""Runs G-code programs on a running controller through the LinuxCNC-style Python API, with
each servo period's commanded position recorded by a HAL sampler; used by motion_bench.py.

The same functions drive our controller (``import cnc``) and LinuxCNC's headless sim (its
``linuxcnc`` module, Debian's python3 as user ``cnc``), so both are timed alike: this file
needs nothing but the standard library. Every program starts from ``G90 G0 X0 Y0 Z10``, as
the reference bench (../shared/reference/bench_lcnc.py) does, and its time runs from
``auto(AUTO_RUN)`` until the interpreter is idle and motion in position.

As LinuxCNC's client (run from a folder user ``cnc`` can read)::

    python3 program_runner.py --lcnc --out DIR PROGRAM.ngc ...

prints ``{name: {"cycle_s", "is_ok", "messages", "samples"}}`` as JSON, ``samples`` being a
halsampler file in DIR with one row per servo period: the pins of ``SAMPLED_PINS``.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

START_MDI = "G90 G0 X0 Y0 Z10"
SAMPLED_PINS = ["axis.x.pos-cmd", "axis.y.pos-cmd", "axis.z.pos-cmd"]
SAMPLER_DEPTH = 16384  # rows: 16 s of servo periods between two reads


def wait_for(s: Any, condition: Callable[[Any], bool], timeout: float, step: float = 0.001) -> bool:
    """Poll ``s`` until ``condition(s)`` holds; False after ``timeout`` seconds."""
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        s.poll()
        if condition(s):
            return True
        time.sleep(step)
    return False


def set_mode(api: Any, s: Any, c: Any, mode: int) -> None:
    s.poll()
    if s.task_mode != mode:
        c.mode(mode)
        c.wait_complete(5)


def is_idle(api: Any) -> Callable[[Any], bool]:
    return lambda s: s.interp_state == api.INTERP_IDLE and s.inpos


def machine_on_and_homed(api: Any) -> None:
    """ESTOP reset, machine on, every joint homed (joint mode)."""
    s, c = api.stat(), api.command()
    c.state(api.STATE_ESTOP_RESET)
    c.wait_complete(5)
    c.state(api.STATE_ON)
    c.wait_complete(5)
    set_mode(api, s, c, api.MODE_MANUAL)
    c.teleop_enable(0)
    c.wait_complete(5)
    c.home(-1)
    c.wait_complete(5)
    if not wait_for(s, lambda s: all(s.homed[: s.joints]) and s.inpos, 60):
        raise RuntimeError("homing did not finish within 60 s")


def drain(e: Any) -> list[str]:
    """The operator messages waiting on error channel ``e``."""
    messages = []
    while (message := e.poll()) is not None:
        messages.append(str(message[1]))
    return messages


def run_program(api: Any, path: str, recorder: Any, timeout: float) -> dict[str, Any]:
    """Run one program from X0 Y0 Z10 while ``recorder`` (start()/stop()) samples the servo
    thread; its time from RUN until idle, whether it finished, and its messages."""
    s, c, e = api.stat(), api.command(), api.error_channel()
    set_mode(api, s, c, api.MODE_MDI)
    c.mdi(START_MDI)
    c.wait_complete(60)
    wait_for(s, is_idle(api), 60)
    set_mode(api, s, c, api.MODE_AUTO)
    drain(e)
    c.program_open(path)
    c.wait_complete(60)
    recorder.start()
    try:
        start = time.perf_counter()
        # no wait_complete() after auto(): poll instead, as bench_lcnc.py does
        c.auto(api.AUTO_RUN, 0)
        is_started = wait_for(s, lambda s: s.interp_state != api.INTERP_IDLE, 5, 0.0005)
        is_done = wait_for(s, is_idle(api), timeout)
        cycle_s = time.perf_counter() - start
        time.sleep(0.05)  # a few still periods after the end
    finally:
        recorder.stop()
    set_mode(api, s, c, api.MODE_MDI)
    return {
        "cycle_s": round(cycle_s, 3),
        "is_ok": bool(is_started and is_done),
        "messages": drain(e),
    }


class HalSampler:
    """LinuxCNC's ``sampler`` + ``halsampler`` on the sim's servo thread, wired while a
    program runs (halcmd as the calling user, who must be ``cnc``)."""

    def __init__(self, out: Path, pins: list[str]) -> None:
        self.out, self.pins = out, pins
        self.proc: subprocess.Popen | None = None
        self.made_signals: list[str] = []

    @staticmethod
    def _halcmd(*words: str) -> str:
        run = subprocess.run(["halcmd", *words], capture_output=True, text=True, timeout=30)
        if run.returncode != 0:
            raise RuntimeError(f"halcmd {' '.join(words)}: {run.stderr.strip() or run.stdout}")
        return run.stdout

    def _signal_of(self, pin: str) -> str | None:
        """The signal linked to ``pin``, from ``halcmd -s show pin``'s arrows."""
        words = self._halcmd("-s", "show", "pin", pin).split()
        for arrow in ("==>", "<==", "<=>"):
            if arrow in words:
                return words[words.index(arrow) + 1]
        return None

    def start(self) -> None:
        cfg = "f" * len(self.pins)
        self._halcmd("loadrt", "sampler", f"depth={SAMPLER_DEPTH}", f"cfg={cfg}")
        for index, pin in enumerate(self.pins):
            signal_name = self._signal_of(pin)
            if signal_name is None:
                signal_name = f"motion-bench-{index}"
                self._halcmd("net", signal_name, pin)
                self.made_signals.append(signal_name)
            self._halcmd("net", signal_name, f"sampler.0.pin.{index}")
        self._halcmd("addf", "sampler.0", "servo-thread")
        with open(self.out, "w") as file:
            self.proc = subprocess.Popen(["halsampler", "-c", "0"], stdout=file)

    def stop(self) -> None:
        if self.proc is not None:
            time.sleep(0.05)  # let halsampler read the last rows
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(10)
            self.proc = None
        self._halcmd("delf", "sampler.0", "servo-thread")
        self._halcmd("unloadrt", "sampler")
        for signal_name in self.made_signals:
            self._halcmd("delsig", signal_name)
        self.made_signals.clear()


def lcnc_main() -> None:
    """Entry point of the LinuxCNC client (see the module's docstring)."""
    parser = argparse.ArgumentParser(description="run programs on LinuxCNC's sim")
    parser.add_argument("--lcnc", action="store_true", required=True)
    parser.add_argument("--out", type=Path, required=True, help="folder for sample files")
    parser.add_argument("--timeout", type=float, default=300)
    parser.add_argument("programs", nargs="+")
    args = parser.parse_args()
    import linuxcnc  # Debian's python3 only

    machine_on_and_homed(linuxcnc)
    results = {}
    for program in args.programs:
        name = Path(program).stem
        samples = args.out / f"{name}.txt"
        result = run_program(
            linuxcnc, os.path.abspath(program), HalSampler(samples, SAMPLED_PINS), args.timeout
        )
        results[name] = result | {"samples": str(samples)}
        print(f"lcnc {name}: {result['cycle_s']} s", file=sys.stderr, flush=True)
    c = linuxcnc.command()
    c.state(linuxcnc.STATE_ESTOP)
    c.wait_complete(5)
    print(json.dumps(results))


if __name__ == "__main__":
    lcnc_main()
