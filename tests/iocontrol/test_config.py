"""iocontrol's INI keys: defaults, paths relative to the INI file, bad values (IO-004)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniError
from iocontrol.config import DEFAULT_CYCLE_TIME_S, load_io_config


def write_ini(folder: Path, text: str) -> Path:
    ini = folder / "machine.ini"
    ini.write_text(text)
    return ini


def test_defaults(tmp_path: Path) -> None:
    config = load_io_config(write_ini(tmp_path, "[EMCIO]\n"))
    assert config.tool_table == tmp_path / "tool.tbl"
    assert not config.is_random_toolchanger
    assert config.cycle_time == DEFAULT_CYCLE_TIME_S
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


def test_bad_cycle_time_warns_with_file_and_line(tmp_path: Path) -> None:
    ini = write_ini(tmp_path, "[EMCIO]\nCYCLE_TIME = fast\nDB_PROGRAM = db.py\n")
    config = load_io_config(ini)
    assert config.cycle_time == DEFAULT_CYCLE_TIME_S
    assert config.warnings[0].startswith(f"{ini}:2: [EMCIO]CYCLE_TIME = 'fast'")
    assert config.warnings[1].startswith(f"{ini}:3: [EMCIO]DB_PROGRAM is not supported")
    config = load_io_config(write_ini(tmp_path, "[EMCIO]\nCYCLE_TIME = -1\n"))
    assert config.cycle_time == DEFAULT_CYCLE_TIME_S and "must be positive" in config.warnings[0]


def test_bad_random_toolchanger_is_fatal(tmp_path: Path) -> None:
    ini = write_ini(tmp_path, "[EMCIO]\nRANDOM_TOOLCHANGER = perhaps\n")
    with pytest.raises(IniError, match=f"{ini}:2:"):
        load_io_config(ini)
