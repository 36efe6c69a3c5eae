"""Fuzzing the reader and the interpreter: any input gives output or a clean InterpError.

Programs are built from G-code-like fragments and random characters; every line is read and
executed as rs274 would (stop at the first error). A Python exception other than
``InterpError`` is a bug. Loops in generated O-words are cut off after a bounded number of
lines.
"""

from __future__ import annotations

import io

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from iocontrol.tooltable import ToolTable
from task.interp.canon import PrintingCanon
from task.interp.errors import INTERP_ENDFILE, INTERP_EXIT, InterpError
from task.interp.interp import Interpreter

WORDS = [
    "G0",
    "G1",
    "G2",
    "G3",
    "G4",
    "G10",
    "G17",
    "G18",
    "G19",
    "G20",
    "G21",
    "G28",
    "G30",
    "G33",
    "G38.2",
    "G40",
    "G41",
    "G42",
    "G41.1",
    "G43",
    "G43.1",
    "G49",
    "G52",
    "G53",
    "G54",
    "G59.3",
    "G61",
    "G64",
    "G73",
    "G76",
    "G80",
    "G81",
    "G83",
    "G84",
    "G87",
    "G90",
    "G91",
    "G92",
    "G92.1",
    "G93",
    "G94",
    "G95",
    "G96",
    "G98",
    "G99",
    "G5",
    "G5.1",
    "G5.2",
    "G5.3",
    "M0",
    "M2",
    "M3",
    "M5",
    "M6",
    "M7",
    "M9",
    "M19",
    "M48",
    "M61",
    "M62",
    "M66",
    "M70",
    "M72",
    "M73",
    "M98",
    "M99",
    "M100",
    "T1",
    "T2",
    "S100",
    "F100",
    "F0",
    "X1",
    "Y-2",
    "Z.5",
    "A3",
    "I1",
    "J-1",
    "K1",
    "R2",
    "P1",
    "Q0.5",
    "L2",
    "H1",
    "D1",
    "E1",
    "N10",
    "$0",
    "#1=",
    "#<a>=",
    "#<_g>=",
    "#1",
    "#<a>",
    "#5220",
    "[",
    "]",
    "+",
    "-",
    "*",
    "/",
    "**",
    "MOD",
    "EQ",
    "LT",
    "AND",
    "OR",
    "SIN[",
    "ATAN[1]/[",
    "EXISTS[",
    "(",
    ")",
    ";",
    "(MSG,",
    "(DEBUG,",
    "(PRINT,",
    "(ABORT,",
    "%",
    "/",
    "o100",
    "o<s>",
    " sub",
    " endsub",
    " call",
    " if",
    " else",
    " endif",
    " while",
    " endwhile",
    " do",
    " repeat",
    " endrepeat",
    " break",
    " continue",
    " return",
    "@1",
    "^45",
    "1.5",
    "-0",
    "...",
    "\t",
    " ",
]

fragment = st.one_of(st.sampled_from(WORDS), st.text(min_size=1, max_size=3))
line = st.lists(fragment, max_size=8).map("".join)
program = st.lists(line, min_size=1, max_size=12)


def run_lines(lines: list[str], tmp_path, max_reads: int = 400) -> str:
    path = tmp_path / "fuzz.ngc"
    path.write_text("\n".join(lines) + "\n", encoding="latin-1", errors="replace")
    out = io.StringIO()
    canon = PrintingCanon(out.write, ToolTable())
    interp = Interpreter(canon, parameter_file=str(tmp_path / "fuzz.var"))
    try:
        interp.init()
        interp.open(str(path))
        for _ in range(max_reads):
            if interp.read() == INTERP_ENDFILE:
                break
            if interp.execute() == INTERP_EXIT:
                break
    except InterpError as error:
        assert str(error)  # a message, as rs274 would print it
    return out.getvalue()


@settings(
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(program)
def test_any_program_gives_output_or_interp_error(tmp_path, lines) -> None:
    run_lines(lines, tmp_path)


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.text(max_size=300))
def test_any_single_line_gives_output_or_interp_error(tmp_path, text) -> None:
    run_lines(["G21", text, "M2"], tmp_path)


def test_runaway_loop_is_bounded(tmp_path) -> None:
    output = run_lines(["o1 while [1]", "G0 X1", "o1 endwhile", "M2"], tmp_path, max_reads=50)
    assert "STRAIGHT_TRAVERSE" in output
