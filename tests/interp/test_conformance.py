"""Conformance with LinuxCNC 2.9's rs274 (issue 4): same canonical calls, numbers and errors.

Every ``corpus/*.ngc`` program and every benchmark program in ``programs/`` is run through
``cnc rs274`` exactly as its expected output was recorded (see ``corpus/README.md`` and
``programs/make_expected.sh``): stdout, stderr, exit status (and the rewritten var file for
``*_varfile_*`` programs) must be identical. Programs we do not match yet are listed in
``KNOWN_DEVIATIONS.txt`` with the reason; they are marked ``xfail(strict=True)``, so fixing
one fails the run until its line is removed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .harness import CORPUS, PROGRAMS, compare

KNOWN = Path(__file__).with_name("KNOWN_DEVIATIONS.txt")


def _known_deviations() -> dict[str, str]:
    known = {}
    for line in KNOWN.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        name, _, reason = line.partition(" ")
        known[name] = reason.strip()
    return known


def _programs() -> list:
    known = _known_deviations()
    params = []
    for folder in (CORPUS, PROGRAMS):
        for program in sorted(folder.glob("*.ngc")):
            if not program.with_suffix(".out").exists():
                continue  # a subroutine file or a program without a recording
            marks = []
            if program.name in known:
                marks.append(pytest.mark.xfail(reason=known[program.name], strict=True))
            params.append(pytest.param(program, id=f"{folder.name}/{program.stem}", marks=marks))
    return params


@pytest.mark.parametrize("program", _programs())
def test_program_matches_rs274(program: Path) -> None:
    problems = compare(program, program.parent)
    assert not problems, "\n".join(problems)


def test_known_deviations_name_real_programs() -> None:
    names = {p.name for folder in (CORPUS, PROGRAMS) for p in folder.glob("*.ngc")}
    unknown = set(_known_deviations()) - names
    assert not unknown, f"KNOWN_DEVIATIONS.txt names programs that do not exist: {unknown}"


@pytest.fixture
def every_line_planned(monkeypatch):
    """Plan every line as its file is loaded, so that plans take even lines read once."""
    from task.interp.compiled import plan_line
    from task.interp.errors import InterpError
    from task.interp.interp import Interpreter
    from task.interp.reader import LINELEN, close_and_downcase

    load = Interpreter._load_file

    def load_and_plan(self, filename: str):
        lines = load(self, filename)
        for raw in lines or ():
            if "\x00" in raw or len(raw) >= LINELEN - 1:
                continue
            text = raw.rstrip(" \t\n\r\f\v")
            try:
                line = close_and_downcase(text)
            except InterpError:
                continue
            plan = plan_line(self._compiler, text, line)
            if plan is not None:
                self._plans[raw] = plan
        return lines

    monkeypatch.setattr(Interpreter, "_load_file", load_and_plan)


@pytest.mark.parametrize("program", _programs())
def test_program_matches_rs274_with_every_line_planned(program: Path, every_line_planned) -> None:
    """Line plans (compiled.py) read a line exactly as the general reader does."""
    problems = compare(program, program.parent)
    assert not problems, "\n".join(problems)
