"""iocontrol's INI keys: defaults, paths relative to the INI file, bad values (IO-004)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniError, IniFile
from cnc.inischema import SCHEMA, check_tool_table, read_config
from iocontrol.config import load_io_config
from iocontrol.tooltable import ToolTable


def write_ini(folder: Path, text: str) -> Path:
    ini = folder / "machine.ini"
    ini.write_text(text)
    return ini


def test_defaults_are_the_schemas(tmp_path: Path) -> None:
    config = load_io_config(write_ini(tmp_path, "[EMCIO]\n"))
    assert config.tool_table == tmp_path / "tool.tbl"
    assert not config.is_random_toolchanger
    assert config.cycle_time == SCHEMA["EMCIO"].keys["CYCLE_TIME"].default == 0.100
    assert config.nml_file is None and config.warnings == []


def test_keys_and_relative_paths(tmp_path: Path) -> None:
    text = (
        "[EMC]\nNML_FILE = nml/my.nml\n"
        "[EMCIO]\nTOOL_TABLE = tables/t.tbl\nRANDOM_TOOLCHANGER = 1\nCYCLE_TIME = 0.05\n"
    )
    config = load_io_config(write_ini(tmp_path, text))
    assert config.tool_table == tmp_path / "tables" / "t.tbl"
    assert config.nml_file == tmp_path / "nml" / "my.nml"
    assert config.is_random_toolchanger and config.cycle_time == 0.05


def test_an_included_table_name_is_relative_to_the_ini_file_as_in_linuxcnc(
    tmp_path: Path,
) -> None:
    (tmp_path / "inc").mkdir()
    (tmp_path / "inc" / "io.inc").write_text("[EMCIO]\nTOOL_TABLE = t.tbl\n")
    config = load_io_config(write_ini(tmp_path, "#INCLUDE inc/io.inc\n"))
    assert config.tool_table == tmp_path / "t.tbl"


@pytest.mark.parametrize("value", ["fast", "-1", "0", "nan"])
def test_a_bad_cycle_time_is_refused_with_file_line_and_range(tmp_path: Path, value) -> None:
    ini = write_ini(tmp_path, f"[EMCIO]\nCYCLE_TIME = {value}\n")
    with pytest.raises(IniError) as caught:
        load_io_config(ini)
    assert str(caught.value).startswith(f"{ini}:2: [EMCIO]CYCLE_TIME = '{value}' ")
    assert "allowed: a number > 0 and <= 1" in str(caught.value)


def test_db_program_is_a_warning(tmp_path: Path) -> None:
    ini = write_ini(tmp_path, "[EMCIO]\nDB_PROGRAM = db.py\n")
    config = load_io_config(ini)
    assert config.warnings[0].startswith(f"{ini}:2: [EMCIO]DB_PROGRAM is not supported")


def test_bad_random_toolchanger_is_fatal(tmp_path: Path) -> None:
    ini = write_ini(tmp_path, "[EMCIO]\nRANDOM_TOOLCHANGER = perhaps\n")
    with pytest.raises(IniError, match=f"{ini}:2:"):
        load_io_config(ini)


@pytest.mark.parametrize(
    ("table", "cause"),
    [
        ("T1 P1 Z1\nT2 P2 Z+nan\n", "2: Z = nan is not a finite number"),
        ("T1 P1 Z1\nT2 P2 Z1,5\n", "2: bad number in word 'Z1,5'"),  # LinuxCNC reads Z1
    ],
)
def test_a_tool_table_line_linuxcnc_misreads_stops_iocontrol(
    tmp_path: Path, table: str, cause: str
) -> None:
    (tmp_path / "tool.tbl").write_text(table)
    with pytest.raises(IniError, match=f"tool.tbl:{cause}"):
        load_io_config(write_ini(tmp_path, "[EMCIO]\n"))


@pytest.mark.parametrize(
    ("table", "cause"),
    [
        ("TOOLNO POCKET LENGTH\nT1 P1 Z1\n", "1: bad number in word 'TOOLNO'"),  # old format
        ("T1 P1 Z1\nT2 P2 K3\n", "2: unknown word 'K3'"),
    ],
)
def test_a_line_linuxcnc_skips_is_a_warning_and_blocks_saving(
    tmp_path: Path, table: str, cause: str
) -> None:
    """LinuxCNC skips such a line: so do we, saying where and why; saving the table over
    its file would lose the line, so iocontrol never does (test_iocontrol_process)."""
    (tmp_path / "tool.tbl").write_text(table)
    load_io_config(write_ini(tmp_path, "[EMCIO]\n"))  # starts
    config = read_config(IniFile.load(tmp_path / "machine.ini"), is_machine=False)
    assert check_tool_table(config) == []
    assert any(f"tool.tbl:{cause}: line skipped" in w for w in config.warnings)
    assert any("will not be saved over" in w for w in config.warnings)


def test_pocket_0_in_a_nonrandom_table_is_accepted_with_a_warning(tmp_path: Path) -> None:
    (tmp_path / "tool.tbl").write_text("T3 P0 D3\nT1 P2 D1\n")  # LinuxCNC's nstools.tbl
    config = read_config(IniFile.load(write_ini(tmp_path, "[EMCIO]\n")), is_machine=False)
    assert check_tool_table(config) == []
    assert any("tool.tbl:1: pocket 0 is not positive (accepted" in w for w in config.warnings)
    table = ToolTable()
    table.load(tmp_path / "tool.tbl")
    assert (table.get(1).toolno, table.get(1).pocketno, table.has_unreadable_lines) == (3, 0, False)
