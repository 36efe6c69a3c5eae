#!/usr/bin/env python3
"""Fault benchmark: how fast a fault brings the simulated mill to rest and to E-stop.

    python scripts/bench/fault_bench.py [--runs 3] [--faults kill_iocontrol,stop_task ...]
                                        [--no-lcnc]

For each fault, on a fresh machine (configs/sim/mill.ini, headless, with halui) moving at
20 mm/s along X: the time from the fault to motion at rest and off (``rest_ms``, from
motion's own HAL pins, sampled every millisecond), to E-stop (``estop_ms``:
``iocontrol.0.user-enable-out`` false, the E-stop chain open), and whether an operator
message naming the fault reached the error channel (``has_message``); medians over
``--runs``. ``null`` means it did not happen within 10 s. ``jog_ui_killed`` measures the
end of a continuous jog whose UI was killed (no E-stop expected); ``rt_function_fails``
counts from the end of the ``halcmd addf`` that adds a function raising every period (a
machine already at rest then reads ~20 ms: the time it takes to see it stand still);
``kill_task`` has no E-stop figure: the launcher saves the positions and shuts down.

Where LinuxCNC's headless sim can be started here (../shared/reference, as root) the same
is measured for it where it has the process (``lcnc_kill_iocontrol``, ``lcnc_stop_task``),
from its HAL pins through ``halcmd`` (coarser: ~20 ms a sample).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import mmap
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
REFERENCE = REPO.parent / "shared" / "reference"
GIVE_UP_S = 10.0

import posix_ipc  # noqa: E402

import cnc  # noqa: E402
from hal.core import Hal  # noqa: E402
from nml.ipcnames import ipc_name  # noqa: E402
from nml.safety import NUM_SLOTS, SafetyBoard  # noqa: E402

HOLD_COMMAND_LOCK = (
    "import os, signal\nfrom cnc.api.connection import Link\n"
    "Link(None).buffer('emcCommand')._lock()\nprint('holding', flush=True)\n"
    "os.kill(os.getpid(), signal.SIGSTOP)\n"
)
JOG_THEN_DIE = (
    "import os, signal, time, cnc\nc = cnc.command()\nc.mode(cnc.MODE_MANUAL); c.wait_complete()\n"
    "c.teleop_enable(1); c.wait_complete()\nc.jog(cnc.JOG_CONTINUOUS, 0, 0, 20.0)\n"
    "c.wait_complete(); print('jogging', flush=True); time.sleep(0.3)\n"
    "os.kill(os.getpid(), signal.SIGKILL)\n"
)


class Machine:
    """A headless copy of the simulated mill, on, homed, in MDI mode."""

    def __init__(self, folder: Path) -> None:
        shutil.copytree(REPO / "configs" / "sim", folder)
        ini = folder / "mill.ini"
        ini.write_text(ini.read_text().replace("DISPLAY = top", "DISPLAY ="))
        self.folder = folder
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "cnc", "run", "--headless", "mill.ini"],
            cwd=folder,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
            env={**os.environ, "PYTHONPATH": str(REPO)},
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            with contextlib.suppress(cnc.error):
                self.s, self.c, self.e = cnc.stat(), cnc.command(), cnc.error_channel()
                self.s.poll()
                break
            time.sleep(0.1)
        c = self.c
        for state in (cnc.STATE_ESTOP_RESET, cnc.STATE_ON):
            c.state(state)
            c.wait_complete()
        c.mode(cnc.MODE_MANUAL)
        c.wait_complete()
        c.home(-1)
        self.until(lambda s: all(s.homed[:3]) and s.inpos, 30)
        c.mode(cnc.MODE_MDI)
        c.wait_complete()
        self.hal = Hal(is_creating=False)
        self.pins = {
            name: self.hal.find_pin(name)[1]
            for name in (
                "joint.0.pos-cmd",
                "motion.motion-enabled",
                "iocontrol.0.user-enable-out",
            )
        }

    def until(self, condition, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.s.poll()
            if condition(self.s):
                return
            time.sleep(0.01)
        raise RuntimeError("the machine did not get there")

    def pin(self, name: str) -> float:
        return self.hal.pin_value(self.pins[name])

    def pids(self) -> dict[str, int]:
        board = SafetyBoard.attach()
        try:
            return {
                slot.name: slot.pid
                for slot in map(board._slot, range(NUM_SLOTS))
                if slot.pid and slot.is_supervised
            }
        finally:
            board.close()

    def start_move(self) -> None:
        self.c.mdi("G1 F1200 X200")
        start = self.pin("joint.0.pos-cmd")
        deadline = time.monotonic() + 10
        while self.pin("joint.0.pos-cmd") - start < 2.0:  # at speed
            if time.monotonic() > deadline:
                raise RuntimeError("the move did not start")
            time.sleep(0.001)

    def watch(self, t0: float, is_estop_expected: bool = True) -> dict[str, float | None]:
        """Sample every millisecond from ``t0`` until at rest (and E-stop) or GIVE_UP_S."""
        rest = estop = None
        last, same_since = self.pin("joint.0.pos-cmd"), None
        while time.perf_counter() - t0 < GIVE_UP_S:
            now = time.perf_counter()
            x = self.pin("joint.0.pos-cmd")
            if x != last:
                last, same_since = x, None
            elif same_since is None:
                same_since = now
            is_off = not self.pin("motion.motion-enabled") or not is_estop_expected
            if rest is None and same_since is not None and now - same_since > 0.02 and is_off:
                rest = same_since - t0
            if estop is None and not self.pin("iocontrol.0.user-enable-out"):
                estop = now - t0
            if rest is not None and (estop is not None or not is_estop_expected):
                break
            time.sleep(0.001)
        return {
            "rest_ms": None if rest is None else rest * 1000,
            "estop_ms": None if estop is None else estop * 1000,
        }

    def has_message(self, words: str, wait: float = 1.0) -> bool:
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            message = self.e.poll()
            if message is None:
                time.sleep(0.01)
            elif words in message[1]:
                return True
        return False

    def stop(self, continued: list[int]) -> None:
        for pid in continued:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGCONT)
        with contextlib.suppress(Exception):
            self.hal.close()
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)


ESTOP_ON_ENTER = (
    "import sys, cnc\nc = cnc.command()\nprint('ready', flush=True)\nsys.stdin.readline()\n"
    "c.state(cnc.STATE_ESTOP)\nprint('sent', flush=True)\n"
)


def ui(code: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", code],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(REPO)},
        start_new_session=True,
    )


def estop_from_another_ui(started: subprocess.Popen[str]) -> float:
    """Tell a ready E-stop UI (ESTOP_ON_ENTER) to press E-stop; the moment it was told."""
    t0 = time.perf_counter()
    started.stdin.write("\n")
    started.stdin.flush()
    return t0


def run_fault(fault: str, folder: Path) -> dict[str, float | bool | None]:
    m = Machine(folder)
    continued: list[int] = []
    try:
        pids = m.pids()
        words, is_estop_expected = "E-stop", True
        if fault == "jog_ui_killed":
            jogger = ui(JOG_THEN_DIE)
            jogger.stdout.readline()
            jogger.wait()  # killed by itself: the fault
            t0 = time.perf_counter()
            result = m.watch(t0, is_estop_expected=False)
            return {**result, "has_message": m.has_message("continuous jog stopped")}
        m.start_move()
        if fault.startswith(("kill_", "stop_")):
            action, name = fault.split("_", 1)
            sig = signal.SIGKILL if action == "kill" else signal.SIGSTOP
            if sig == signal.SIGSTOP:
                continued.append(pids[name])
            t0 = time.perf_counter()
            os.kill(pids[name], sig)
            words = name
            if fault == "kill_task":  # the launcher shuts the machine down: rest only
                result = m.watch(t0)
                return {**result, "has_message": None}
        elif fault == "estop_while_task_frozen":
            presser = ui(ESTOP_ON_ENTER)
            presser.stdout.readline()
            continued.append(pids["task"])
            os.kill(pids["task"], signal.SIGSTOP)
            t0 = estop_from_another_ui(presser)
            words = ""
        elif fault == "estop_while_ui_holds_command_lock":
            presser = ui(ESTOP_ON_ENTER)
            presser.stdout.readline()
            holder = ui(HOLD_COMMAND_LOCK)
            holder.stdout.readline()
            continued.append(holder.pid)
            t0 = estop_from_another_ui(presser)
            words = "held the command lock"
        elif fault == "garbage_motCommand":
            shm = posix_ipc.SharedMemory(ipc_name("shm", "motCommand"))
            with mmap.mmap(shm.fd, shm.size) as mm:
                shm.close_fd()
                t0 = time.perf_counter()
                mm[:] = random.Random(1).randbytes(len(mm))
            words = "motion"
        elif fault == "rt_function_fails":  # from the end of `addf` (halcmd is slow to start)
            broken = REPO / "tests" / "hal" / "files" / "broken.py"
            for args in (["loadrt", str(broken)], ["addf", "broken.0", "servo-thread"]):
                subprocess.run([sys.executable, "-m", "cnc", "halcmd", *args], check=True)
            t0 = time.perf_counter()
            words = "HAL function broken.0 failed"
        else:
            raise SystemExit(f"unknown fault {fault}")
        result = m.watch(t0, is_estop_expected)
        return {**result, "has_message": m.has_message(words) if words else None}
    finally:
        m.stop(continued)


FAULTS = [
    "kill_iocontrol",
    "kill_halui",
    "stop_iocontrol",
    "stop_halui",
    "stop_task",
    "kill_task",
    "estop_while_task_frozen",
    "estop_while_ui_holds_command_lock",
    "garbage_motCommand",
    "rt_function_fails",
    "jog_ui_killed",
]


def summarise(runs: list[dict]) -> dict:
    out: dict[str, float | bool | None] = {}
    for key in ("rest_ms", "estop_ms"):
        values = [run[key] for run in runs if run[key] is not None]
        out[key] = round(statistics.median(values), 1) if len(values) == len(runs) else None
    messages = [run["has_message"] for run in runs]
    out["has_message"] = None if None in messages else all(messages)
    return out


# ------------------------------------------------------------------ LinuxCNC, where it runs
LCNC_CLIENT = """
import json, sys, time, linuxcnc
s, c = linuxcnc.stat(), linuxcnc.command()
c.state(linuxcnc.STATE_ESTOP_RESET); c.wait_complete()
c.state(linuxcnc.STATE_ON); c.wait_complete()
c.mode(linuxcnc.MODE_MANUAL); c.wait_complete(); c.teleop_enable(0); c.wait_complete(); c.home(-1)
t = time.time()
while time.time() - t < 20:
    s.poll()
    if all(s.homed[:3]) and s.inpos: break
    time.sleep(0.01)
c.mode(linuxcnc.MODE_MDI); c.wait_complete(); c.mdi("G1 F1200 X200")
time.sleep(1.0)
print("moving", flush=True)
"""


def halcmd_pin(name: str) -> str:
    done = subprocess.run(
        ["su", "cnc", "-c", f"halcmd -s getp {name}"], capture_output=True, text=True
    )
    return done.stdout.strip()


def lcnc_fault(fault: str) -> dict[str, float | None]:
    import fcntl

    home = os.environ.get("LCNC_HOME", "/home/cnc/lcnc")
    env = {**os.environ, "LCNC_HOME": home}
    lock = open("/tmp/lcnc-sim.lock", "w")  # noqa: SIM115  (one LinuxCNC sim per machine)
    fcntl.flock(lock, fcntl.LOCK_EX)
    subprocess.run([str(REFERENCE / "up.sh")], env=env, check=True, capture_output=True)
    try:
        client = subprocess.Popen(
            ["su", "cnc", "-c", f"/usr/bin/python3 -c '{LCNC_CLIENT}'"],
            stdout=subprocess.PIPE,
            text=True,
        )
        client.stdout.readline()
        name = {"kill_iocontrol": "io", "stop_task": "milltask"}[fault]
        pid = int(subprocess.check_output(["pgrep", "-x", name]).split()[0])
        t0 = time.perf_counter()
        os.kill(pid, signal.SIGKILL if fault.startswith("kill") else signal.SIGSTOP)
        last, rest = None, None
        while time.perf_counter() - t0 < GIVE_UP_S:
            x = halcmd_pin("joint.0.pos-cmd")
            if x == last and halcmd_pin("motion.motion-enabled") == "FALSE":
                rest = time.perf_counter() - t0
                break
            last = x
        if fault == "stop_task":
            os.kill(pid, signal.SIGCONT)
        client.wait(30)
        return {"rest_ms": None if rest is None else round(rest * 1000, 1)}
    finally:
        subprocess.run([str(REFERENCE / "down.sh")], env=env, capture_output=True)
        lock.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--faults", default=",".join(FAULTS))
    parser.add_argument("--no-lcnc", action="store_true")
    args = parser.parse_args()
    results: dict[str, dict] = {}
    for fault in args.faults.split(","):
        runs = []
        for index in range(args.runs):
            os.environ["CNC_INSTANCE"] = f"faultbench{os.getpid()}"
            with tempfile.TemporaryDirectory() as scratch:
                runs.append(run_fault(fault, Path(scratch) / f"m{index}"))
            print(fault, runs[-1], file=sys.stderr, flush=True)
        results[fault] = summarise(runs)
    if not args.no_lcnc and os.geteuid() == 0 and (REFERENCE / "up.sh").exists():
        for fault in ("kill_iocontrol", "stop_task"):
            try:
                results[f"lcnc_{fault}"] = lcnc_fault(fault)
            except (subprocess.CalledProcessError, OSError, ValueError) as exc:
                results[f"lcnc_{fault}"] = {"error": str(exc)}
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
