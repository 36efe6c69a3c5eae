"""Remapping and embedded Python against LinuxCNC 2.9's rs274 -i (issue 16, TEST-001..008).

Every program ``prog*.ngc`` of every scenario folder in ``remap/`` runs through
``cnc rs274 -g -i test.ini [args]`` in a scratch copy of its folder (with the standard glue
module copied in as ``glue/``; the folder's path is SCRATCH in the outputs), exactly as
``remap/make_expected.sh`` ran LinuxCNC's rs274:
stdout (canonical calls and what Python printed, in order) and the exit status must be
identical, and so must stderr, except where a scenario deviates on purpose: then
``<program>.ours.out``, ``.ours.err``, ``.ours.rc`` hold our output and ``DEVIATIONS`` in the
folder says why (the rs274 recordings stay next to them). ``python -m
tests.interp.test_remap_scenarios PROGRAM ...`` writes those files from our run.
"""

from __future__ import annotations

import shlex
import shutil
import tempfile
from pathlib import Path

import pytest

from .harness import _diff, run_rs274_inprocess

SCENARIOS = Path(__file__).with_name("remap")
GLUE = Path(__file__).resolve().parents[2] / "task" / "interp" / "python" / "glue"


def _programs() -> list:
    return [
        pytest.param(program, id=f"{program.parent.name}/{program.stem}")
        for program in sorted(SCENARIOS.glob("*/prog*.ngc"))
    ]


def run_scenario(program: Path) -> tuple[str, str, int]:
    """Run ``program`` the way make_expected.sh ran rs274: (stdout, stderr, exit status)."""
    folder = program.parent
    args_file = folder / "args"
    args = shlex.split(args_file.read_text()) if args_file.exists() else []
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(scratch) / "w"
        shutil.copytree(
            folder,
            work,
            ignore=shutil.ignore_patterns("prog*.out", "prog*.err", "prog*.rc", "__pycache__"),
        )
        (work / "glue").mkdir()
        shutil.copy(GLUE / "stdglue.py", work / "glue" / "stdglue.py")
        out, err, rc = run_rs274_inprocess(["-g", "-i", "test.ini", *args, program.name], work)
    # Python tracebacks name the scratch folder (make_expected.sh does the same)
    return out.replace(str(work), "SCRATCH"), err.replace(str(work), "SCRATCH"), rc


@pytest.mark.parametrize("program", _programs())
def test_program_matches_rs274(program: Path) -> None:
    out, err, rc = run_scenario(program)
    want_out_file = _expected(program, ".out")
    want_out = want_out_file.read_bytes().decode("latin-1")
    want_err_file = _expected(program, ".err")
    want_err = want_err_file.read_bytes().decode("latin-1")
    want_rc = int(_expected(program, ".rc").read_text())
    problems = []
    if out != want_out:
        problems.append(f"stdout differs from {want_out_file.name}:\n" + _diff(want_out, out))
    if err != want_err:
        problems.append(f"stderr differs from {want_err_file.name}:\n" + _diff(want_err, err))
    if rc != want_rc:
        problems.append(f"exit status {rc}, expected {want_rc}")
    assert not problems, "\n".join(problems)


def _expected(program: Path, suffix: str) -> Path:
    ours = program.with_suffix(".ours" + suffix)
    return ours if ours.exists() else program.with_suffix(suffix)


def test_every_deviation_is_explained() -> None:
    for ours in SCENARIOS.glob("*/*.ours.*"):
        notes = ours.parent / "DEVIATIONS"
        assert notes.exists() and ours.name.split(".")[0] in notes.read_text(), ours


if __name__ == "__main__":
    import sys

    for name in sys.argv[1:]:
        program = Path(name).resolve()
        out, err, rc = run_scenario(program)
        for suffix, text in ((".out", out), (".err", err), (".rc", f"{rc}\n")):
            if text != program.with_suffix(suffix).read_bytes().decode("latin-1"):
                program.with_suffix(".ours" + suffix).write_bytes(text.encode("latin-1"))
                print(f"wrote {program.with_suffix('.ours' + suffix)}")
