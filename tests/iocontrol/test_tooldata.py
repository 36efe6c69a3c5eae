"""The shared tool data store: iocontrol writes, any process reads a consistent copy."""

from __future__ import annotations

import pytest

from iocontrol.tooldata import ToolDataError, ToolDataReader, ToolDataWriter, read_tool_data
from iocontrol.tooltable import ToolTable


def table(lines: list[str], *, is_random: bool = False) -> ToolTable:
    tools = ToolTable(random_toolchanger=is_random)
    tools.load_lines(lines, "tool.tbl")
    return tools


def test_reader_sees_what_the_writer_published() -> None:
    writer = ToolDataWriter()
    try:
        writer.publish(table(["T5 P0 Z5\n", "T1 P1 X0.1 Z0.5 W9 D3 I10 J20 Q2\n"], is_random=True))
        got = read_tool_data()
        assert got.random_toolchanger and got.find_index_for_tool(1) == 1
        one = got.get(1)
        assert (one.toolno, one.pocketno, one.diameter, one.orientation) == (1, 1, 3.0, 2)
        assert one.offset == [0.1, 0, 0.5, 0, 0, 0, 0, 0, 9.0]
        assert (one.frontangle, one.backangle) == (10.0, 20.0)
        assert got.get(0).toolno == 5
    finally:
        writer.close()


def test_sequence_tells_readers_about_changes() -> None:
    writer = ToolDataWriter()
    try:
        with ToolDataReader() as reader:
            first = reader.sequence
            tools = table(["T1 P4 Z1\n"])
            writer.publish(tools)
            assert reader.sequence > first and reader.sequence % 2 == 0
            assert reader.read().get(1).pocketno == 4
            tools.put(2, tools.get(1))
            writer.publish(tools)
            assert reader.read().last_index == 2
    finally:
        writer.close()


def test_no_store_and_closed_store_are_clear_errors() -> None:
    with pytest.raises(ToolDataError, match="is iocontrol running"):
        read_tool_data()
    writer = ToolDataWriter()
    reader = ToolDataReader()
    writer.close()
    with pytest.raises(ToolDataError):
        reader.read()
    reader.close()
