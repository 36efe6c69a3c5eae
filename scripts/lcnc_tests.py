#!/usr/bin/env python3
"""Run LinuxCNC 2.9's own regression tests (its ``tests/`` folder) against this controller.

    .venv/bin/python scripts/lcnc_tests.py [-j N] [--timeout S] [--checkout DIR] [-v] [TEST ...]

The tests come from the LinuxCNC mirror (``git archive`` of the 2.9 branch into a scratch
folder, or ``--checkout DIR`` to reuse one) and run as LinuxCNC's ``scripts/runtests`` runs
them: ``test.hal`` with ``halrun -f`` (again while the result has an ``overrun`` line),
``test.sh`` with ``bash -x``, ``test`` directly; the result is compared with ``expected`` or
judged by ``checkresult``. No test and no expected output is edited: only names are mapped,
through a folder of wrappers put first on ``PATH`` and a module folder on ``PYTHONPATH``:

    linuxcnc -> cnc run          halcmd -> cnc halcmd        halrun -> cnc halrun
    halsampler -> cnc hal sample halstreamer -> cnc hal stream
    rs274 -> cnc rs274           linuxcncrsh -> cnc rsh      realtime -> cnc hal realtime
    python3 -> this Python (its ``import hal`` is ours)   import linuxcnc -> import cnc
    import gcode -> task.interp.python.gcode (LinuxCNC's preview interpreter module)
    rs274 -p canterp.so -> cnc rs274's canterp (task/interp/canterp.py, in Python)

Tests outside the project's scope (halcompile and C builds, Mesa hm2 hardware, Modbus
hardware, classicladder, Tk/GTK/Qt GUIs, LinuxCNC's uspace internals) are listed as
``OUT`` with the reason and not run; ``--all`` runs them too. Prints one line per test and
a summary; always exits 0 (CI does not run this: it needs the LinuxCNC mirror). Like
LinuxCNC's own run, the tests need ``nc`` (Debian: ``netcat-openbsd``) and ``bash``.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import difflib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO

REPO = Path(__file__).resolve().parents[1]
MIRROR = Path("/work/.mirror/LinuxCNC+linuxcnc/repo")
BRANCH = "2.9"
OVERRUN_RETRIES = 10
UTIL_MODULE = "lib/python/linuxcnc_util.py"

# test folder (or a prefix of it) -> why it is not this project's to pass
OUT_OF_SCOPE = {
    "build/": "C/C++ build against LinuxCNC's headers",
    "halcompile/": "halcompile (C components)",
    "hm2-idrom": "Mesa hm2 hardware",
    "interp/compile": "C++ build against LinuxCNC's librs274 and Python headers",
    "lowlevel/mutex": "C build against LinuxCNC's rtapi headers",
    "mb2hal/": "mb2hal: Modbus hardware driver",
    "module-loading/rtapi-app-main-fails": "halcompile (C component)",
    "pyhal": "module 'pyhal' is not part of LinuxCNC 2.9 (fails there too)",
    "pyvcp": "Tk GUI (pyvcp)",
    "realtime-math": "halcompile (C component)",
    "rtapi-shmem": "halcompile (C component), uspace internals",
    "rtapi_printf.0": "C build against LinuxCNC's rtapi",
    "symbols.0": "halcompile (C components): kernel symbol export",
    "symbols.1": "halcompile (C components): kernel symbol export",
    "uspace/": "uspace internals (rtapi_spawnv as root), halcompile",
}

# command -> what runs instead (arguments follow)
WRAPPERS = {
    "linuxcnc": ["-m", "cnc", "run"],
    "halcmd": ["-m", "cnc", "halcmd"],
    "halrun": ["-m", "cnc", "halrun"],
    "halsampler": ["-m", "cnc", "hal", "sample"],
    "halstreamer": ["-m", "cnc", "hal", "stream"],
    "rs274": ["-m", "cnc", "rs274"],
    "linuxcncrsh": ["-m", "cnc", "rsh"],
    "realtime": ["-m", "cnc", "hal", "realtime"],
    "python3": [],
    "python": [],
}


@dataclass
class Outcome:
    name: str
    verdict: str  # PASS, FAIL, OUT
    reason: str = ""
    seconds: float = 0.0
    diff: str = ""


def extract(checkout: Path, mirror: Path, branch: str) -> None:
    """``tests/``, ``scripts/runtests.in`` and the test helper module ``linuxcnc_util``
    (LinuxCNC's pure-Python layer over the ``linuxcnc`` module, which tests import) of
    ``branch`` from the mirror."""
    checkout.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(
        [
            "git",
            f"--git-dir={mirror}",
            "archive",
            branch,
            "tests",
            "scripts/runtests.in",
            UTIL_MODULE,
        ],
        capture_output=True,
        check=True,
    )
    subprocess.run(["tar", "-x", "-C", str(checkout)], input=archive.stdout, check=True)


def make_shims(folder: Path, checkout: Path) -> tuple[Path, Path]:
    """Wrapper commands, the ``linuxcnc`` module alias and LinuxCNC's own ``linuxcnc_util``
    (it imports ``linuxcnc``, so it runs on ours); returns (bin, python path)."""
    bin_dir, py_dir = folder / "bin", folder / "python"
    bin_dir.mkdir(parents=True, exist_ok=True)
    py_dir.mkdir(parents=True, exist_ok=True)
    for name, args in WRAPPERS.items():
        words = " ".join([sys.executable, *args])
        script = bin_dir / name
        script.write_text(f'#!/bin/sh\nexec {words} "$@"\n')
        script.chmod(0o755)
    (py_dir / "linuxcnc.py").write_text(
        '"""LinuxCNC\'s Python module name, mapped to ours."""\n'
        "import sys\n\nimport cnc\n\nsys.modules[__name__] = cnc\n"
    )
    (py_dir / "gcode.py").write_text(
        '"""LinuxCNC\'s preview interpreter module, mapped to ours."""\n'
        "import sys\n\nfrom task.interp.python import gcode\n\nsys.modules[__name__] = gcode\n"
    )
    if (checkout / UTIL_MODULE).is_file():
        shutil.copy(checkout / UTIL_MODULE, py_dir)
    return bin_dir, py_dir


def configure_runtests(checkout: Path, bin_dir: Path) -> Path:
    """LinuxCNC's runtests, configured as for an installed system (the ``overrun`` test
    runs it on a test of its own)."""
    text = (checkout / "scripts" / "runtests.in").read_text()
    values = {
        "@prefix@": "/usr",
        "@RUN_IN_PLACE@": "no",
        "@EMC2_HOME@": "/usr",
        "@includedir@": "/usr/include",
        "@WISH@": shutil.which("wish") or "wish",
        "@REALTIME@": str(bin_dir / "realtime"),
    }
    for key, value in values.items():
        text = text.replace(key, value)
    for key in ("@PYTHON_CPPFLAGS@", "@PYTHON_EXTRA_LIBS@", "@PYTHON_EXTRA_LDFLAGS@"):
        text = text.replace(key, "")
    path = checkout / "scripts" / "runtests"
    path.write_text(text)
    path.chmod(0o755)
    return path


def find_tests(tests_root: Path) -> list[Path]:
    found = []
    for path in tests_root.rglob("*"):
        if path.name in ("test.hal", "test.sh", "test") and path.is_file():
            found.append(path)
    return sorted(found)


def scope_reason(name: str) -> str:
    for prefix, reason in OUT_OF_SCOPE.items():
        if name == prefix.rstrip("/") or name.startswith(prefix):
            return reason
    return ""


# linuxcncrsh's TCP port is fixed (5007): the tests that use it run one at a time
RSH_PORT_LOCK = threading.Lock()


def uses_rsh_port(folder: Path) -> bool:
    return any(
        b"linuxcncrsh" in path.read_bytes()
        for path in folder.iterdir()
        if path.is_file() and path.suffix in ("", ".sh", ".ini", ".py")
    )


def run_one(script: Path, tests_root: Path, env: dict[str, str], timeout: float) -> Outcome:
    if uses_rsh_port(script.parent):
        with RSH_PORT_LOCK:
            return run_one_alone(script, tests_root, env, timeout)
    return run_one_alone(script, tests_root, env, timeout)


def run_one_alone(script: Path, tests_root: Path, env: dict[str, str], timeout: float) -> Outcome:
    folder = script.parent
    name = str(folder.relative_to(tests_root))
    started = time.monotonic()
    for leftover in ("result", "stderr"):
        (folder / leftover).unlink(missing_ok=True)
    instance = f"lt{os.getpid()}x{abs(hash(name)) % 10**8}"
    test_env = {**env, "TEST_DIR": str(folder), "CNC_INSTANCE": instance}
    if script.name == "test.hal":
        command = ["halrun", "-f", "test.hal"]
    elif script.name == "test.sh":
        command = ["bash", "-x", "test.sh"]
    else:
        command = ["./test"]
    exitcode = 0
    for _ in range(OVERRUN_RETRIES if script.name == "test.hal" else 1):
        with open(folder / "result", "wb") as out, open(folder / "stderr", "wb") as err:
            try:
                exitcode = run_in_own_group(command, folder, test_env, out, err, timeout)
            except subprocess.TimeoutExpired:
                cleanup(test_env)
                return Outcome(
                    name, "FAIL", f"timed out after {timeout:g} s", time.monotonic() - started
                )
            except OSError as exc:
                return Outcome(name, "FAIL", f"cannot run: {exc}", time.monotonic() - started)
        if b"overrun\n" not in (folder / "result").read_bytes().splitlines(keepends=True):
            break
    cleanup(test_env)
    seconds = time.monotonic() - started
    if exitcode != 0:
        return Outcome(
            name, "FAIL", f"test run exited with {exitcode}", seconds, tail(folder / "stderr")
        )
    if (folder / "checkresult").exists():
        check = subprocess.run(
            [str(folder / "checkresult"), str(folder / "result")],
            cwd=tests_root.parent,
            env=test_env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        if check.returncode != 0:
            return Outcome(
                name,
                "FAIL",
                f"checkresult exited with {check.returncode}",
                seconds,
                (check.stdout + check.stderr)[-2000:] + tail(folder / "stderr"),
            )
        return Outcome(name, "PASS", "", seconds)
    if (folder / "expected").is_file():
        expected = (folder / "expected").read_bytes()
        actual = (folder / "result").read_bytes()
        if expected != actual:
            diff = difflib.unified_diff(
                expected.decode(errors="replace").splitlines(),
                actual.decode(errors="replace").splitlines(),
                "expected",
                "result",
                lineterm="",
            )
            return Outcome(
                name,
                "FAIL",
                "result differed from expected",
                seconds,
                "\n".join(list(diff)[:40]) + "\n" + tail(folder / "stderr"),
            )
        return Outcome(name, "PASS", "", seconds)
    return Outcome(name, "FAIL", "neither expected nor checkresult exists", seconds)


def run_in_own_group(
    command: list[str], folder: Path, env: dict[str, str], out: IO, err: IO, timeout: float
) -> int:
    """Run a test's script in a process group of its own; on a timeout kill the whole
    group (the machine it launched too, not only its shell), then raise TimeoutExpired."""
    proc = subprocess.Popen(
        command,
        cwd=folder,
        env=env,
        stdout=out,
        stderr=err,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=5)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise


def tail(path: Path, lines: int = 15) -> str:
    try:
        text = path.read_text(errors="replace").splitlines()
    except OSError:
        return ""
    return "stderr:\n" + "\n".join(text[-lines:]) if text else ""


def cleanup(env: dict[str, str]) -> None:
    """Whatever a test left of its HAL and machine (its own instance only)."""
    subprocess.run(
        [sys.executable, "-m", "cnc", "halrun", "-U"], env=env, capture_output=True, timeout=60
    )
    # the NML buffers and semaphores of a machine killed at the timeout
    for leftover in Path("/dev/shm").glob(f"*.{env['CNC_INSTANCE']}.*"):
        leftover.unlink(missing_ok=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tests", nargs="*", help="test folders (relative to tests/) to run")
    parser.add_argument("--mirror", type=Path, default=MIRROR, help="LinuxCNC git mirror")
    parser.add_argument("--branch", default=BRANCH)
    parser.add_argument("--checkout", type=Path, help="reuse (or make) this checkout folder")
    parser.add_argument("-j", "--jobs", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per test")
    parser.add_argument("--all", action="store_true", help="also run out-of-scope tests")
    parser.add_argument("-v", "--verbose", action="store_true", help="print why tests fail")
    opts = parser.parse_args(argv)

    scratch = Path(tempfile.mkdtemp(prefix="lcnc-tests-"))
    checkout = opts.checkout or scratch / "linuxcnc"
    try:
        if not (checkout / UTIL_MODULE).is_file():
            extract(checkout, opts.mirror, opts.branch)
        bin_dir, py_dir = make_shims(scratch / "shims", checkout)
        env = dict(os.environ)
        env.pop("DISPLAY", None)
        env.update(
            LC_ALL="C",
            LANGUAGES="",
            PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
            PYTHONPATH=os.pathsep.join([str(py_dir), str(REPO), env.get("PYTHONPATH", "")]),
            REALTIME="realtime",
            SYSTEM_BUILD="1",
            EMC2_HOME="/usr",
            HEADERS="/usr/include/linuxcnc",
            LIBDIR="/usr/lib",
            LINUXCNC_EMCSH=shutil.which("wish") or "wish",
            RUNTESTS=str(configure_runtests(checkout, bin_dir)),
        )
        tests_root = checkout / "tests"
        scripts = find_tests(tests_root)
        if opts.tests:
            wanted = [t.strip("/") for t in opts.tests]
            scripts = [
                s
                for s in scripts
                if any(str(s.parent.relative_to(tests_root)).startswith(w) for w in wanted)
            ]
        outcomes: list[Outcome] = []
        to_run = []
        for script in scripts:
            name = str(script.parent.relative_to(tests_root))
            reason = scope_reason(name)
            if reason and not opts.all:
                outcomes.append(Outcome(name, "OUT", reason))
                print(f"OUT  {name}: {reason}", flush=True)
            elif (script.parent / "skip").exists():
                outcomes.append(Outcome(name, "OUT", "disabled by LinuxCNC (skip file)"))
            else:
                to_run.append(script)
        with concurrent.futures.ThreadPoolExecutor(max(opts.jobs, 1)) as pool:
            futures = [pool.submit(run_one, s, tests_root, env, opts.timeout) for s in to_run]
            for future in concurrent.futures.as_completed(futures):
                outcome = future.result()
                is_xfail = (tests_root / outcome.name / "xfail").exists()
                if is_xfail:
                    outcome.reason = f"expected to fail (xfail): {outcome.verdict}"
                    outcome.verdict = "XFAIL" if outcome.verdict == "FAIL" else "XPASS"
                outcomes.append(outcome)
                line = f"{outcome.verdict:<4} {outcome.name} ({outcome.seconds:.1f} s)"
                if outcome.reason:
                    line += f": {outcome.reason}"
                print(line, flush=True)
                if opts.verbose and outcome.diff and outcome.verdict == "FAIL":
                    print("    " + outcome.diff.replace("\n", "\n    "), flush=True)
        counts = {v: sum(o.verdict == v for o in outcomes) for v in ("PASS", "FAIL", "OUT")}
        in_scope = counts["PASS"] + counts["FAIL"]
        print(
            f"\n{counts['PASS']} passed, {counts['FAIL']} failed of {in_scope} in scope; "
            f"{counts['OUT']} out of scope; {len(outcomes)} tests in all"
        )
        failed = sorted(o.name for o in outcomes if o.verdict == "FAIL")
        if failed:
            print("failed: " + " ".join(failed))
    finally:
        shutil.rmtree(scratch / "shims", ignore_errors=True)
        shutil.rmtree(scratch, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
