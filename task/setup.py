"""What task reads from the INI file: the machine it drives (CFG-*, TASK-001).

Task tells motion the joint and axis limits at start-up (as LinuxCNC's task does through
motion's shared memory; here as NML messages) and gives the canon the machine's units and
axis limits.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from cnc.ini import IniError, IniFile
from motion.pose import AXIS_LETTERS
from nml import emc

MM_PER_INCH = 25.4
# [TRAJ]ANGULAR_UNITS -> units per degree (LinuxCNC's traj.angularUnits)
ANGULAR_UNITS_PER_DEGREE = {
    "deg": 1.0,
    "degree": 1.0,
    "rad": math.pi / 180,
    "radian": math.pi / 180,
    "grad": 10 / 9,
    "gon": 10 / 9,
}


@dataclass
class JointSetup:
    min_limit: float = -math.inf
    max_limit: float = math.inf
    max_vel: float = 1.0
    max_acc: float = 1.0
    ferror: float = 1.0
    min_ferror: float = 1.0
    backlash: float = 0.0
    home: float = 0.0
    home_offset: float = 0.0
    home_search_vel: float = 0.0
    home_latch_vel: float = 0.0
    home_final_vel: float = -1.0
    home_sequence: int = 999  # LinuxCNC's "no HOME_SEQUENCE": not homed by home-all
    home_use_index: bool = False
    home_ignore_limits: bool = False
    home_is_shared: bool = False


@dataclass
class AxisSetup:
    min_limit: float = -math.inf
    max_limit: float = math.inf
    max_vel: float = math.inf
    max_acc: float = math.inf


@dataclass
class MachineSetup:
    ini_path: str
    folder: Path
    cycle_time: float = 0.01
    linear_units: str = "mm"
    angular_units: float = 1.0  # LinuxCNC's traj.angularUnits: machine angle units per degree
    coordinates: str = "XYZ"
    joints: list[JointSetup] = field(default_factory=list)
    axes: dict[int, AxisSetup] = field(default_factory=dict)
    max_velocity: float = math.inf
    max_acceleration: float = math.inf
    default_velocity: float = 1.0
    parameter_file: str = ""
    position_file: str = ""
    is_homing_forced: bool = True
    random_toolchanger: bool = False
    # [EMCIO]TOOL_CHANGE_POSITION: 3, 6 or 9 machine coordinates (XYZ[ABC[UVW]]), or None
    tool_change_position: list[float] | None = None
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
        path = Path(name).expanduser()
        return str(path if path.is_absolute() else self.folder / path)

    def motion_init_messages(self) -> list[emc.NMLmsg]:
        """The limits motion needs before it can move (sent once at start-up)."""
        out: list[emc.NMLmsg] = []
        for index, joint in enumerate(self.joints):
            out += [
                emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=index, limit=joint.min_limit),
                emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=index, limit=joint.max_limit),
                emc.EMC_JOINT_SET_MAX_VELOCITY(joint=index, vel=joint.max_vel),
                emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=index, acc=joint.max_acc),
                emc.EMC_JOINT_SET_FERROR(joint=index, ferror=joint.ferror),
                emc.EMC_JOINT_SET_MIN_FERROR(joint=index, ferror=joint.min_ferror),
                emc.EMC_JOINT_SET_BACKLASH(joint=index, backlash=joint.backlash),
                emc.EMC_JOINT_SET_HOMING_PARAMS(
                    joint=index,
                    home=joint.home,
                    offset=joint.home_offset,
                    home_final_vel=joint.home_final_vel,
                    search_vel=joint.home_search_vel,
                    latch_vel=joint.home_latch_vel,
                    use_index=joint.home_use_index,
                    ignore_limits=joint.home_ignore_limits,
                    is_shared=joint.home_is_shared,
                    home_sequence=joint.home_sequence,
                ),
            ]
        for index, axis in self.axes.items():
            out += [
                emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=index, limit=axis.min_limit),
                emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=index, limit=axis.max_limit),
                emc.EMC_AXIS_SET_MAX_VELOCITY(axis=index, vel=axis.max_vel),
                emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=index, acc=axis.max_acc),
            ]
        if math.isfinite(self.max_velocity):
            out.append(emc.EMC_TRAJ_SET_MAX_VELOCITY(velocity=self.max_velocity))
        if math.isfinite(self.max_acceleration):
            out.append(emc.EMC_TRAJ_SET_MAX_ACCELERATION(acceleration=self.max_acceleration))
        return out


def load_setup(ini: IniFile) -> MachineSetup:
    """Read the machine from an INI file; a bad value raises IniError with file:line."""
    setup = MachineSetup(ini.path, Path(ini.path).resolve().parent)
    setup.cycle_time = ini.get_float("TASK", "CYCLE_TIME", 0.01)
    units = (ini.find("TRAJ", "LINEAR_UNITS", "mm") or "mm").lower()
    if units in ("mm", "metric", "millimeter", "1"):
        setup.linear_units = "mm"
    elif units in ("inch", "in", "imperial", "0.03937007874016"):
        setup.linear_units = "inch"
    else:
        entry = ini.entry("TRAJ", "LINEAR_UNITS")
        raise IniError(
            ini.path if entry is None else entry.file,
            0 if entry is None else entry.line,
            f"[TRAJ]LINEAR_UNITS = '{units}' is not mm or inch",
        )
    angular = (ini.find("TRAJ", "ANGULAR_UNITS", "degree") or "degree").lower()
    setup.angular_units = ANGULAR_UNITS_PER_DEGREE.get(angular, 1.0)
    coordinates = (ini.find("TRAJ", "COORDINATES") or "XYZ").replace(" ", "").upper()
    setup.coordinates = coordinates
    num_joints = ini.get_int("KINS", "JOINTS", len(coordinates))
    for index in range(num_joints):
        section = f"JOINT_{index}"
        setup.joints.append(
            JointSetup(
                min_limit=ini.get_float(section, "MIN_LIMIT", -math.inf),
                max_limit=ini.get_float(section, "MAX_LIMIT", math.inf),
                max_vel=ini.get_float(section, "MAX_VELOCITY", 1.0),
                max_acc=ini.get_float(section, "MAX_ACCELERATION", 1.0),
                ferror=ini.get_float(section, "FERROR", 1.0),
                min_ferror=ini.get_float(section, "MIN_FERROR", 1.0),
                backlash=ini.get_float(section, "BACKLASH", 0.0),
                home=ini.get_float(section, "HOME", 0.0),
                home_offset=ini.get_float(section, "HOME_OFFSET", 0.0),
                home_search_vel=ini.get_float(section, "HOME_SEARCH_VEL", 0.0),
                home_latch_vel=ini.get_float(section, "HOME_LATCH_VEL", 0.0),
                home_final_vel=ini.get_float(section, "HOME_FINAL_VEL", -1.0),
                home_sequence=ini.get_int(section, "HOME_SEQUENCE", 999),
                home_use_index=ini.get_bool(section, "HOME_USE_INDEX", False),
                home_ignore_limits=ini.get_bool(section, "HOME_IGNORE_LIMITS", False),
                home_is_shared=ini.get_bool(section, "HOME_IS_SHARED", False),
            )
        )
    for letter in dict.fromkeys(coordinates):
        index = AXIS_LETTERS.index(letter.lower())
        section = f"AXIS_{letter}"
        setup.axes[index] = AxisSetup(
            min_limit=ini.get_float(section, "MIN_LIMIT", -math.inf),
            max_limit=ini.get_float(section, "MAX_LIMIT", math.inf),
            max_vel=ini.get_float(section, "MAX_VELOCITY", math.inf),
            max_acc=ini.get_float(section, "MAX_ACCELERATION", math.inf),
        )
    setup.max_velocity = ini.get_float("TRAJ", "MAX_LINEAR_VELOCITY", math.inf)
    setup.max_acceleration = ini.get_float("TRAJ", "MAX_LINEAR_ACCELERATION", math.inf)
    setup.default_velocity = ini.get_float("TRAJ", "DEFAULT_LINEAR_VELOCITY", 1.0)
    parameter_file = ini.find("RS274NGC", "PARAMETER_FILE")
    setup.parameter_file = setup.resolve(parameter_file) if parameter_file else ""
    position_file = ini.find("TRAJ", "POSITION_FILE")
    setup.position_file = setup.resolve(position_file) if position_file else ""
    setup.is_homing_forced = not ini.get_bool("TRAJ", "NO_FORCE_HOMING", False)
    setup.random_toolchanger = ini.get_bool("EMCIO", "RANDOM_TOOLCHANGER", False)
    setup.tool_change_position = _tool_change_position(ini)
    setup.user_m_commands = _user_m_commands(ini, setup)
    return setup


def _tool_change_position(ini: IniFile) -> list[float] | None:
    """Like LinuxCNC, the first 9, 6 or 3 numbers of the value (ABC and UVW default to 0)."""
    text = ini.find("EMCIO", "TOOL_CHANGE_POSITION")
    if text is None:
        return None
    numbers: list[float] = []
    for word in text.split():
        try:
            numbers.append(float(word))
        except ValueError:
            break
    for count in (9, 6, 3):
        if len(numbers) >= count:
            return numbers[:count]
    entry = ini.entry("EMCIO", "TOOL_CHANGE_POSITION")
    raise IniError(
        ini.path if entry is None else entry.file,
        0 if entry is None else entry.line,
        f"[EMCIO]TOOL_CHANGE_POSITION = '{text}' needs 3, 6 or 9 numbers (X Y Z [A B C [U V W]])",
    )


def _user_m_commands(ini: IniFile, setup: MachineSetup) -> dict[int, str]:
    """Executable files M100..M199 in [DISPLAY]PROGRAM_PREFIX (default ``nc_files``), then
    the ``:``-separated [RS274NGC]USER_M_PATH folders; the first one found wins, as in
    LinuxCNC. Relative folders are relative to the INI file's folder."""
    folders = [ini.find("DISPLAY", "PROGRAM_PREFIX") or "nc_files"]
    folders += [part for part in (ini.find("RS274NGC", "USER_M_PATH") or "").split(":") if part]
    found: dict[int, str] = {}
    for number in range(100, 200):
        for folder in folders:
            path = Path(setup.resolve(folder)) / f"M{number}"
            if path.is_file() and os.access(path, os.X_OK):
                found[number] = str(path)
                break
    return found
