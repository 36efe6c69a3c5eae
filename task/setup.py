"""What task reads from the INI file: the machine it drives (CFG-*, TASK-001).

Task tells motion the joint and axis limits at start-up (as LinuxCNC's task does through
motion's shared memory; here as NML messages) and gives the canon the machine's units and
axis limits. Every value, its default and its bounds come from ``cnc.inischema``; this
module only arranges them for task.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from cnc.ini import IniFile
from cnc.inischema import (
    AXIS_LETTERS,
    MM_PER_INCH,
    ConfigError,
    MachineConfig,
    check_parameter_file,
    read_config,
)
from nml import emc


@dataclass
class JointSetup:
    """One [JOINT_n] section as motion is told it."""

    min_limit: float
    max_limit: float
    max_vel: float
    max_acc: float
    ferror: float
    min_ferror: float
    backlash: float
    home: float
    home_offset: float
    home_search_vel: float
    home_latch_vel: float
    home_final_vel: float
    home_sequence: int | None  # None: not homed by home-all
    home_use_index: bool
    home_index_no_encoder_reset: bool
    home_ignore_limits: bool
    home_is_shared: bool
    home_absolute_encoder: int
    volatile_home: bool
    locking_indexer: bool
    is_angular: bool = False  # [JOINT_n]TYPE = ANGULAR

    @classmethod
    def from_config(cls, config: MachineConfig, index: int) -> JointSetup:
        def value(key: str):  # type: ignore[no-untyped-def]
            return config.value(f"JOINT_{index}", key)

        return cls(
            is_angular=value("TYPE") == "ANGULAR",
            min_limit=value("MIN_LIMIT"),
            max_limit=value("MAX_LIMIT"),
            max_vel=value("MAX_VELOCITY"),
            max_acc=value("MAX_ACCELERATION"),
            ferror=value("FERROR"),
            min_ferror=value("MIN_FERROR"),
            backlash=value("BACKLASH"),
            home=value("HOME"),
            home_offset=value("HOME_OFFSET"),
            home_search_vel=value("HOME_SEARCH_VEL"),
            home_latch_vel=value("HOME_LATCH_VEL"),
            home_final_vel=value("HOME_FINAL_VEL"),
            home_sequence=value("HOME_SEQUENCE"),
            home_use_index=value("HOME_USE_INDEX"),
            home_index_no_encoder_reset=value("HOME_INDEX_NO_ENCODER_RESET"),
            home_ignore_limits=value("HOME_IGNORE_LIMITS"),
            home_is_shared=value("HOME_IS_SHARED"),
            home_absolute_encoder=value("HOME_ABSOLUTE_ENCODER"),
            volatile_home=value("VOLATILE_HOME"),
            locking_indexer=value("LOCKING_INDEXER"),
        )


@dataclass
class AxisSetup:
    """One [AXIS_L] section (LinuxCNC's defaults where the section is missing)."""

    min_limit: float
    max_limit: float
    max_vel: float
    max_acc: float


@dataclass
class MachineSetup:
    config: MachineConfig
    ini_path: str
    folder: Path
    cycle_time: float
    linear_units: str  # "mm" or "inch"
    angular_units: float  # LinuxCNC's traj.angularUnits: machine angle units per degree
    coordinates: str  # [TRAJ]COORDINATES, upper case, repeats kept
    max_velocity: float
    max_acceleration: float
    default_velocity: float
    parameter_file: str
    position_file: str
    is_homing_forced: bool
    random_toolchanger: bool
    # [EMCIO]TOOL_CHANGE_POSITION: 3, 6 or 9 machine coordinates (XYZ[ABC[UVW]]), or None
    tool_change_position: list[float] | None
    joints: list[JointSetup] = field(default_factory=list)
    axes: dict[int, AxisSetup] = field(default_factory=dict)  # axis index -> its setup
    # [RS274NGC]RS274NGC_STARTUP_CODE (or its old place in [EMC]): run when task starts
    startup_code: str = ""
    # M100..M199 programs found in PROGRAM_PREFIX and USER_M_PATH: M number -> path
    user_m_commands: dict[int, str] = field(default_factory=dict)

    @property
    def units_per_mm(self) -> float:
        """LinuxCNC's traj.linearUnits: machine length units per millimetre."""
        return 1.0 if self.linear_units == "mm" else 1.0 / MM_PER_INCH

    @property
    def axis_mask(self) -> int:
        return sum(1 << index for index in self.axes)

    def resolve(self, name: str) -> str:
        """A file named in the INI, relative to the INI's folder."""
        return str(self.config.resolve(name))

    def motion_init_messages(self) -> list[emc.NMLmsg]:
        """What motion needs before it can move (sent once at start-up), in the order
        LinuxCNC's task sends it (iniTraj, iniJoint, iniAxis, iniSpindle): trajectory
        settings, then each joint, each axis, each spindle."""
        value = self.config.value
        default_acceleration = value("TRAJ", "DEFAULT_LINEAR_ACCELERATION")
        out: list[emc.NMLmsg] = [
            # no speed yet (a move brings its own); the default is the UIs' jog speed
            emc.EMC_TRAJ_SET_VELOCITY(velocity=0.0, ini_maxvel=self.default_velocity),
            # 1e99 when the INI file sets none: the axes' limits apply
            emc.EMC_TRAJ_SET_MAX_VELOCITY(velocity=self.max_velocity),
            emc.EMC_TRAJ_SET_ACCELERATION(acceleration=default_acceleration),
        ]
        if self.config.is_set("TRAJ", "MAX_LINEAR_ACCELERATION"):
            out.append(emc.EMC_TRAJ_SET_MAX_ACCELERATION(acceleration=self.max_acceleration))
        for index, joint in enumerate(self.joints):
            sequence = joint.home_sequence
            out += [
                emc.EMC_JOINT_SET_BACKLASH(joint=index, backlash=joint.backlash),
                emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=index, limit=joint.min_limit),
                emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=index, limit=joint.max_limit),
                emc.EMC_JOINT_SET_FERROR(joint=index, ferror=joint.ferror),
                emc.EMC_JOINT_SET_MIN_FERROR(joint=index, ferror=joint.min_ferror),
                emc.EMC_JOINT_SET_HOMING_PARAMS(
                    joint=index,
                    home=joint.home,
                    offset=joint.home_offset,
                    home_final_vel=joint.home_final_vel,
                    search_vel=joint.home_search_vel,
                    latch_vel=joint.home_latch_vel,
                    use_index=joint.home_use_index,
                    encoder_does_not_reset=joint.home_index_no_encoder_reset,
                    ignore_limits=joint.home_ignore_limits,
                    is_shared=joint.home_is_shared,
                    home_sequence=emc.NO_HOME_SEQUENCE if sequence is None else sequence,
                    volatile_home=joint.volatile_home,
                    locking_indexer=joint.locking_indexer,
                    absolute_encoder=joint.home_absolute_encoder,
                ),
                emc.EMC_JOINT_SET_MAX_VELOCITY(joint=index, vel=joint.max_vel),
                emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=index, acc=joint.max_acc),
            ]
        for index, axis in self.axes.items():
            out += [
                emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=index, limit=axis.min_limit),
                emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=index, limit=axis.max_limit),
                emc.EMC_AXIS_SET_MAX_VELOCITY(axis=index, vel=axis.max_vel),
                emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=index, acc=axis.max_acc),
            ]
        for index in range(value("TRAJ", "SPINDLES")):
            section = f"SPINDLE_{index}"  # (the reverse limits default to the forward ones)
            out.append(
                emc.EMC_SPINDLE_SET_PARAMS(
                    spindle=index,
                    max_forward=value(section, "MAX_FORWARD_VELOCITY"),
                    min_forward=value(section, "MIN_FORWARD_VELOCITY"),
                    max_reverse=value(section, "MAX_REVERSE_VELOCITY"),
                    min_reverse=value(section, "MIN_REVERSE_VELOCITY"),
                )
            )
        return out


def load_setup(ini: IniFile) -> MachineSetup:
    """Read the machine from an INI file, and check its parameter file; an IniError (a
    ConfigError listing every bad value as ``file:line: cause``) if it cannot run."""
    config = read_config(ini)
    problems = check_parameter_file(config)
    if problems:
        raise ConfigError(problems)
    value = config.value
    parameter_file = config.file("RS274NGC", "PARAMETER_FILE")
    position_file = config.file("TRAJ", "POSITION_FILE")
    setup = MachineSetup(
        config=config,
        ini_path=ini.path,
        folder=config.folder,
        cycle_time=value("TASK", "CYCLE_TIME"),
        linear_units=value("TRAJ", "LINEAR_UNITS"),
        angular_units=value("TRAJ", "ANGULAR_UNITS"),
        coordinates=config.coordinates,
        max_velocity=value("TRAJ", "MAX_LINEAR_VELOCITY"),
        max_acceleration=value("TRAJ", "MAX_LINEAR_ACCELERATION"),
        default_velocity=value("TRAJ", "DEFAULT_LINEAR_VELOCITY"),
        parameter_file=str(parameter_file) if parameter_file else "",
        position_file=str(position_file) if position_file else "",
        is_homing_forced=not value("TRAJ", "NO_FORCE_HOMING"),
        random_toolchanger=value("EMCIO", "RANDOM_TOOLCHANGER"),
        tool_change_position=value("EMCIO", "TOOL_CHANGE_POSITION"),
    )
    setup.joints = [JointSetup.from_config(config, index) for index in range(config.joints)]
    for letter in config.axes:
        section = f"AXIS_{letter}"
        setup.axes[AXIS_LETTERS.index(letter)] = AxisSetup(
            min_limit=value(section, "MIN_LIMIT"),
            max_limit=value(section, "MAX_LIMIT"),
            max_vel=value(section, "MAX_VELOCITY"),
            max_acc=value(section, "MAX_ACCELERATION"),
        )
    setup.user_m_commands = _user_m_commands(config)
    setup.startup_code = (
        value("RS274NGC", "RS274NGC_STARTUP_CODE") or value("EMC", "RS274NGC_STARTUP_CODE") or ""
    )
    return setup


def _user_m_commands(config: MachineConfig) -> dict[int, str]:
    """Executable files M100..M199 in [DISPLAY]PROGRAM_PREFIX (default ``nc_files``), then
    the ``:``-separated [RS274NGC]USER_M_PATH folders; the first one found wins, as in
    LinuxCNC. Relative folders are relative to the INI file's folder."""
    folders = [config.value("DISPLAY", "PROGRAM_PREFIX") or "nc_files"]
    folders += [part for part in (config.value("RS274NGC", "USER_M_PATH") or "").split(":") if part]
    found: dict[int, str] = {}
    for number in range(100, 200):
        for folder in folders:
            path = config.resolve(folder) / f"M{number}"
            if path.is_file() and os.access(path, os.X_OK):
                found[number] = str(path)
                break
    return found
