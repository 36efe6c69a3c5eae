"""iocontrol's INI keys: defaults, paths relative to the INI file, bad values (IO-004)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniError
from cnc.inischema import SCHEMA
from iocontrol.config import load_io_config


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
        ("T1 P1 Z1\nT2 P2 K3\n", "2: unknown word 'K3'"),
    ],
)
def test_a_bad_tool_table_line_stops_iocontrol(tmp_path: Path, table: str, cause: str) -> None:
    (tmp_path / "tool.tbl").write_text(table)
    with pytest.raises(IniError, match=f"tool.tbl:{cause}"):
        load_io_config(write_ini(tmp_path, "[EMCIO]\n"))
