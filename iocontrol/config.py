"""The INI keys iocontrol reads (IO-004, IO-015, TOOL-001), as LinuxCNC 2.9's ``io`` does.

- ``[EMCIO]TOOL_TABLE`` (default ``tool.tbl``), relative to the INI file's folder;
- ``[EMCIO]RANDOM_TOOLCHANGER`` (default 0: nonrandom);
- ``[EMCIO]CYCLE_TIME`` in seconds (default 0.100);
- ``[EMCIO]HEARTBEAT_TIMEOUT``: how long iocontrol may stay silent before it counts as lost;
- ``[EMC]NML_FILE`` (default: the project's ``configs/common/cnc.nml``);
- ``[EMCIO]DB_PROGRAM`` (TOOL-013, not supported yet): reported, the tool table file is used.

Their types, defaults and bounds are those of ``cnc.inischema``: a bad value anywhere in the
file, or a bad tool table line, stops iocontrol before it starts, with ``file:line``. The
file need not describe a whole machine (iocontrol runs under ``halrun`` with only its keys).
The other ``[EMCIO]`` keys (TOOL_CHANGE_POSITION, TOOL_CHANGE_QUILL_UP, ...) belong to task
and the interpreter.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from cnc.ini import IniFile
from cnc.inischema import ConfigError, check_tool_table, read_config


@dataclass
class IoConfig:
    """Everything iocontrol takes from the INI file; ``warnings`` are ``file:line: ...``."""

    ini_path: Path
    tool_table: Path
    is_random_toolchanger: bool
    cycle_time: float
    heartbeat_timeout: float  # [EMCIO]HEARTBEAT_TIMEOUT (nml/safety.py)
    nml_file: Path | None = None
    warnings: list[str] = field(default_factory=list)


def load_io_config(ini_path: str | os.PathLike[str]) -> IoConfig:
    """Read iocontrol's keys and check its tool table; raises IniError (``file:line:
    cause``, every problem) if iocontrol must not start."""
    config = read_config(IniFile.load(ini_path), is_machine=False)
    problems = check_tool_table(config)
    if problems:
        raise ConfigError(problems)
    table = config.file("EMCIO", "TOOL_TABLE")
    assert table is not None  # there is a default
    io_config = IoConfig(
        ini_path=Path(ini_path),
        tool_table=table,
        is_random_toolchanger=config.value("EMCIO", "RANDOM_TOOLCHANGER"),
        cycle_time=config.value("EMCIO", "CYCLE_TIME"),
        heartbeat_timeout=config.value("EMCIO", "HEARTBEAT_TIMEOUT"),
        nml_file=config.file("EMC", "NML_FILE"),
    )
    db_program = config.entry("EMCIO", "DB_PROGRAM")
    if db_program is not None and db_program.value:
        io_config.warnings.append(
            f"{db_program.where}: [EMCIO]DB_PROGRAM is not supported; "
            f"using the tool table file {io_config.tool_table}"
        )
    return io_config
