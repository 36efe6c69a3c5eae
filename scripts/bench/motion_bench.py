#!/usr/bin/env python3
"""Motion benchmark on the real controller: servo-thread lateness, motion's CPU time per
period, and the shared benchmark programs run end to end, next to LinuxCNC 2.9's sim.

    .venv/bin/python scripts/bench/motion_bench.py [--programs NAME|FILE ...] [--dense P]
                                                   [--no-lcnc] [--no-c] [--quick] [--keep]

Our machine is ``scripts/bench/axis_mm.ini`` (exactly the limits of LinuxCNC's sim
``axis_mm.ini``: per axis 30.48 mm/s and 508 mm/s², [TRAJ] 53.34 mm/s, 1 ms servo period),
started headless (``cnc run --headless``). Each program runs from ``G90 G0 X0 Y0 Z10``
through the ``cnc`` Python API (program_runner.py), while ``cnc hal sample`` records every
servo period: the commanded position and the pins of ``motion_probe`` (lateness of the
period's start, CPU and wall time of motion's two functions). The same programs then run
in LinuxCNC's headless sim (../shared/reference, as root; user ``cnc``), recorded with
halsampler.

Prints one JSON object:

- ``lateness``: ``{p50_us, p99_us, p999_us, max_us, overruns, periods}`` of the servo thread
  while the dense program runs (start of the period after its deadline; overruns from the
  host's servo-thread overrun count), and ``loaded`` the same with one busy process on every
  CPU but the realtime one.
- ``planner_us_per_period``: CPU time of motion-command-handler + motion-controller per
  period during the dense program (queueing moves, planning, joints, status), p50/p99/p999/max;
  ``planner_wall_us_per_period`` the same in wall time.
- ``machine_floor`` (with a C compiler): the same lateness figures of an empty 1 ms loop in
  C (hal_bench's hal_latency.c, same CPU, priority and settings as the host) for as long as
  the dense program ran, idle and ``loaded``: the overruns this machine itself causes (vCPU
  stalls, kernel), to read ours against.
- ``host_memory_growth_mib``: growth of the realtime host's resident memory while the dense
  program ran (memory locked: what it grows by is faulted in inside servo periods).
- ``programs``: per program ``ours_s`` (RUN to idle) and ``lcnc_s``, ``time_ratio``
  (ours / LinuxCNC), ``max_vel_ratio`` / ``max_acc_ratio`` (peak per-axis velocity and
  acceleration over the configured limit) and ``max_path_dev_mm`` (largest distance from
  the programmed path, which our interpreter computes: task/interp with a recording canon),
  ``stops`` (how often the machine comes to rest inside the program), ``servo`` (our servo
  thread during that program: lateness p99/max, overruns, planner p50/p99); ``lcnc_*`` the same
  figures of LinuxCNC's run; ``ours_is_ok`` / ``lcnc_is_ok`` (the run started and ended
  idle) and ``ours_messages`` / ``lcnc_messages`` (operator messages, if any).

Both machines run the programs in the order given (default: the shared set sorted by name,
as bench_lcnc.py does) in one session: a program can leave interpreter state that changes
the next one's path (pocket_g41 after oword_subs), so only the same order compares. Rows of
the sample files are periods the servo thread ran: an overrun skips periods, so velocities
stay per period. ``--quick`` runs circle_g64 only (also as the dense program) for a smoke
run; ``--keep`` keeps the sample files; ``--instance`` sets our machine's CNC_INSTANCE.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(HERE))

from hal_bench import build_c_check, measure_c, start_load, stop_load, summary  # noqa: E402
from program_runner import (  # noqa: E402
    SAMPLED_PINS,
    START_MDI,
    machine_on_and_homed,
    run_program,
)
from tp_bench import AXIS_ACC, AXIS_VEL, PERIOD, TRAJ_VEL, dense_path, seg_distance  # noqa: E402

REFERENCE = REPO.parent / "shared" / "reference"
PROGRAMS = REFERENCE / "programs"
MACHINE_FILES = ["axis_mm.ini", "axis_mm.hal", "axis_mm.var", "axis_mm.tbl"]
PROBE_PINS = ["motion-probe.0.lateness", "motion-probe.0.cpu-ns", "motion-probe.0.wall-ns"]
DENSE = "bigprog_50k"
QUICK = "circle_g64"
LCNC_WORK = Path("/tmp/motion_bench_ref")  # readable by user cnc (not under /root)
DEVIATION_WINDOW = 400  # programmed-path segments searched either side of the last match
WINDOW_TRUST_MM = 0.005  # farther from every segment of the window: search the whole path


# ------------------------------------------------------------------ our machine
@contextlib.contextmanager
def our_machine(folder: Path, instance: str) -> Iterator[dict[str, str]]:
    """Start ``cnc run --headless axis_mm.ini`` from a copy in ``folder`` as CNC_INSTANCE
    ``instance``; yields the environment that reaches it and stops it afterwards."""
    for name in MACHINE_FILES:
        shutil.copy(HERE / name, folder / name)
    env = dict(os.environ, CNC_INSTANCE=instance, CNC_HAL_COMPONENTS=str(HERE))
    os.environ.update(env)  # for `import cnc` in this process
    log = open(folder / "run.log", "w")  # noqa: SIM115
    proc = subprocess.Popen(
        [sys.executable, "-m", "cnc", "run", "--headless", "axis_mm.ini"],
        cwd=folder,
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    try:
        import cnc

        s = cnc.stat()
        deadline = time.perf_counter() + 30
        while True:
            try:
                s.poll()
                break
            except cnc.error:
                if proc.poll() is not None or time.perf_counter() > deadline:
                    log.flush()
                    text = (folder / "run.log").read_text()
                    raise SystemExit(f"our machine did not start:\n{text}") from None
                time.sleep(0.01)
        yield env
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


class CncSampler:
    """``cnc hal sample -T servo-thread`` into a file while a program runs; ``overruns``
    counts the servo thread's overruns while it records (not while it wires: loading a
    module into the realtime host may itself cost a period)."""

    def __init__(self, out: Path, env: dict[str, str]) -> None:
        self.out, self.env = out, env
        self.proc: subprocess.Popen | None = None
        self.overruns = 0

    def start(self) -> None:
        command = [sys.executable, "-m", "cnc", "hal", "sample", "-T", "servo-thread"]
        pins = SAMPLED_PINS + PROBE_PINS
        self.proc = subprocess.Popen([*command, "-o", str(self.out), *pins], env=self.env)
        deadline = time.perf_counter() + 10
        while not (self.out.exists() and self.out.stat().st_size):  # wired and recording
            if self.proc.poll() is not None or time.perf_counter() > deadline:
                raise SystemExit("cnc hal sample did not start recording")
            time.sleep(0.01)
        self.overruns = -thread_overruns()

    def stop(self) -> None:
        if self.proc is not None:
            time.sleep(0.05)  # let it read the last rows
            self.overruns += thread_overruns()
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(10)
            self.proc = None


def thread_overruns() -> int:
    """The realtime host's servo-thread overrun count of the running machine."""
    from hal.core import Hal

    hal = Hal(is_creating=False)
    try:
        return hal.thread_overruns("servo-thread")
    finally:
        hal.close()


def host_memory_kib() -> int:
    """Resident memory of the running machine's realtime host (owner of ``motmod``), KiB."""
    from hal.core import Hal

    hal = Hal(is_creating=False)
    try:
        pid = hal.meta["comps"]["motmod"]["pid"]
    finally:
        hal.close()
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def realtime_cpu() -> int:
    """The CPU of the realtime host's threads: $CNC_HAL_CPU, else the last one."""
    from hal.rtapi_app import CPU_ENV

    return int(os.environ.get(CPU_ENV) or (os.cpu_count() or 1) - 1)


def run_ours(
    programs: list[Path], dense: Path, folder: Path, instance: str, timeout: float
) -> tuple[dict[str, dict], dict[str, Any]]:
    """Every program on our machine, then the dense one again under load: per program
    {cycle_s, is_ok, messages, samples}, and per dense run {samples, overruns}."""
    import cnc

    results: dict[str, dict] = {}
    dense_runs: dict[str, Any] = {}
    with our_machine(folder, instance) as env:
        machine_on_and_homed(cnc)

        def run(program: Path, tag: str) -> dict:
            samples = folder / f"ours_{program.stem}{tag}.txt"
            recorder = CncSampler(samples, env)
            memory_before = host_memory_kib()
            result = run_program(cnc, str(program), recorder, timeout)
            grown_mib = round((host_memory_kib() - memory_before) / 1024, 1)
            print(f"ours {program.stem}{tag}: {result['cycle_s']} s", file=sys.stderr, flush=True)
            return result | {
                "samples": samples,
                "overruns": recorder.overruns,
                "host_memory_growth_mib": grown_mib,
            }

        for program in programs:
            results[program.stem] = run(program, "")
        dense_runs["idle"] = results.get(dense.stem) or run(dense, "")
        load = start_load(realtime_cpu())
        try:
            time.sleep(0.5)  # let the load settle
            dense_runs["loaded"] = run(dense, "_loaded")
        finally:
            stop_load(load)
    return results, dense_runs


def machine_floor(seconds: float, folder: Path) -> dict[str, Any] | None:
    """The C loop alone, idle then loaded, for ``seconds`` each (None without a compiler)."""
    from hal.rtapi_app import host_options_from_env

    binary = build_c_check(str(folder))
    if binary is None:
        return None
    options = host_options_from_env()
    idle = measure_c(binary, seconds, is_loaded=False, host_options=options)
    loaded = measure_c(binary, seconds, is_loaded=True, host_options=options)
    return None if idle is None else {**idle, "loaded": loaded}


# ------------------------------------------------------------------ LinuxCNC's sim
def run_lcnc(programs: list[Path], folder: Path, timeout: float) -> dict[str, dict] | None:
    """The programs in LinuxCNC's headless sim (up.sh / down.sh of ../shared/reference),
    driven by program_runner.py as user cnc, with their sample files moved to ``folder``;
    None when the sim cannot run here."""
    if os.geteuid() != 0 or not (REFERENCE / "up.sh").exists() or not Path("/home/cnc").exists():
        print("lcnc: skipped (needs root, ../shared/reference and user cnc)", file=sys.stderr)
        return None
    if not wait_for_no_sim(600):
        print("lcnc: skipped (another LinuxCNC sim kept running)", file=sys.stderr)
        return None
    shutil.rmtree(LCNC_WORK, ignore_errors=True)
    shutil.copytree(REFERENCE, LCNC_WORK)
    shutil.copy(HERE / "program_runner.py", LCNC_WORK / "program_runner.py")
    for program in programs:
        shutil.copy(program, LCNC_WORK / "programs" / program.name)
    out = LCNC_WORK / "samples"
    out.mkdir()
    (folder / "lcnc").mkdir()
    subprocess.run(["chmod", "-R", "a+rwX", str(LCNC_WORK)], check=False)
    try:
        up = subprocess.run([str(LCNC_WORK / "up.sh")], capture_output=True, text=True)
        if up.returncode != 0 or "ready" not in up.stdout + up.stderr:
            print(f"lcnc: the sim did not start: {up.stdout}{up.stderr}", file=sys.stderr)
            return None
        names = " ".join(str(LCNC_WORK / "programs" / p.name) for p in programs)
        command = (
            f"cd {LCNC_WORK} && /usr/bin/python3 program_runner.py --lcnc "
            f"--out {out} --timeout {timeout} {names}"
        )
        run = subprocess.run(
            ["su", "cnc", "-c", command],
            stdout=subprocess.PIPE,
            text=True,
            timeout=timeout * (len(programs) + 1),
        )
        if run.returncode != 0:
            print("lcnc: the client failed", file=sys.stderr)
            return None
        results = json.loads(run.stdout.strip().splitlines()[-1])
        for result in results.values():
            result["samples"] = Path(shutil.move(result["samples"], folder / "lcnc"))
    finally:
        subprocess.run([str(LCNC_WORK / "down.sh")], capture_output=True)
        shutil.rmtree(LCNC_WORK, ignore_errors=True)
    return results


def wait_for_no_sim(timeout: float) -> bool:
    """Only one LinuxCNC sim can run on a machine: wait until nobody else's is running."""
    deadline = time.perf_counter() + timeout
    while subprocess.run(["pgrep", "-x", "milltask"], capture_output=True).returncode == 0:
        if time.perf_counter() > deadline:
            return False
        time.sleep(2)
    return True


# ------------------------------------------------------------------ analysis
def load_samples(path: Path) -> tuple[np.ndarray, int]:
    """Rows of a (cnc hal sample / halsampler) file, and how many gaps it reports."""
    rows, gaps = [], 0
    for line in path.read_text().splitlines():
        if line.startswith("overrun"):
            gaps += 1
        elif line.strip():
            rows.append([float(word) for word in line.split()])
    return np.array(rows), gaps


def moving_span(positions: np.ndarray) -> slice:
    """The rows from the first to the last period in which the position changes."""
    moved = np.flatnonzero(np.any(np.diff(positions, axis=0) != 0, axis=1))
    if len(moved) == 0:
        return slice(0, 0)
    return slice(int(moved[0]), int(moved[-1]) + 2)


def programmed_paths(programs: list[Path], folder: Path) -> dict[str, np.ndarray]:
    """Each program's path from X0 Y0 Z10 as a fine polyline: our interpreter runs the
    programs with a canon that records each move (arcs split by tp_bench.dense_path). As on
    the machines, one interpreter runs them all in order, each after the MDI line
    ``START_MDI``: what one program leaves in the interpreter can change the next one's path
    (pocket_g41 after oword_subs makes more moves, in LinuxCNC too)."""
    from task.interp.canon import PLANE_XY, PLANE_YZ, PrintingCanon
    from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT, InterpError
    from task.interp.interp import Interpreter

    moves: list[dict] = []

    class RecordingCanon(PrintingCanon):
        def STRAIGHT_TRAVERSE(self, line, x, y, z, *rest) -> None:
            super().STRAIGHT_TRAVERSE(line, x, y, z, *rest)
            moves.append({"end": [x, y, z]})

        def STRAIGHT_FEED(self, line, x, y, z, *rest) -> None:
            super().STRAIGHT_FEED(line, x, y, z, *rest)
            moves.append({"end": [x, y, z]})

        def ARC_FEED(self, line, first_end, second_end, first_axis, second_axis, rotation,
                     *rest) -> None:  # fmt: skip
            start = list(self.position[:3])
            super().ARC_FEED(line, first_end, second_end, first_axis, second_axis, rotation, *rest)
            # (first, second, normal) axes of the plane, as LinuxCNC's canon orders them
            first, second, normal_axis = {PLANE_XY: (0, 1, 2), PLANE_YZ: (1, 2, 0)}.get(
                self.active_plane, (2, 0, 1)
            )
            centre = start
            centre[first], centre[second] = first_axis, second_axis
            normal = [0.0, 0.0, 0.0]
            normal[normal_axis] = 1.0 if rotation > 0 else -1.0
            moves.append(
                {
                    "end": list(self.position[:3]),
                    "centre": centre,
                    "normal": normal,
                    "turns": abs(rotation) - 1,
                }
            )

    canon = RecordingCanon(lambda text: None)
    var = folder / "path.var"
    shutil.copy(HERE / "axis_mm.var", var)
    interp = Interpreter(canon, parameter_file=str(var))
    paths = {}
    interp.init()
    for program in programs:
        try:
            interp.read(START_MDI)
            interp.execute()
            moves.clear()
            interp.open(str(program))
            while interp.read() != INTERP_ENDFILE and interp.execute() != INTERP_EXIT:
                pass
            interp.close()
        except InterpError as error:
            raise SystemExit(f"{program}: {error.message} at '{interp.linetext}'") from None
        paths[program.stem] = dense_path(moves)[0]
    return paths


def max_path_deviation(positions: np.ndarray, dense: np.ndarray, block: int = 64) -> float:
    """Largest distance of a sampled position from the programmed polyline ``dense``. The
    samples follow the path in order, so each block of samples is first compared with the
    segments around where the previous block matched; a sample farther than
    ``WINDOW_TRUST_MM`` from those is compared with the whole path (where a path passes
    itself again, as arc_spiral's return pass, the window alone can lose its place)."""
    a_all, b_all = dense[:-1], dense[1:]
    if len(a_all) == 0:
        return float(np.linalg.norm(positions - dense[0], axis=1).max())
    worst, at = 0.0, 0
    for first in range(0, len(positions), block):
        points = positions[first : first + block]
        lo, hi = max(at - DEVIATION_WINDOW, 0), min(at + DEVIATION_WINDOW, len(a_all))
        dist, nearest = _nearest_segments(points, a_all[lo:hi], b_all[lo:hi])
        nearest += lo
        far = dist > WINDOW_TRUST_MM
        if far.any():
            dist[far], nearest[far] = _nearest_segments(points[far], a_all, b_all)
        worst = max(worst, float(dist.max()))
        at = int(nearest[-1])
    return worst


def _nearest_segments(
    points: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 1_000_000
) -> tuple[np.ndarray, np.ndarray]:
    """For each point, the distance to the nearest segment a[i]-b[i] and that i."""
    best = np.full(len(points), np.inf)
    index = np.zeros(len(points), dtype=int)
    step = max(chunk // max(len(points), 1), 1)
    for lo in range(0, len(a), step):
        width = min(step, len(a) - lo)
        dist = seg_distance(
            np.repeat(points, width, axis=0),
            np.tile(a[lo : lo + width], (len(points), 1)),
            np.tile(b[lo : lo + width], (len(points), 1)),
        ).reshape(len(points), width)
        nearest = dist.argmin(axis=1)
        value = dist[np.arange(len(points)), nearest]
        better = value < best
        best[better], index[better] = value[better], nearest[better] + lo
    return best, index


def motion_figures(samples: Path, dense: np.ndarray) -> dict[str, Any]:
    """Peak per-axis velocity and acceleration over the limits, and the path deviation."""
    rows, gaps = load_samples(samples)
    positions = rows[:, :3]
    vel = np.abs(np.diff(positions, axis=0)) / PERIOD
    acc = np.abs(np.diff(positions, 2, axis=0)) / PERIOD**2
    speed = np.linalg.norm(np.diff(positions, axis=0), axis=1) / PERIOD  # along the path
    figures = {
        "max_vel_ratio": round(float(vel.max()) / AXIS_VEL, 4),
        "max_acc_ratio": round(float(acc.max()) / AXIS_ACC, 4),
        "max_path_dev_mm": round(max_path_deviation(positions, dense), 5),
        "max_speed_mm_s": round(float(speed.max()), 3),
        "stops": count_stops(speed),
    }
    if gaps:
        figures["sampler_gaps"] = gaps  # the sampler's FIFO overflowed: figures less exact
    return figures


def count_stops(speed: np.ndarray) -> int:
    """How often the machine comes to rest between its first and last motion."""
    is_moving = speed > 1e-9
    moving = np.flatnonzero(is_moving)
    if len(moving) == 0:
        return 0
    inside = is_moving[moving[0] : moving[-1] + 1]
    return int(np.count_nonzero(inside[:-1] & ~inside[1:]))


def period_figures(run: dict) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Lateness, motion's CPU and wall time per period over the moving part of a run."""
    rows, _ = load_samples(run["samples"])
    span = rows[moving_span(rows[:, :3])]
    lateness, cpu_us, wall_us = span[:, 3], span[:, 4] / 1000, span[:, 5] / 1000
    return (
        summary([int(v) for v in lateness], run["overruns"]),
        _stats(cpu_us),
        _stats(wall_us),
    )


def _stats(us: np.ndarray) -> dict[str, float | None]:
    if len(us) == 0:
        return {"p50": None, "p99": None, "p999": None, "max": None}
    return {
        "p50": round(float(np.median(us)), 1),
        "p99": round(float(np.percentile(us, 99)), 1),
        "p999": round(float(np.percentile(us, 99.9)), 1),
        "max": round(float(us.max()), 1),
    }


def run_notes(run: dict, prefix: str) -> dict[str, Any]:
    """Whether a run started and ended idle, and its operator messages (the five most
    frequent, with their counts) if it had any."""
    notes: dict[str, Any] = {f"{prefix}is_ok": run["is_ok"]}
    if run["messages"]:
        counts = Counter(run["messages"]).most_common(5)
        notes[f"{prefix}messages"] = [f"{text} (x{count})" for text, count in counts]
    return notes


def program_path(name: str) -> Path:
    """A program of the shared set by name, or a file."""
    path = Path(name)
    if path.suffix == ".ngc" and path.exists():
        return path.resolve()
    shared = PROGRAMS / f"{name}.ngc"
    if not shared.exists():
        raise SystemExit(f"motion_bench: no program '{name}' (neither a file nor in {PROGRAMS})")
    return shared


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--programs", nargs="+", help="names in the shared set, or .ngc files")
    parser.add_argument("--dense", help=f"program for lateness and CPU (default {DENSE})")
    parser.add_argument("--no-lcnc", action="store_true", help="skip LinuxCNC's sim")
    parser.add_argument("--no-c", action="store_true", help="skip the C loop (machine_floor)")
    parser.add_argument("--quick", action="store_true", help=f"{QUICK} only, a smoke run")
    parser.add_argument("--timeout", type=float, default=300, help="per program, seconds")
    parser.add_argument(
        "--keep", action="store_true", help="keep the sample files (folder named on stderr)"
    )
    parser.add_argument(
        "--instance", default=f"motionbench{os.getpid()}", help="CNC_INSTANCE of our machine"
    )
    args = parser.parse_args()
    if args.programs:
        names = args.programs
    elif args.quick:
        names = [QUICK]
    else:
        names = sorted(p.stem for p in PROGRAMS.glob("*.ngc"))
    programs = [program_path(name) for name in names]
    dense = program_path(args.dense or (names[0] if args.quick or args.programs else DENSE))
    folder = Path(tempfile.mkdtemp(prefix="motion_bench_"))
    try:
        ours, dense_runs = run_ours(programs, dense, folder, args.instance, args.timeout)
        lcnc = None if args.no_lcnc else run_lcnc(programs, folder, args.timeout)
        lateness, cpu, wall = period_figures(dense_runs["idle"])
        lateness["loaded"] = period_figures(dense_runs["loaded"])[0]
        report: dict[str, Any] = {
            "servo_period_us": PERIOD * 1e6,
            "limits": {"axis_vel": AXIS_VEL, "axis_acc": AXIS_ACC, "traj_vel": TRAJ_VEL},
            "dense_program": dense.stem,
            "lateness": lateness,
            "planner_us_per_period": cpu,
            "planner_wall_us_per_period": wall,
            "machine_floor": None
            if args.no_c
            else machine_floor(dense_runs["idle"]["cycle_s"], folder),
            "host_memory_growth_mib": dense_runs["idle"]["host_memory_growth_mib"],
            "programs": {},
        }
        paths = programmed_paths(programs, folder)
        for program in programs:
            name = program.stem
            dense_polyline = paths[name]
            mine = ours[name]
            entry: dict[str, Any] = {"ours_s": mine["cycle_s"], "lcnc_s": None}
            entry |= motion_figures(mine["samples"], dense_polyline)
            entry |= run_notes(mine, "ours_")
            lateness, cpu, _ = period_figures(mine)
            entry["servo"] = {
                "lateness_p99_us": lateness["p99_us"],
                "lateness_max_us": lateness["max_us"],
                "overruns": lateness["overruns"],
                "planner_us_p50": cpu["p50"],
                "planner_us_p99": cpu["p99"],
                "host_memory_growth_mib": mine["host_memory_growth_mib"],
            }
            theirs = (lcnc or {}).get(name)
            if theirs is not None:
                entry["lcnc_s"] = theirs["cycle_s"]
                entry["time_ratio"] = round(mine["cycle_s"] / theirs["cycle_s"], 4)
                entry |= run_notes(theirs, "lcnc_")
                lcnc_figures = motion_figures(theirs["samples"], dense_polyline)
                entry |= {f"lcnc_{key}": value for key, value in lcnc_figures.items()}
            report["programs"][name] = entry
        print(json.dumps(report, indent=2))
    finally:
        if args.keep:
            print(f"motion_bench: sample files kept in {folder}", file=sys.stderr)
        else:
            shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
