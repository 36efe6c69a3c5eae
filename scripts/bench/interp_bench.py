#!/usr/bin/env python3
"""Interpreter throughput, ours against LinuxCNC's rs274 (issue 4).

Prints one JSON object::

    {"short_moves": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...},
     "subroutines": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...},
     "oword_subs": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...}}

``short_moves`` is a 50,000-line program of short G1 moves (``bigprog_50k.ngc`` from
``../shared/reference/programs`` when it is there, otherwise one generated like it);
``subroutines`` is a loop that calls an O-word subroutine 5,000 times; ``oword_subs`` is the
shared subroutine-heavy program ``oword_subs.ngc`` from the same folder (left out when it is
not there): small, so its figure is mostly process start-up. Each figure is
interpreted lines (every line read, loops counted as often as they run) divided by the median
wall time of 3 runs of the whole command, process start included, as
``interp_throughput.sh`` measures rs274 (our runs and rs274's take turns).
``rs274_lines_per_s`` appears only where ``/usr/bin/rs274`` exists.
Usage: ``interp_bench.py [--runs N]``.
"""

from __future__ import annotations

import argparse
import compileall
import io
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

# ../shared/reference/programs of the checkout (a helper's worktree is one folder deeper)
REFERENCE_PROGRAMS = next(
    (
        folder / "shared" / "reference" / "programs"
        for folder in (REPO.parent, REPO.parent.parent)
        if (folder / "shared" / "reference" / "programs").is_dir()
    ),
    REPO.parent / "shared" / "reference" / "programs",
)
REFERENCE = REFERENCE_PROGRAMS / "bigprog_50k.ngc"
OWORD_SUBS = REFERENCE_PROGRAMS / "oword_subs.ngc"
RS274 = "/usr/bin/rs274"
TOOL_TABLE = "T1 P1 Z0.511 D3 ;3mm end mill\n"


def short_moves_program(path: Path) -> None:
    if REFERENCE.exists():
        shutil.copy(REFERENCE, path)
        return
    lines = [
        "%",
        "(50,000 short moves)",
        "G21 G17 G40 G49 G80 G90 G94 G54",
        "G64",
        "G0 Z10",
        "G0 X0 Y0",
    ]
    n = 50000 - len(lines) - 4
    for k in range(n):
        t = 2 * math.pi * k / n
        lines.append(f"G1 X{40 * math.sin(3 * t):.4f} Y{40 * math.sin(2 * t):.4f}")
    lines += ["G0 Z10", "G0 X0 Y0", "M2", "%"]
    path.write_text("\n".join(lines) + "\n")


def subroutine_program(path: Path) -> None:
    path.write_text("""(subroutine-heavy loop: 5,000 calls)
G21 G17 G90 G64 F1000
o<step> sub
  #<r> = [#2 * 0.5 + 10]
  G1 X[#<r> * COS[#1]] Y[#<r> * SIN[#1]]
  o<step> return [#<r>]
o<step> endsub
#1 = 0
o100 while [#1 LT 5000]
  o<step> call [#1 * 0.72] [#1 MOD 7]
  #1 = [#1 + 1]
o100 endwhile
G0 X0 Y0
M2
""")


def count_lines(program: Path, folder: Path) -> int:
    """Lines the interpreter reads (loops and calls re-read theirs), counted in-process."""
    from task.interp.canon import PrintingCanon
    from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT
    from task.interp.interp import Interpreter

    canon = PrintingCanon(io.StringIO().write)
    interp = Interpreter(canon, parameter_file=str(folder / "count.var"))
    interp.init()
    interp.open(str(program))
    count = 0
    while True:
        status = interp.read()
        count += 1
        if status == INTERP_ENDFILE or interp.execute() == INTERP_EXIT:
            break
    return count


def median_times(commands: list[list[str]], cwd: Path, runs: int) -> list[float]:
    """The median wall time of each command. Their runs take turns, so that a change in
    the machine's load (other processes) weighs on each command alike."""
    times: list[list[float]] = [[] for _ in commands]
    for _ in range(runs):
        for command, measured in zip(commands, times, strict=True):
            start = time.perf_counter()
            subprocess.run(
                command,
                cwd=cwd,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                stdin=subprocess.DEVNULL,
                check=False,
            )
            measured.append(time.perf_counter() - start)
    return [statistics.median(measured) for measured in times]


def measure(program: Path, folder: Path, runs: int) -> dict:
    lines = count_lines(program, folder)
    args = ["-g", "-t", "tool.tbl", "-v", "params.var", program.name]
    commands = [[sys.executable, "-m", "cnc", "rs274", *args]]
    if os.path.exists(RS274):
        commands.append([RS274, *args])
    seconds = median_times(commands, folder, runs)
    result = {"lines": lines, "seconds": round(seconds[0], 4)}
    result["lines_per_s"] = round(lines / seconds[0])
    if len(seconds) > 1:
        result["rs274_seconds"] = round(seconds[1], 4)
        result["rs274_lines_per_s"] = round(lines / seconds[1])
        result["ratio"] = round(result["lines_per_s"] / result["rs274_lines_per_s"], 3)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    options = parser.parse_args(argv)
    # An installed package has byte code; with PYTHONDONTWRITEBYTECODE a checkout has none,
    # so compile once instead of paying for it on every run.
    for package in ("cnc", "task", "iocontrol"):
        compileall.compile_dir(str(REPO / package), quiet=1)
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        (folder / "tool.tbl").write_text(TOOL_TABLE)
        (folder / "params.var").write_text("")
        env_path = os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])
        os.environ["PYTHONPATH"] = env_path
        short = folder / "short_moves.ngc"
        short_moves_program(short)
        subs = folder / "subroutines.ngc"
        subroutine_program(subs)
        report = {
            "short_moves": measure(short, folder, options.runs),
            "subroutines": measure(subs, folder, options.runs),
        }
        if OWORD_SUBS.exists():
            shutil.copy(OWORD_SUBS, folder / OWORD_SUBS.name)
            report["oword_subs"] = measure(folder / OWORD_SUBS.name, folder, options.runs)
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
