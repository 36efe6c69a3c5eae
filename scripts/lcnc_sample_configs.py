#!/usr/bin/env python3
"""Run LinuxCNC 2.9's sample sim configs through ``cnc run --headless`` (issue 17).

Each config (``sim/axis/*.ini`` and ``sim/axis/*/*.ini`` of the ``linuxcnc-uspace``
package's sample configs, 77 of them) is copied with its neighbours to a scratch folder,
its ``[DISPLAY]DISPLAY`` blanked (nothing else changed), started with ``cnc run --headless``,
taken out of E-stop, turned on and homed through the Python API (``import cnc as
linuxcnc``), then stopped with SIGTERM. It passes when all of that works, the launcher exits
with status 0 and no shared memory is left behind.

    .venv/bin/python scripts/lcnc_sample_configs.py            # all of them
    .venv/bin/python scripts/lcnc_sample_configs.py gantry     # those whose path has 'gantry'
    .venv/bin/python scripts/lcnc_sample_configs.py -j 2 -v    # two at a time, with logs

Prints one line per config, then ``N passed, M failed``. Not run in CI: it needs LinuxCNC's
sample configs installed (``apt-get install linuxcnc-uspace``).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = Path("/usr/share/doc/linuxcnc/examples")
SAMPLES = EXAMPLES / "sample-configs"
SIM_AXIS = SAMPLES / "sim" / "axis"
START_TIMEOUT_S = 60.0
HOME_TIMEOUT_S = 90.0
STOP_TIMEOUT_S = 60.0
# The launcher's progress messages; any other line of its stderr may be the error.
_PROGRESS = re.compile(
    r"^cnc: (starting|running|NML buffers|machine ready|no display|removed|shutting down"
    r"|stopped|found|skipping)"
)
_DISPLAY_LINE = re.compile(r"^(\s*DISPLAY\s*=).*$", re.MULTILINE)


def sample_configs() -> list[Path]:
    return sorted([*SIM_AXIS.glob("*.ini"), *SIM_AXIS.glob("*/*.ini")])


def prepare(config: Path, scratch: Path) -> Path:
    """Copy the sample configs' ``sim`` and ``common`` folders (configs point into their
    neighbours and ``../../nc_files``) and blank DISPLAY in the INI and what it includes."""
    shutil.copytree(SAMPLES / "sim", scratch / "sim", symlinks=True)
    shutil.copytree(SAMPLES / "common", scratch / "common", symlinks=True)
    (scratch / "nc_files").symlink_to((SAMPLES / "nc_files").resolve())
    ini = scratch / config.relative_to(SAMPLES)
    for path in [ini, *included_files(ini)]:
        text = path.read_text(errors="replace")
        blanked = _DISPLAY_LINE.sub(r"\1", text)
        if blanked != text:
            path.unlink()  # it may be a link into the package: never write through it
            path.write_text(blanked)
    return ini


def included_files(ini: Path) -> list[Path]:
    found = []
    for line in ini.read_text(errors="replace").splitlines():
        if line.strip().upper().startswith("#INCLUDE"):
            name = os.path.expanduser(line.split(None, 1)[1].strip()) if " " in line else ""
            path = (ini.parent / name) if name else None
            if path is not None and path.is_file():
                found.append(path)
    return found


def first_error(log: str) -> str:
    """The launcher's complaint: the last message before it shut down that is neither
    progress, a warning nor "see the message above"."""
    lines = [line.strip() for line in log.splitlines() if line.strip()]
    if "cnc: shutting down" in lines:
        lines = lines[: lines.index("cnc: shutting down")]
    for line in reversed(lines):
        if _PROGRESS.match(line) or "(see the message above)" in line:
            continue
        if re.search(r": exit \d+$", line):  # a Tcl file's exit: its reason came before
            continue
        if "warning" in line.lower() or "skipping" in line:
            continue
        return line
    return lines[-1] if lines else "(no output)"


# ------------------------------------------------------------------ one config, in a child
def run_one(ini: Path, instance: str) -> dict[str, object]:
    """Start, turn on, home, stop; in its own process with its own CNC_INSTANCE."""
    os.environ["CNC_INSTANCE"] = instance
    os.environ.setdefault("CNC_HAL_NO_RT", "1")  # several hosts on 2 cores: no SCHED_FIFO
    import cnc as linuxcnc
    from cnc.runtime import read_runtime_info
    from nml.ipcnames import remove_instance_objects

    log_path = ini.parent / f"{ini.stem}.cnc-run.log"
    with open(log_path, "w") as log:
        launcher = subprocess.Popen(
            [sys.executable, "-m", "cnc", "run", "--headless", ini.name],
            cwd=ini.parent,
            stdout=log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
        )
    step, error = "start", ""
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while (info := read_runtime_info()) is None or info.pid != launcher.pid:
            if launcher.poll() is not None:
                raise RuntimeError(f"the launcher exited (status {launcher.returncode})")
            if time.monotonic() > deadline:
                raise RuntimeError(f"not ready within {START_TIMEOUT_S:g} s")
            time.sleep(0.1)
        step = "turn on"
        stat, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()
        command.state(linuxcnc.STATE_ESTOP_RESET)
        command.wait_complete()
        command.state(linuxcnc.STATE_ON)
        command.wait_complete()
        stat.poll()
        if stat.task_state != linuxcnc.STATE_ON:
            raise RuntimeError(f"task_state {stat.task_state} after STATE_ON{messages(errors)}")
        step = "home"
        home_all(linuxcnc, stat, command, errors)
    except Exception as exc:  # reported, then the machine is stopped as always
        error = f"{step}: {exc}"
    if launcher.poll() is None:
        launcher.send_signal(signal.SIGTERM)
    try:
        status = launcher.wait(STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(launcher.pid, signal.SIGKILL)
        status = launcher.wait()
        error = error or f"stop: not stopped within {STOP_TIMEOUT_S:g} s"
    leftovers = remove_instance_objects(instance)
    log_text = log_path.read_text(errors="replace")
    if error.startswith("start:"):
        error = f"start: {first_error(log_text)}"
    elif not error and status != 0:
        error = f"stop: exit status {status}: {first_error(log_text)}"
    elif not error and leftovers:
        error = f"stop: left {len(leftovers)} shared-memory objects"
    return {"config": str(ini), "ok": not error, "error": error, "log": str(log_path)}


def home_all(linuxcnc, stat, command, errors) -> None:
    command.mode(linuxcnc.MODE_MANUAL)
    command.wait_complete()
    command.teleop_enable(0)
    command.wait_complete()
    command.home(-1)
    command.wait_complete()
    deadline = time.monotonic() + HOME_TIMEOUT_S
    is_tried_each = False
    while True:
        time.sleep(0.1)
        stat.poll()
        joints = stat.joints
        homed = stat.homed[:joints]
        if all(homed):
            return
        is_homing = any(stat.joint[j]["homing"] for j in range(joints))
        if not is_homing and not is_tried_each:
            # joints without HOME_SEQUENCE are not homed by "home all": home them one by one
            is_tried_each = True
            for joint in range(joints):
                stat.poll()
                if not stat.homed[joint]:
                    command.home(joint)
                    command.wait_complete()
                    wait_while_homing(stat, joint, deadline)
            continue
        if (not is_homing and is_tried_each) or time.monotonic() > deadline:
            missing = [j for j in range(joints) if not homed[j]]
            raise RuntimeError(f"joints {missing} not homed{messages(errors)}")


def wait_while_homing(stat, joint: int, deadline: float) -> None:
    time.sleep(0.1)
    while time.monotonic() < deadline:
        stat.poll()
        if not stat.joint[joint]["homing"]:
            return
        time.sleep(0.05)


def messages(errors) -> str:
    texts = []
    while (message := errors.poll()) is not None:
        texts.append(message[1].strip())
    return f" ({'; '.join(texts)})" if texts else ""


# ------------------------------------------------------------------ the whole run
def run_in_child(config: Path, scratch_root: Path, index: int, is_keep: bool) -> dict[str, object]:
    scratch = scratch_root / f"{index:02d}-{config.stem}"
    scratch.mkdir()
    ini = prepare(config, scratch)
    instance = f"lcncsample{os.getpid()}-{index}"
    done = subprocess.run(
        [sys.executable, __file__, "--one", str(ini), "--instance", instance],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    for line in reversed(done.stdout.splitlines()):
        if line.startswith("{"):
            result = json.loads(line)
            break
    else:
        tail = (done.stderr.strip().splitlines() or ["(nothing)"])[-1]
        result = {"config": str(ini), "ok": False, "error": f"driver crashed: {tail}", "log": ""}
    result["config"] = str(config.relative_to(SIM_AXIS))
    if result["log"]:  # the log outlives the scratch copy (21 MB a config)
        log = scratch_root / f"{scratch.name}.log"
        shutil.copyfile(result["log"], log)
        result["log"] = str(log)
    if not is_keep:
        shutil.rmtree(scratch, ignore_errors=True)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("patterns", nargs="*", help="run only configs whose path has one")
    parser.add_argument("-j", "--jobs", type=int, default=1, help="configs run at a time")
    parser.add_argument("-v", "--verbose", action="store_true", help="print each log's path")
    parser.add_argument("--keep", action="store_true", help="keep the scratch folders")
    parser.add_argument("--json", help="also write the results to this file")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--instance", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(Path(args.one), args.instance)), flush=True)
        return 0
    if not SIM_AXIS.is_dir():
        print(f"no sample configs at {SIM_AXIS}: install linuxcnc-uspace", file=sys.stderr)
        return 2
    configs = [
        c
        for c in sample_configs()
        if not args.patterns or any(p in str(c.relative_to(SIM_AXIS)) for p in args.patterns)
    ]
    scratch_root = Path(tempfile.mkdtemp(prefix="lcnc-samples-"))
    results = []
    try:
        with concurrent.futures.ThreadPoolExecutor(max(1, args.jobs)) as pool:
            futures = [
                pool.submit(run_in_child, config, scratch_root, index, args.keep)
                for index, config in enumerate(configs)
            ]
            for future in futures:
                result = future.result()
                results.append(result)
                mark = "ok  " if result["ok"] else "FAIL"
                print(
                    f"{mark} {result['config']}" + ("" if result["ok"] else f": {result['error']}")
                )
                if args.verbose and result.get("log"):
                    print(f"     log: {result['log']}")
                sys.stdout.flush()
    finally:
        print(f"logs{' and scratch folders' if args.keep else ''} in {scratch_root}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1) + "\n")
    passed = sum(1 for r in results if r["ok"])
    print(f"{passed} passed, {len(results) - passed} failed")
    return 0 if passed == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())
