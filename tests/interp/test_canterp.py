"""canterp, the interpreter of printed canonical calls (``cnc rs274 -p canterp.so``).

The expected outputs in ``canterp/`` were made by LinuxCNC 2.9's ``rs274`` with its
``canterp.so`` plug-in (``canterp/make_expected.sh``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from task.interp.canon import CLOCKWISE
from task.interp.canterp import Canterp, parse, scan
from task.interp.errors import InterpError
from tests.interp.harness import run_rs274_inprocess

HERE = Path(__file__).resolve().parent / "canterp"


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["-g", "replay.can"], "replay"),
        (["-g", "calls.can"], "calls"),
        (["-g", "errors.can"], "errors-stop"),
        (["-n", "0", "-g", "errors.can"], "errors-continue"),
    ],
)
def test_replay_matches_linuxcnc(args: list[str], expected: str) -> None:
    out, err, rc = run_rs274_inprocess(["-p", "canterp.so", "-t", "tool.tbl", *args], HERE)
    assert out == (HERE / f"{expected}.out").read_text()
    assert err == (HERE / f"{expected}.err").read_text()
    assert rc == int((HERE / f"{expected}.rc").read_text())


def test_plugin_is_found_by_its_file_name_whatever_the_folder() -> None:
    for name in ("./canterp.so", "/usr/lib/linuxcnc/canterp.so"):
        out, _, rc = run_rs274_inprocess(["-p", name, "-t", "tool.tbl", "-g", "replay.can"], HERE)
        assert (rc, out) == (0, (HERE / "replay.out").read_text())


def test_unknown_plugin_is_reported_and_the_builtin_interpreter_runs(tmp_path: Path) -> None:
    (tmp_path / "tool.tbl").write_text("T1 P1\n")
    (tmp_path / "p.ngc").write_text("G0 X1\nM2\n")
    out, err, rc = run_rs274_inprocess(
        ["-p", "other.so", "-g", "-t", "tool.tbl", "p.ngc"], tmp_path
    )
    assert err.startswith("emcTaskInit: could not open interpreter '/usr/lib/linuxcnc/other.so'")
    assert rc == 0
    assert "STRAIGHT_TRAVERSE(1.0000" in out


def test_parse_skips_two_columns_and_keeps_inner_quotes() -> None:
    assert parse('  7 N0010 COMMENT("4"x4" stock")\n') == (
        "COMMENT",
        '4"x4" stock',
        'COMMENT("4"x4" stock")',
    )
    assert parse("1 N..... FEED(1, 2,3)") == ("FEED", "1  2 3", "FEED(1, 2,3)")
    assert parse("1 N..... PROGRAM_END\n") == ("PROGRAM_END", "", "PROGRAM_END")
    assert parse("  only-two columns\n")[0] == ""
    assert parse("\n")[0] == ""
    for bad in ("1 N X 2", "1 N X(1, 2\n"):
        with pytest.raises(InterpError, match="ERROR 5"):
            parse(bad)


def test_scan_converts_as_sscanf() -> None:
    assert scan(" 1.5 -2 3e2 x", "fff") == [1.5, -2.0, 300.0]
    assert scan("0x10 010 9", "iii") == [16, 8, 9]
    assert scan("1 2.5 CANON_CLOCKWISE", "dfs") == [1, 2.5, "CANON_CLOCKWISE"]
    assert scan("1 two 3", "fff") == [1.0]


class RecordingCanon:
    def __init__(self) -> None:
        self.calls: list[tuple] = []

    def __getattr__(self, name: str):
        return lambda *args: self.calls.append((name, *args))


def test_calls_reach_the_canon_with_converted_arguments() -> None:
    canon = RecordingCanon()
    interp = Canterp(canon)
    for line in (
        "1 N ORIENT_SPINDLE(0, 1.5, CANON_CLOCKWISE)",
        "2 N STRAIGHT_PROBE(1, 2, 3, 4, 5, 6)",
        "3 N ARC_FEED(1, 2, 3, 4, -1, 5, 6, 7, 8, 9, 10, 11)",
    ):
        interp.read(line)
        interp.execute()
    assert canon.calls == [
        # (LinuxCNC's canterp.so prints the orientation as 0.0000 here: a mismatch of its
        # build, not of the call it reads)
        ("ORIENT_SPINDLE", 0, 1.5, CLOCKWISE),
        ("STRAIGHT_PROBE", -1, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0, 0.0, 0.0, 0),
        ("ARC_FEED", -1, 1.0, 2.0, 3.0, 4.0, -1, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0),
    ]
    for wrong in ("1 N STRAIGHT_FEED(1, 2, 3)", "1 N ORIENT_SPINDLE(0, 1, SIDEWAYS)"):
        interp.read(wrong)
        with pytest.raises(InterpError):
            interp.execute()
