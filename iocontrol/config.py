"""The INI keys iocontrol reads (IO-004, IO-015, TOOL-001), as LinuxCNC 2.9's ``io`` does.

- ``[EMCIO]TOOL_TABLE`` (default ``tool.tbl``), relative paths from the INI file's folder;
- ``[EMCIO]RANDOM_TOOLCHANGER`` (default 0: nonrandom);
- ``[EMCIO]CYCLE_TIME`` in seconds (default 0.100); a bad value is reported and the default
  used, as LinuxCNC does;
- ``[EMC]NML_FILE`` (default: the project's ``configs/common/cnc.nml``);
- ``[EMCIO]DB_PROGRAM`` (TOOL-013, not supported yet): reported, the tool table file is used.

The other ``[EMCIO]`` keys (TOOL_CHANGE_POSITION, TOOL_CHANGE_QUILL_UP, ...) belong to task
and the interpreter.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from cnc.ini import IniError, IniFile

DEFAULT_CYCLE_TIME_S = 0.100
DEFAULT_TOOL_TABLE = "tool.tbl"


@dataclass
class IoConfig:
    """Everything iocontrol takes from the INI file; ``warnings`` are ``file:line: ...``."""

    ini_path: Path
    tool_table: Path
    is_random_toolchanger: bool = False
    cycle_time: float = DEFAULT_CYCLE_TIME_S
    nml_file: Path | None = None
    heartbeat_timeout: float = 1.0  # [EMCIO]HEARTBEAT_TIMEOUT (nml/safety.py)
    warnings: list[str] = field(default_factory=list)


def _resolve(ini: IniFile, section: str, key: str, default: str | None) -> Path | None:
    """A file named in the INI: ``~`` expanded, relative to the folder of the line naming it."""
    entry = ini.entry(section, key)
    text = entry.value if entry is not None and entry.value else default  # empty: unset
    if text is None:
        return None
    path = Path(os.path.expanduser(text))
    if path.is_absolute():
        return path
    base = Path(entry.file).parent if entry is not None else Path(ini.path).parent
    return base / path


def load_io_config(ini_path: str | os.PathLike[str]) -> IoConfig:
    """Read iocontrol's keys; raises IniError (``file:line: cause``) for a fatal problem."""
    ini = IniFile.load(ini_path)
    table = _resolve(ini, "EMCIO", "TOOL_TABLE", DEFAULT_TOOL_TABLE)
    assert table is not None  # there is a default
    config = IoConfig(
        ini_path=Path(ini_path),
        tool_table=table,
        is_random_toolchanger=bool(ini.get_bool("EMCIO", "RANDOM_TOOLCHANGER", False)),
        nml_file=_resolve(ini, "EMC", "NML_FILE", None),
        heartbeat_timeout=ini.get_float("EMCIO", "HEARTBEAT_TIMEOUT", 1.0) or 1.0,
    )
    try:
        cycle = ini.get_float("EMCIO", "CYCLE_TIME")
    except IniError as exc:
        config.warnings.append(f"{exc}; using default {DEFAULT_CYCLE_TIME_S:.3f} s")
    else:
        if cycle is not None and cycle > 0:
            config.cycle_time = cycle
        elif cycle is not None:
            found = ini.entry("EMCIO", "CYCLE_TIME")
            assert found is not None
            config.warnings.append(
                f"{found.file}:{found.line}: [EMCIO]CYCLE_TIME = '{found.value}' must be "
                f"positive; using default {DEFAULT_CYCLE_TIME_S:.3f} s"
            )
    db_program = ini.entry("EMCIO", "DB_PROGRAM")
    if db_program is not None:
        config.warnings.append(
            f"{db_program.file}:{db_program.line}: [EMCIO]DB_PROGRAM is not supported; "
            f"using the tool table file {config.tool_table}"
        )
    return config
