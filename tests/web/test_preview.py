"""cnc ui web: the toolpath preview runs a program through an interpreter of its own."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ui.web.preview import FEED, RAPID, decode, preview


def run(tmp_path: Path, text: str, **options) -> dict:
    """The preview's result, with "points" decoded (the origin, where moves start, left
    out)."""
    program = tmp_path / "part.ngc"
    program.write_text(text)
    data = bytearray()
    found = preview(str(program), data.extend, **options)
    points = decode(bytes(data))
    assert points[0] == [0.0, 0.0, 0.0, RAPID, 0] and found["points"] == len(points)
    return found | {"points": points[1:]}


def test_moves_are_rapids_and_feeds_with_their_lines(tmp_path: Path) -> None:
    found = run(tmp_path, "G21 G90\nG0 X1 Y2 Z3\nG1 X4 F100\nM2\n")
    assert found["error"] is None and found["is_truncated"] is False
    assert found["points"] == [[1.0, 2.0, 3.0, RAPID, 2], [4.0, 2.0, 3.0, FEED, 3]]


def test_an_arc_is_drawn_as_chords_on_its_circle(tmp_path: Path) -> None:
    found = run(tmp_path, "G21 G90 G17\nG0 X0 Y0\nG2 X10 Y0 I5 J0 F100\nM2\n")
    arc = [point for point in found["points"] if point[4] == 3]
    assert len(arc) > 10 and arc[-1][:3] == [10.0, 0.0, 0.0]
    for x, y, *_ in arc:
        assert (x - 5) ** 2 + y**2 == pytest.approx(25, abs=1e-3)
        assert y >= -1e-9  # clockwise from the left end: over the top


def test_inch_programs_are_drawn_in_machine_units(tmp_path: Path) -> None:
    found = run(tmp_path, "G20 G90\nG0 X1\nM2\n")
    assert found["points"][0][0] == pytest.approx(25.4)


def test_an_error_stops_the_preview_with_its_line(tmp_path: Path) -> None:
    found = run(tmp_path, "G0 X1\nG999\nG0 X2\nM2\n")
    assert found["error"] == {"line": 2, "message": "G-code out of range"}
    assert found["errors"] == [found["error"]]
    assert [point[0] for point in found["points"]] == [1.0]


def test_a_check_goes_on_after_errors_and_reports_each(tmp_path: Path) -> None:
    text = "G21\nG0 X1\nG999\nG1 X2 F100\nG1 Q\nG0 X3\n"  # and no M2
    found = run(tmp_path, text, is_checking_all=True)
    assert found["errors"] == [
        {"line": 3, "message": "G-code out of range"},
        {"line": 5, "message": "No characters found in reading real value"},
        {"line": 6, "message": "File ended with no percent sign or program end"},
    ]
    assert [point[0] for point in found["points"]] == [1.0, 2.0, 3.0]


def test_large_programs_reach_the_sink_in_chunks_and_small_arcs_take_few_chords(
    tmp_path: Path,
) -> None:
    lines = ["G21 G90 F1000"] + [f"G1 X{n % 7} Y{n % 5}" for n in range(40_000)] + ["M2"]
    program = tmp_path / "big.ngc"
    program.write_text("\n".join(lines) + "\n")
    chunks: list[bytes] = []
    found = preview(str(program), chunks.append)
    assert found["points"] == 40_001 and found["end_line"] == 40_002
    assert len(chunks) == 3 and all(len(chunk) % 16 == 0 for chunk in chunks)
    small = run(tmp_path, "G21 G90\nG0 X0 Y0\nG2 X0.2 Y0 I0.1 J0 F100\nM2\n")
    assert 2 <= len(small["points"]) - 1 <= 10  # a 0.1 mm radius: a few chords


def test_the_preview_interpreter_runs_with_task_zero(tmp_path: Path) -> None:
    found = run(tmp_path, "o100 if [#<_task> EQ 0]\nG0 X7\no100 endif\nM2\n")
    assert found["error"] is None and found["points"][0][0] == 7.0


def test_the_machines_parameter_file_is_read_but_never_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # nor is a default rs274ngc.var written here
    parameters = tmp_path / "machine.var"
    parameters.write_text("5221\t10.000000\n")  # G54 X offset
    found = run(tmp_path, "G54 G0 X1\nM2\n", parameter_file=str(parameters))
    assert found["error"] is None and found["points"][0][0] == 1.0
    assert parameters.read_text() == "5221\t10.000000\n"
    assert not (tmp_path / "machine.var.bak").exists()
    assert not (tmp_path / "rs274ngc.var").exists()
