#!/usr/bin/env python3
"""Interpreter throughput, ours against LinuxCNC's rs274 (issue 4).

Prints one JSON object::

    {"short_moves": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...},
     "subroutines": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...},
     "oword_subs": {"lines_per_s": ..., "rs274_lines_per_s": ..., ...}}

``short_moves`` is a 50,000-line program of short G1 moves (``bigprog_50k.ngc`` from
``../shared/reference/programs`` when it is there, otherwise one generated like it);
``subroutines`` is a loop that calls an O-word subroutine 5,000 times; ``remaps`` is 6,000
lines each with a remapped code (``-i remap.ini``): M400 runs an NGC procedure with a prolog
and an epilog in Python, M401 a Python handler, G88.6 a Python handler with argspec words;
``oword_subs`` is the
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
        "G64 F1000",
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


REMAP_INI = """[RS274NGC]
SUBROUTINE_PATH = .
REMAP=M400 modalgroup=10 argspec=P prolog=prolog ngc=m400 epilog=epilog
REMAP=M401 modalgroup=10 argspec=Pq python=m401
REMAP=G88.6 modalgroup=1 argspec=XYp python=g886

[PYTHON]
PATH_PREPEND = .
TOPLEVEL = toplevel.py
"""
REMAP_FILES = {
    "toplevel.py": "import remap\n",
    "remap.py": """from interpreter import INTERP_OK


def prolog(self, **words):
    self.params["scale"] = 0.5
    return INTERP_OK


def epilog(self, **words):
    self.params["_last"] = self.params["result"]
    return INTERP_OK


def m401(self, **words):
    self.params["_sum"] = self.params["_sum"] + words["p"]
    return INTERP_OK


def g886(self, **words):
    self.execute("G1 X%.4f Y%.4f" % (words["x"], words["y"]))
    return INTERP_OK
""",
    "m400.ngc": """o<m400> sub
#<result> = [#<p> * #<scale>]
G1 X[#<result> / 1000] Y0
o<m400> endsub
M2
""",
}


def remap_program(path: Path) -> None:
    """6,000 lines, each with a remapped code: NGC and Python handlers in turn."""
    for name, text in REMAP_FILES.items():
        (path.parent / name).write_text(text)
    (path.parent / "remap.ini").write_text(REMAP_INI)
    lines = ["G21 G90 G64 F1000", "#<_sum> = 0", "#<_last> = 0"]
    for k in range(2000):
        lines.append(f"M400 P{k}")
        lines.append(f"M401 P{k} Q1")
        lines.append(f"G88.6 X{k % 50 * 0.1:.1f} Y{k % 7 * 0.2:.1f}")
    lines += ["G0 X0 Y0", "M2"]
    path.write_text("\n".join(lines) + "\n")


def count_lines(program: Path, folder: Path, ini: Path | None = None) -> int:
    """Lines the interpreter reads (loops and calls re-read theirs), counted in-process."""
    from cnc.ini import IniFile
    from task.interp.canon import PrintingCanon
    from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT
    from task.interp.interp import Interpreter

    canon = PrintingCanon(io.StringIO().write)
    interp = Interpreter(
        canon,
        ini=None if ini is None else IniFile.load(ini),
        parameter_file=str(folder / "count.var"),
    )
    cwd = os.getcwd()
    os.chdir(folder)  # (the INI's folders are relative)
    try:
        interp.init()
        interp.open(str(program))
        count = 0
        while True:
            status = interp.read()
            count += 1
            if status == INTERP_ENDFILE or interp.execute() == INTERP_EXIT:
                break
        interp.exit()
    finally:
        os.chdir(cwd)
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


def measure(program: Path, folder: Path, runs: int, ini: Path | None = None) -> dict:
    lines = count_lines(program, folder, ini)
    args = ["-g", "-t", "tool.tbl", "-v", "params.var", program.name]
    if ini is not None:
        args = ["-i", ini.name, *args]
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
        remaps = folder / "remaps.ngc"
        remap_program(remaps)
        report = {
            "short_moves": measure(short, folder, options.runs),
            "subroutines": measure(subs, folder, options.runs),
            "remaps": measure(remaps, folder, options.runs, folder / "remap.ini"),
        }
        if OWORD_SUBS.exists():
            shutil.copy(OWORD_SUBS, folder / OWORD_SUBS.name)
            report["oword_subs"] = measure(folder / OWORD_SUBS.name, folder, options.runs)
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
