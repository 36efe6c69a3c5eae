"""What halui reads from the INI file: the machine's size, its limits and the MDI buttons."""

from __future__ import annotations

import os
from dataclasses import dataclass

from cnc.api.commands import TEXT_LIMIT
from cnc.ini import IniError, IniFile
from nml.emc import EMCMOT_MAX_JOINTS, EMCMOT_MAX_SPINDLES

AXIS_LETTERS = "xyzabcuvw"  # axis index -> letter, as halui.axis.selected counts them
MAX_MDI_COMMANDS = 64  # LinuxCNC's limit on [HALUI]MDI_COMMAND lines
CYCLE_TIME_S = 0.02  # LinuxCNC's halui polls every 20 ms


@dataclass(frozen=True)
class HaluiConfig:
    ini_path: str
    num_joints: int = 3  # [KINS]JOINTS
    axes: str = AXIS_LETTERS  # lowercase letters of [TRAJ]COORDINATES, in XYZABCUVW order
    num_spindles: int = 1  # [TRAJ]SPINDLES
    has_home_all: bool = False  # [JOINT_0]HOME_SEQUENCE is set: halui.home-all exists
    mdi_commands: tuple[str, ...] = ()  # [HALUI]MDI_COMMAND, one halui.mdi-command-NN each
    max_feed_override: float = 1.0  # [DISPLAY]MAX_FEED_OVERRIDE
    min_spindle_override: float = 0.0  # [DISPLAY]MIN_SPINDLE_OVERRIDE
    max_spindle_override: float = 1.0  # [DISPLAY]MAX_SPINDLE_OVERRIDE
    max_velocity: float = 1.0  # [TRAJ]MAX_LINEAR_VELOCITY, else [AXIS_X]MAX_VELOCITY
    cycle_time: float = CYCLE_TIME_S  # [HALUI]CYCLE_TIME (ours; LinuxCNC's is fixed)
    heartbeat_timeout: float = 1.0  # [HALUI]HEARTBEAT_TIMEOUT (nml/safety.py)


def load_config(ini_path: str | os.PathLike[str]) -> HaluiConfig:
    """Read the INI file; IniError (``file:line: cause``) for a value halui cannot use.

    Like LinuxCNC's halui, non-positive limits and counts keep their defaults; unlike it,
    a value that is not a number is an error rather than silently ignored.
    """
    ini = IniFile.load(ini_path)
    return HaluiConfig(
        ini_path=str(ini_path),
        num_joints=_count(ini, "KINS", "JOINTS", 3, EMCMOT_MAX_JOINTS),
        axes=_axes(ini.find("TRAJ", "COORDINATES") or ""),
        num_spindles=_count(ini, "TRAJ", "SPINDLES", 1, EMCMOT_MAX_SPINDLES),
        has_home_all=ini.find("JOINT_0", "HOME_SEQUENCE") is not None,
        mdi_commands=_mdi_commands(ini),
        max_feed_override=_positive(ini, "DISPLAY", "MAX_FEED_OVERRIDE", 1.0),
        min_spindle_override=_positive(ini, "DISPLAY", "MIN_SPINDLE_OVERRIDE", 0.0),
        max_spindle_override=_positive(ini, "DISPLAY", "MAX_SPINDLE_OVERRIDE", 1.0),
        max_velocity=_max_velocity(ini),
        cycle_time=_positive(ini, "HALUI", "CYCLE_TIME", CYCLE_TIME_S),
        heartbeat_timeout=_positive(ini, "HALUI", "HEARTBEAT_TIMEOUT", 1.0),
    )


def _count(ini: IniFile, section: str, key: str, default: int, limit: int) -> int:
    value = ini.get_int(section, key)
    if value is None or value <= 0:
        return default
    if value > limit:
        entry = ini.entry(section, key)
        assert entry is not None
        raise IniError(entry.file, entry.line, f"[{section}]{key} = {value}: at most {limit}")
    return value


def _positive(ini: IniFile, section: str, key: str, default: float) -> float:
    value = ini.get_float(section, key)
    return value if value is not None and value > 0 else default


def _axes(coordinates: str) -> str:
    """The axes named in [TRAJ]COORDINATES (every axis when it names none, as LinuxCNC)."""
    named = {letter for letter in coordinates.lower() if letter in AXIS_LETTERS}
    return "".join(letter for letter in AXIS_LETTERS if letter in named) or AXIS_LETTERS


def _max_velocity(ini: IniFile) -> float:
    for section, key in (("TRAJ", "MAX_LINEAR_VELOCITY"), ("AXIS_X", "MAX_VELOCITY")):
        value = ini.get_float(section, key)
        if value is not None:
            return value
    return 1.0


def _mdi_commands(ini: IniFile) -> tuple[str, ...]:
    entries = ini.entries("HALUI", "MDI_COMMAND")
    if len(entries) > MAX_MDI_COMMANDS:
        extra = entries[MAX_MDI_COMMANDS]
        raise IniError(extra.file, extra.line, f"more than {MAX_MDI_COMMANDS} MDI_COMMAND lines")
    for entry in entries:
        if not entry.value:
            raise IniError(entry.file, entry.line, "[HALUI]MDI_COMMAND is empty")
        if len(entry.value.encode()) > TEXT_LIMIT:  # what an MDI command message holds
            raise IniError(
                entry.file, entry.line, f"[HALUI]MDI_COMMAND longer than {TEXT_LIMIT} bytes"
            )
    return tuple(entry.value for entry in entries)
