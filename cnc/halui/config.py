"""What halui reads from the INI file: the machine's size, its limits and the MDI buttons.

Types, bounds and the INI-wide checks are ``cnc.inischema``'s: a bad value anywhere stops
halui before it touches HAL, with ``file:line``. Keys a file may leave out have halui's own
defaults here, as LinuxCNC's halui has them (the file need not describe a whole machine).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from cnc.ini import IniFile
from cnc.inischema import SCHEMA, MachineConfig, read_config
from nml.axes import AXIS_LETTERS as ALL_AXES

AXIS_LETTERS = ALL_AXES.lower()  # axis index -> letter, as halui.axis.selected counts them
_KEYS = SCHEMA["HALUI"].keys


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
    cycle_time: float = _KEYS["CYCLE_TIME"].default  # [HALUI]CYCLE_TIME
    heartbeat_timeout: float = _KEYS["HEARTBEAT_TIMEOUT"].default  # (nml/safety.py)


def load_config(ini_path: str | os.PathLike[str]) -> HaluiConfig:
    """Read the INI file; IniError (``file:line: cause``, every problem) for a value halui
    or any other part of the controller cannot use."""
    config = read_config(IniFile.load(ini_path), is_machine=False)
    value = config.value
    defaults = HaluiConfig(str(ini_path))
    return HaluiConfig(
        ini_path=str(ini_path),
        num_joints=value("KINS", "JOINTS") or defaults.num_joints,
        axes=config.axes.lower() if config.entry("TRAJ", "COORDINATES") else AXIS_LETTERS,
        num_spindles=value("TRAJ", "SPINDLES"),
        has_home_all=value("JOINT_0", "HOME_SEQUENCE") is not None,
        mdi_commands=tuple(config.values("HALUI", "MDI_COMMAND")),
        max_feed_override=value("DISPLAY", "MAX_FEED_OVERRIDE"),
        min_spindle_override=_given(
            value("DISPLAY", "MIN_SPINDLE_OVERRIDE"), defaults.min_spindle_override
        ),
        max_spindle_override=_given(
            value("DISPLAY", "MAX_SPINDLE_OVERRIDE"), defaults.max_spindle_override
        ),
        max_velocity=_max_velocity(config),
        cycle_time=value("HALUI", "CYCLE_TIME"),
        heartbeat_timeout=value("HALUI", "HEARTBEAT_TIMEOUT"),
    )


def _given(value: float | None, default: float) -> float:
    return default if value is None else value


def _max_velocity(config: MachineConfig) -> float:
    for section, key in (("TRAJ", "MAX_LINEAR_VELOCITY"), ("AXIS_X", "MAX_VELOCITY")):
        if config.is_set(section, key):
            return config.value(section, key)
    return 1.0
