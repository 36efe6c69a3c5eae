"""LinuxCNC's own remap and embedded-Python tests, and its remap sample configurations,
through ``cnc rs274`` exactly as LinuxCNC 2.9's rs274 ran them (issue 16).

The cases are listed in ``linuxcnc/cases.txt``; their inputs are LinuxCNC's, taken from the
LinuxCNC source mirror and from the installed sample configurations (so these tests skip
where those are not on the machine); what rs274 printed is recorded in
``linuxcnc/expected/`` by ``linuxcnc/make_expected.py``. Stdout (every canonical call, and
what Python printed, in order) and the exit status must be identical; stderr too, unless
the case compares stdout only. Where we differ on purpose, ``expected/<case>.ours.*`` holds
our output and ``linuxcnc/DEVIATIONS.txt`` says why (``python -m
tests.interp.test_linuxcnc_remap CASE ...`` writes those files from our run).
"""

from __future__ import annotations

import contextlib
import io
import os
import runpy
import sys
import tempfile
from pathlib import Path

import pytest

from .harness import _diff, run_rs274_inprocess
from .linuxcnc.cases import HERE, Case, cases


def run_case(case: Case, scratch: Path) -> tuple[str, str, int] | None:
    """Our (stdout, stderr, exit status) for the case, or None when its files are not here."""
    folder = case.prepare(scratch)
    if folder is None:
        return None
    if case.args[0] == "@python":
        out, err, rc = run_python_script(case.args[1:], folder)
    else:
        out, err, rc = run_rs274_inprocess(case.args, folder)
    return case.normalize(out, folder), case.normalize(err, folder), rc


def run_python_script(args: list[str], folder: Path) -> tuple[str, str, int]:
    """``python3 -m<module> args...`` in-process, our gcode module standing for LinuxCNC's."""
    from task.interp.python import gcode

    module = args[0].removeprefix("-m")
    out, err = io.StringIO(), io.StringIO()
    saved = os.getcwd(), list(sys.argv), list(sys.path), sys.modules.get("gcode")
    rc = 0
    try:
        os.chdir(folder)
        sys.argv = [module, *args[1:]]
        sys.path.insert(0, str(folder))
        sys.modules["gcode"] = gcode
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                runpy.run_module(module, run_name="__main__")
            except SystemExit as end:
                if isinstance(end.code, str):
                    err.write(end.code + "\n")
                    rc = 1
                else:
                    rc = end.code or 0
    finally:
        os.chdir(saved[0])
        sys.argv, sys.path = saved[1], saved[2]
        sys.modules.pop(module, None)
        if saved[3] is None:
            sys.modules.pop("gcode", None)
    return out.getvalue(), err.getvalue(), rc


def _expected(case: Case, suffix: str) -> str:
    ours = case.recorded(".ours" + suffix)
    path = ours if ours.exists() else case.recorded(suffix)
    return path.read_bytes().decode("latin-1")


@pytest.mark.parametrize("case", [pytest.param(c, id=c.name) for c in cases()])
def test_case_matches_linuxcnc(case: Case) -> None:
    with tempfile.TemporaryDirectory() as scratch:
        result = run_case(case, Path(scratch))
    if result is None:
        pytest.skip("LinuxCNC's source mirror or sample configurations are not here")
    out, err, rc = result
    problems = []
    if out != _expected(case, ".out"):
        problems.append("stdout differs:\n" + _diff(_expected(case, ".out"), out))
    if not case.is_stdout_only and err != _expected(case, ".err"):
        problems.append("stderr differs:\n" + _diff(_expected(case, ".err"), err))
    if rc != int(_expected(case, ".rc")):
        problems.append(f"exit status {rc}, expected {_expected(case, '.rc').strip()}")
    assert not problems, "\n".join(problems)


def test_every_case_is_recorded_and_every_deviation_explained() -> None:
    notes = (HERE / "DEVIATIONS.txt").read_text()
    for case in cases():
        assert case.recorded(".out").exists(), case.name
    for ours in (HERE / "expected").glob("*.ours.*"):
        name = ours.name.split(".ours.")[0].replace("__", "/")
        assert f"\n{name}:" in "\n" + notes, ours.name


if __name__ == "__main__":
    import sys

    for case in cases():
        if case.name not in sys.argv[1:]:
            continue
        with tempfile.TemporaryDirectory() as scratch:
            out, err, rc = run_case(case, Path(scratch))
        for suffix, text in ((".out", out), (".err", err), (".rc", f"{rc}\n")):
            if text != case.recorded(suffix).read_bytes().decode("latin-1"):
                case.recorded(".ours" + suffix).write_bytes(text.encode("latin-1"))
                print(f"wrote {case.recorded('.ours' + suffix).name}")
