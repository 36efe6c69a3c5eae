"""Tool table files (TOOL-006..012): parsing, index model, file:line errors, atomic save."""

from __future__ import annotations

import pytest

from iocontrol.tooltable import CANON_POCKETS_MAX, ToolEntry, ToolTable, ToolTableError, parse_line

SAMPLE = """T1 P1 Z0.511 D3 ;3mm end mill
T2 P4 Z0.1 D1.5 X-0.2 ;1.5mm  end mill
t3 p3 z1.273 d5 i10 j20 q4
; a comment line

T99 P12 W-1 A90 ;last
"""


def test_parse_line_reads_every_word() -> None:
    entry = parse_line("T3 P7 X1 Y2 Z3 A4 B5 C6 U7 V8 W9 D0.5 I10 J20 Q2 ;note", exact=True)
    assert entry is not None
    assert (entry.toolno, entry.pocketno) == (3, 7)
    assert entry.offset == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    assert (entry.diameter, entry.frontangle, entry.backangle, entry.orientation) == (
        0.5,
        10.0,
        20.0,
        2,
    )
    assert entry.comment == "note"


def test_blank_and_comment_lines_are_skipped() -> None:
    assert parse_line("; only a comment", exact=True) is None
    assert parse_line("\n", exact=True) is None


def test_nonrandom_tools_take_indices_in_load_order(tmp_path) -> None:
    path = tmp_path / "tool.tbl"
    path.write_text(SAMPLE)
    table = ToolTable(random_toolchanger=False)
    assert table.load(path) == []
    assert [table.get(i).toolno for i in (1, 2, 3, 4)] == [1, 2, 3, 99]
    assert table.get(4).pocketno == 12  # the file's pocket is kept for saving
    assert table.find_index_for_tool(99) == 4
    assert table.find_index_for_tool(0) == 0  # nonrandom: T0 is "no tool"
    assert table.find_index_for_tool(5) == -1


def test_random_changer_indexes_by_pocket(tmp_path) -> None:
    path = tmp_path / "tool.tbl"
    path.write_text("T0 P0 ;empty\nT7 P3 Z1\nT8 P1000 Z2\n")
    table = ToolTable(random_toolchanger=True)
    table.load(path)
    assert table.get(3).toolno == 7
    assert table.get(1000).toolno == 8
    assert table.find_index_for_tool(0) == 0
    assert CANON_POCKETS_MAX == 1001  # pockets 0..1000 all fit (TOOL-009)


@pytest.mark.parametrize(
    ("text", "cause"),
    [
        ("T1 P1 Z0.5\nT2 P2 Z1.5x\n", "2: bad number in word 'Z1.5x'"),
        ("T1 P1 Z1,5\n", "1: bad number in word 'Z1,5'"),
        ("P3 Z1\n", "1: T word missing"),
    ],
)
def test_errors_name_file_and_line(tmp_path, text: str, cause: str) -> None:
    path = tmp_path / "bad.tbl"
    path.write_text(text)
    with pytest.raises(ToolTableError) as info:
        ToolTable().load(path)
    assert str(info.value) == f"{path}:{cause}"


def test_pocket_0_in_a_non_random_table_is_kept_as_written(tmp_path) -> None:
    path = tmp_path / "tool.tbl"
    path.write_text("T2 P0 D1.5\nT1 P1\n")  # LinuxCNC's tests/io-startup/nonrandom/tool-in-P0
    table = ToolTable()
    table.load(path)
    assert (table.get(1).toolno, table.get(1).pocketno) == (2, 0)
    assert table.get(2).toolno == 1


def test_lenient_load_skips_bad_lines_like_linuxcnc(tmp_path) -> None:
    path = tmp_path / "tool.tbl"
    path.write_text("T1 P1 Z0.5\nT2 P2 K3\nT3 P3\n")
    table = ToolTable()
    assert table.load(path, strict=False) == ["T2 P2 K3\n"]
    assert [table.get(i).toolno for i in (1, 2, 3)] == [1, 3, -1]


def test_save_round_trips_and_replaces_atomically(tmp_path) -> None:
    path = tmp_path / "tool.tbl"
    path.write_text(SAMPLE)
    table = ToolTable()
    table.load(path)
    entry = table.get(1)
    entry.offset[2] = 0.75
    table.put(1, entry)
    table.save(path)
    text = path.read_text()
    assert text.splitlines()[0] == "T1   P1   D+3.000000 Z+0.750000 ;3mm end mill"
    assert not list(tmp_path.glob(".tool.tbl.*"))  # no temporary file left behind
    again = ToolTable()
    again.load(path)
    assert again.get(1).offset[2] == 0.75
    assert again.get(3).orientation == 4
    assert again.get(4).offset[8] == -1.0


def test_entries_are_copies() -> None:
    table = ToolTable()
    table.put(1, ToolEntry(toolno=5, pocketno=5))
    entry = table.get(1)
    entry.toolno = 6
    assert table.get(1).toolno == 5


@pytest.mark.parametrize(
    ("text", "warning"),
    [
        ("T1 P1 Z0.5\nT2 P2 K3\n", "2: unknown word 'K3': line skipped"),
        ("T1 P1 Z0.5\nT2 P2 Zabc\n", "2: bad number in word 'Zabc': line skipped"),
        ("TOOLNO POCKET\nT1 P1 Z0.5\n", "1: bad number in word 'TOOLNO': line skipped"),
    ],
)
def test_lines_linuxcnc_skips_are_skipped_with_a_warning(tmp_path, text: str, warning: str):
    path = tmp_path / "tool.tbl"
    path.write_text(text)
    table = ToolTable()
    table.load(path)
    assert [str(w) for w in table.warnings] == [f"{path}:{warning}, as LinuxCNC does"]
    assert table.has_unreadable_lines  # iocontrol never saves it over the file
    assert table.get(1).toolno == 1 and table.get(2).toolno == -1


@pytest.mark.parametrize(
    ("text", "warning"),
    [
        ("T0 P1\n", "1: tool number 0 is not positive"),
        ("T1 P0\n", "1: pocket 0 is not positive"),
    ],
)
def test_what_linuxcnc_accepts_is_loaded_with_a_warning(tmp_path, text: str, warning: str):
    path = tmp_path / "tool.tbl"
    path.write_text(text)
    table = ToolTable()
    table.load(path)
    assert [str(w) for w in table.warnings] == [f"{path}:{warning} (accepted, as LinuxCNC)"]
    assert not table.has_unreadable_lines
    assert table.get(1).toolno == int(text[1])
