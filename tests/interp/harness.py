"""Run ``cnc rs274`` in-process on a corpus program the way the corpus was recorded.

Used by ``test_conformance.py`` and handy by hand::

    python -m tests.interp.harness tests/interp/corpus/001_g0_g1_basic.ngc [-v]
"""

from __future__ import annotations

import contextlib
import io
import os
import shlex
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from task.interp import cli

HERE = Path(__file__).resolve().parent
CORPUS = HERE / "corpus"
PROGRAMS = HERE / "programs"


@dataclass
class Result:
    out: str
    err: str
    rc: int
    var: str | None = None


def run_rs274_inprocess(args: list[str], cwd: Path) -> tuple[str, str, int]:
    """Run ``cli.main`` with stdout/stderr captured as bytes (decoded latin-1)."""
    out = io.TextIOWrapper(io.BytesIO(), encoding="latin-1")
    err = io.TextIOWrapper(io.BytesIO(), encoding="latin-1")
    old_cwd = os.getcwd()
    old_stdin = sys.stdin
    try:
        os.chdir(cwd)
        sys.stdin = io.StringIO("")
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = cli.main(args)
    finally:
        sys.stdin = old_stdin
        os.chdir(old_cwd)
    out.flush()
    err.flush()
    return (out.buffer.getvalue().decode("latin-1"), err.buffer.getvalue().decode("latin-1"), rc)


def corpus_args(program: Path) -> list[str]:
    args_file = program.with_suffix(".args")
    extra = shlex.split(args_file.read_text()) if args_file.exists() else []
    return ["-g", "-t", "tool.tbl", "-v", "params.var", *extra, program.name]


def run_program(program: Path, folder: Path, args: list[str]) -> Result:
    """Copy ``folder`` (inputs only) to a scratch folder and run there, as make_expected.sh."""
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(scratch) / "w"
        work.mkdir()
        # the inputs a run can see: the program, the tables and the folders of support files
        for name in (program.name, "tool.tbl", "params.var"):
            if (folder / name).exists():
                shutil.copy(folder / name, work / name)
        for sub in folder.iterdir():
            if sub.is_dir() and sub.name != "__pycache__":
                shutil.copytree(sub, work / sub.name)
        out, err, rc = run_rs274_inprocess(args, work)
        var_path = work / "params.var"
        var = var_path.read_text() if var_path.exists() else None
    return Result(out, err, rc, var)


def expected(program: Path) -> Result:
    var = program.with_suffix(".var")
    return Result(
        program.with_suffix(".out").read_bytes().decode("latin-1"),
        program.with_suffix(".err").read_bytes().decode("latin-1"),
        int(program.with_suffix(".rc").read_text().strip()),
        var.read_text() if var.exists() else None,
    )


def compare(program: Path, folder: Path) -> list[str]:
    """Differences between our run and the recorded one (empty when they match)."""
    want = expected(program)
    got = run_program(program, folder, corpus_args(program))
    problems = []
    if got.out != want.out:
        problems.append("stdout differs:\n" + _diff(want.out, got.out))
    if got.err != want.err:
        problems.append("stderr differs:\n" + _diff(want.err, got.err))
    if got.rc != want.rc:
        problems.append(f"exit status {got.rc}, expected {want.rc}")
    if want.var is not None and got.var != want.var:
        problems.append("var file differs:\n" + _diff(want.var, got.var or ""))
    return problems


def _diff(want: str, got: str) -> str:
    import difflib

    lines = difflib.unified_diff(
        want.splitlines(), got.splitlines(), "rs274", "ours", lineterm="", n=1
    )
    return "\n".join(list(lines)[:40])


def main(argv: list[str]) -> int:
    verbose = "-v" in argv
    failed = 0
    names = [a for a in argv if not a.startswith("-")]
    for name in names:
        program = Path(name).resolve()
        problems = compare(program, program.parent)
        if problems:
            failed += 1
            print(f"FAIL {program.name}")
            if verbose:
                print("\n".join(problems))
        elif verbose:
            print(f"ok   {program.name}")
    print(f"{len(names) - failed}/{len(names)} match")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
