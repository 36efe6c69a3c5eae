#!/usr/bin/env python3
"""Whole-machine benchmark: ours (``cnc run``) and LinuxCNC's headless sim, side by side.

    python scripts/bench/system_bench.py [--ini configs/sim/mill.ini] [--no-lcnc]

Prints JSON with ``startup_s``, ``poll_us_median``, ``mdi_rtt_ms_median``, ``mdi_rtt_ms_p90``,
``first_motion_ms``, ``home_all_s``, ``abort_slowdown_ms`` (from ``abort()`` during a
program of short moves at 25 mm/s until the velocity drops, median of 3), and the same
keys prefixed ``lcnc_`` when LinuxCNC's sim can be started here (../shared/reference:
setup.sh done, run as root).

The measurements are one function, ``measure(api)``, run once with ``import cnc`` and once
with LinuxCNC's ``linuxcnc`` module (as user ``cnc`` with Debian's python3), so both
controllers are driven by exactly the same code.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
REFERENCE = REPO.parent / "shared" / "reference"
PROGRAM = "G21 G90\nG0 X1 Y1\nG1 X2 F600\nG0 X1\nM2\n"
# 0.05 mm moves at 25 mm/s, aborted on the way (written beside PROGRAM as dense.ngc)
DENSE_PROGRAM = (
    "G21 G90 G64 G0 X0 Y0\nF1500\n"
    + "".join(f"G1 X{0.05 * i:.2f} Y{0.001 * (i % 2):.3f}\n" for i in range(1, 1000))
    + "M2\n"
)


def percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def wait_for(s, condition, timeout: float) -> bool:
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        s.poll()
        if condition(s):
            return True
        time.sleep(0.001)
    return False


def measure(api, program_path: str) -> dict[str, float]:
    """The figures of a running machine, through the LinuxCNC-style Python API."""
    s, c = api.stat(), api.command()
    s.poll()
    samples = []
    for _ in range(5000):
        start = time.perf_counter()
        s.poll()
        samples.append(time.perf_counter() - start)
    result = {"poll_us_median": statistics.median(samples) * 1e6}
    c.state(api.STATE_ESTOP_RESET)
    c.wait_complete(5)
    c.state(api.STATE_ON)
    c.wait_complete(5)
    c.mode(api.MODE_MANUAL)
    c.wait_complete(5)
    c.teleop_enable(0)
    c.wait_complete(5)
    start = time.perf_counter()
    c.home(-1)
    c.wait_complete(5)
    if wait_for(s, lambda s: all(s.homed[: s.joints]) and s.inpos, 60):
        result["home_all_s"] = time.perf_counter() - start
    c.mode(api.MODE_MDI)
    c.wait_complete(5)
    c.mdi("G90 G0 X0 Y0")
    c.wait_complete(10)
    samples = []
    for _ in range(100):
        start = time.perf_counter()
        c.mdi("G91 G0 X0")
        c.wait_complete(5)
        samples.append(time.perf_counter() - start)
    result["mdi_rtt_ms_median"] = statistics.median(samples) * 1e3
    result["mdi_rtt_ms_p90"] = percentile(samples, 0.9) * 1e3
    c.mdi("G90")
    c.wait_complete(5)
    c.mode(api.MODE_AUTO)
    c.wait_complete(5)
    c.program_open(program_path)
    c.wait_complete(5)
    s.poll()
    start_pos = s.position[0]
    start = time.perf_counter()
    c.auto(api.AUTO_RUN, 0)
    if wait_for(s, lambda s: abs(s.position[0] - start_pos) > 1e-6, 10):
        result["first_motion_ms"] = (time.perf_counter() - start) * 1e3
    wait_for(s, lambda s: s.interp_state == api.INTERP_IDLE and s.inpos, 30)
    slowdowns = []
    for _ in range(3):
        slowdowns.append(
            abort_slowdown_s(api, s, c, str(Path(program_path).with_name("dense.ngc")))
        )
    if None not in slowdowns:
        result["abort_slowdown_ms"] = statistics.median(slowdowns) * 1e3
    c.mode(api.MODE_MDI)
    c.wait_complete(5)
    c.state(api.STATE_ESTOP)
    c.wait_complete(5)
    return {key: round(value, 3) for key, value in result.items()}


def abort_slowdown_s(api, s, c, dense_path: str) -> float | None:
    """Run the dense program, abort it at speed: seconds until the velocity drops."""
    c.mode(api.MODE_AUTO)
    c.wait_complete(5)
    c.program_open(dense_path)
    c.wait_complete(5)
    c.auto(api.AUTO_RUN, 0)
    if not wait_for(s, lambda s: s.position[0] < 1.0, 30):  # (its G0 X0 first)
        return None
    if not wait_for(s, lambda s: s.position[0] > 20.0, 30):
        return None
    s.poll()
    speed = s.current_vel
    start = time.perf_counter()
    c.abort()
    if not wait_for(s, lambda s: s.current_vel < speed - 1e-6, 5):
        return None
    slowdown = time.perf_counter() - start
    wait_for(s, lambda s: s.interp_state == api.INTERP_IDLE and s.current_vel == 0, 10)
    return slowdown


def ours(ini: Path) -> dict[str, float]:
    import cnc

    folder = Path(tempfile.mkdtemp(prefix="system_bench_"))
    machine = folder / "machine"
    shutil.copytree(ini.parent, machine)
    program = folder / "bench.ngc"
    program.write_text(PROGRAM)
    program.with_name("dense.ngc").write_text(DENSE_PROGRAM)
    env = dict(os.environ, CNC_INSTANCE=f"bench{os.getpid()}")
    os.environ.update(env)
    start = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "cnc", "run", "--headless", ini.name],
        cwd=machine,
        env=env,
        stderr=subprocess.DEVNULL,
    )
    try:
        s = cnc.stat()
        while True:
            try:
                s.poll()
                break
            except cnc.error:
                if proc.poll() is not None or time.perf_counter() - start > 30:
                    raise SystemExit("our machine did not start") from None
                time.sleep(0.005)
        result = {"startup_s": round(time.perf_counter() - start, 3)}
        result |= measure(cnc, str(program))
        return result
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(30)
        shutil.rmtree(folder, ignore_errors=True)


def lcnc() -> dict[str, float] | None:
    """The same figures from LinuxCNC's headless sim, if it can run here."""
    if os.geteuid() != 0 or not (REFERENCE / "up.sh").exists() or not Path("/home/cnc").exists():
        return None
    work = Path("/tmp/system_bench_ref")
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(REFERENCE, work)
    (work / "bench.ngc").write_text(PROGRAM)
    (work / "dense.ngc").write_text(DENSE_PROGRAM)
    shutil.copy(__file__, work / "system_bench.py")
    subprocess.run(["chmod", "-R", "a+rX", str(work)], check=False)
    start = time.perf_counter()
    up = subprocess.run([str(work / "up.sh")], capture_output=True, text=True)
    if up.returncode != 0 or "ready" not in up.stdout + up.stderr:
        return None
    startup = time.perf_counter() - start
    try:
        code = (
            "import sys, json, linuxcnc; sys.path.insert(0, '/tmp/system_bench_ref'); "
            "import system_bench as b; "
            "print(json.dumps(b.measure(linuxcnc, '/tmp/system_bench_ref/bench.ngc')))"
        )
        run = subprocess.run(
            ["su", "cnc", "-c", f'/usr/bin/python3 -c "{code}"'],
            capture_output=True,
            text=True,
            timeout=300,
        )
        if run.returncode != 0:
            return None
        figures = json.loads(run.stdout.strip().splitlines()[-1])
    finally:
        subprocess.run([str(work / "down.sh")], capture_output=True)
    figures["startup_s"] = round(startup, 3)  # includes up.sh's own polling
    return {f"lcnc_{key}": value for key, value in figures.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    default_ini = REPO / "configs" / "sim" / "mill.ini"
    if not default_ini.exists():
        default_ini = REPO / "tests" / "task" / "machine" / "mill.ini"
    parser.add_argument("--ini", type=Path, default=default_ini)
    parser.add_argument("--no-lcnc", action="store_true")
    args = parser.parse_args()
    result = ours(args.ini.resolve())
    if not args.no_lcnc:
        result |= lcnc() or {}
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
