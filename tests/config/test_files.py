"""The machine's other files: the ``.var`` parameter file (task/varfile.py, the interpreter's
read and save) and the tool table's numbers: a bad file is a ``file:line`` error, nothing the
user had is overwritten, nan is never written. (Atomic writes: tests/test_atomicfile.py.)"""

from __future__ import annotations

import io
import math
from pathlib import Path

import pytest

from iocontrol.tooltable import ToolEntry, ToolTable, ToolTableError
from task.interp.canon import PrintingCanon
from task.interp.interp import Interpreter
from task.varfile import VarFileError, format_var_file, parse_var_text, read_var_file

GOOD_VAR = "5161\t1.000000\n5220\t1.000000\n5221\t2.500000\n"


# --------------------------------------------------------------------------- .var files
def test_a_var_file_reads_by_number(tmp_path: Path) -> None:
    path = tmp_path / "p.var"
    path.write_text("# saved by hand\n\n" + GOOD_VAR)
    assert read_var_file(path) == {5161: 1.0, 5220: 1.0, 5221: 2.5}


@pytest.mark.parametrize(
    ("text", "line", "cause"),
    [
        ("5220\t1\n5161\t1\n", 2, "parameter 5161 after 5220: the numbers must be in ascending"),
        ("5220\t1\n5220\t2\n", 2, "parameter 5220 after 5220"),
        ("5161\t1\n5602\t1\n", 2, "parameter number 5602 out of range 1 to 5601"),
        ("0\t1\n", 1, "parameter number 0 out of range"),
        ("5161\t1\n5220 one\n", 2, "not '<parameter number> <value>': 5220 one"),
        ("5161\t1\n5220\t1.0 extra\n", 2, "not '<parameter number> <value>'"),
        ("5161\tnan\n", 1, "not '<parameter number> <value>': 5161 nan"),
        ("5161\t1e999\n", 1, "parameter 5161 = 1e999 is too large"),
        ("5161\t1\nGARBAGE\n", 2, "not '<parameter number> <value>': GARBAGE"),
    ],
)
def test_a_bad_var_file_names_file_and_line(tmp_path: Path, text: str, line: int, cause: str):
    path = tmp_path / "p.var"
    path.write_text(text)
    with pytest.raises(VarFileError) as caught:
        read_var_file(path)
    assert (caught.value.file, caught.value.line) == (str(path), line)
    assert caught.value.cause.startswith(cause)
    assert str(caught.value) == f"{path}:{line}: {caught.value.cause}"


def test_a_binary_var_file_is_refused_at_its_line(tmp_path: Path) -> None:
    path = tmp_path / "p.var"
    path.write_bytes(GOOD_VAR.encode() + b"\x00\x01\xff\xfe binary\n")
    with pytest.raises(VarFileError, match=r"p\.var:4: not a text file"):
        read_var_file(path)
    path.write_bytes(GOOD_VAR.encode() + b"5222\t1\x00\n")
    with pytest.raises(VarFileError, match=r"p\.var:4: binary data"):
        read_var_file(path)


def test_the_lenient_reader_is_linuxcncs() -> None:
    """What ``rs274`` does with the same files: unmatched lines skipped, LinuxCNC's texts."""
    text = "junk\n5161 nan\n5220\t1.5 extra\n5221.5\n"
    found = parse_var_text(text, strict=False)
    assert math.isnan(found[5161]) and found[5220] == 1.5 and found[5221] == 0.5
    with pytest.raises(VarFileError, match="Parameter file out of order"):
        parse_var_text("5220\t1\n5161\t1\n", strict=False)
    with pytest.raises(VarFileError, match="Parameter number out of range"):
        parse_var_text("5602\t1\n", strict=False)


def test_nan_is_never_written() -> None:
    assert format_var_file({5220: 1.0, 5161: -2.0}) == "5161\t-2.000000\n5220\t1.000000\n"
    with pytest.raises(VarFileError, match="parameter 5221 = nan is not finite: not saved"):
        format_var_file({5220: 1.0, 5221: math.nan})


def make_interp(tmp_path: Path) -> Interpreter:
    interp = Interpreter(PrintingCanon(io.StringIO().write, ToolTable()), parameter_file="p.var")
    interp.parameter_file = str(tmp_path / "p.var")
    return interp


def test_the_interpreter_never_overwrites_a_var_file_it_cannot_read(tmp_path: Path) -> None:
    path = tmp_path / "p.var"
    path.write_text(GOOD_VAR)
    interp = make_interp(tmp_path)
    interp.init()
    bad = "5220\t1\n5161\t7\n"
    path.write_text(bad)  # the user edits it while the machine runs
    interp.exit()
    assert str(interp.save_error) == f"{path}:2: Parameter file out of order"
    assert path.read_text() == bad


def test_the_interpreter_never_writes_nan_and_keeps_the_file(tmp_path: Path) -> None:
    path = tmp_path / "p.var"
    path.write_text(GOOD_VAR)
    interp = make_interp(tmp_path)
    interp.init()
    saved = path.read_text()
    interp.parameters[5221] = math.inf
    interp.exit()
    assert str(interp.save_error) == f"{path}: parameter 5221 = inf is not finite: not saved"
    assert path.read_text() == saved


def test_the_interpreter_says_why_a_save_failed(tmp_path: Path) -> None:
    interp = make_interp(tmp_path)
    interp.init()
    assert interp.save_error is None
    interp.parameter_file = str(tmp_path / "gone" / "p.var")
    interp.exit()
    assert isinstance(interp.save_error, FileNotFoundError)


# --------------------------------------------------------------------------- tool tables
@pytest.mark.parametrize("word", ["Z+nan", "Xinf", "D-inf", "I+nan"])
def test_a_tool_line_with_a_number_that_is_not_finite_is_refused(tmp_path: Path, word: str):
    path = tmp_path / "tool.tbl"
    path.write_text(f"T1 P1 Z1\nT2 P2 {word}\n")
    with pytest.raises(ToolTableError) as caught:
        ToolTable().load(path)
    assert (caught.value.file, caught.value.line) == (str(path), 2)


def test_a_table_never_holds_a_number_that_is_not_finite() -> None:
    table = ToolTable()
    with pytest.raises(ValueError, match="Z = nan is not a finite number"):
        table.put(1, ToolEntry(1, 1, [0.0, 0.0, math.nan, 0, 0, 0, 0, 0, 0]))
    assert table.entries == {}
