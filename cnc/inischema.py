"""Every INI key the controller reads, declared once: type, default, bounds, required (CFG-004).

``SCHEMA`` below is the single list of the sections and keys that the launcher, task (and
through it motion), iocontrol and halui read, with LinuxCNC 2.9's defaults. ``read_config``
checks an INI file against it in one pass and returns a ``MachineConfig`` whose
``value(section, key)`` is the typed value or the default; every bad value is reported with
``file:line``, the key and the allowed range, all at once (``ConfigError``), and a key the
schema does not know in a section it does know is a warning (never an error), unless one of
the machine's HAL files uses it (``[JOINT_0]SCALE``, ``$::JOINT_0(SCALE)``).

The launcher calls ``check_machine`` before it starts anything: the INI file, then the tool
table and the ``.var`` parameter file it names (``check_tool_table``,
``check_parameter_file``), so a machine that cannot run never starts a process.

Adding a key is one line in its section, e.g. ``real("HEARTBEAT_TIMEOUT", 0.5, above=0,
high=60)`` in ``[EMCMOT]``; a process then reads ``config.value("EMCMOT",
"HEARTBEAT_TIMEOUT")``, ``config`` being ``load_config(path)`` or ``read_config(ini)``.
Kinds: ``real`` (a finite number), ``integer`` (decimal or 0x hex), ``flag`` (1/0, yes/no,
true/false), ``text``, ``path`` (a file named relative to the INI file's folder),
``choice`` (one of some words), ``numbers`` (a list of numbers), ``coordinates`` (axis
letters). Bounds: ``low``/``high`` inclusive, ``above``/``below`` exclusive.
``repeat=True`` for keys that may appear more than once (``HALFILE``).

Beyond LinuxCNC, which reads most of these leniently (``sscanf``: ``1,5`` is 1, ``nan`` is
accepted, an unknown axis letter is skipped, a bad value often silently becomes the
default), a value here is a complete number within its bounds or the machine does not start.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from cnc.ini import IniError, IniFile, IniValue, parse_bool, parse_float, parse_int
from nml.axes import AXIS_LETTERS

# Sizes of LinuxCNC's motion controller (nml.emc holds the same numbers, checked by a test;
# importing the message catalogue here would cost every process 0.3 s at start-up).
MAX_JOINTS = 16  # EMCMOT_MAX_JOINTS
MAX_SPINDLES = 8  # EMCMOT_MAX_SPINDLES
MAX_MDI_COMMANDS = 64  # LinuxCNC's limit on [HALUI]MDI_COMMAND lines
MDI_COMMAND_BYTES = 254  # what an EMC_TASK_PLAN_EXECUTE holds (LINELEN - 1; cnc.api's TEXT_LIMIT)
HUGE = 1e99  # LinuxCNC's "no limit" for positions, velocities and accelerations
MM_PER_INCH = 25.4
# The blending the canon starts with (LinuxCNC's INIT_CANON: G64 within 0.001 inch); motion
# starts with it too, in the machine's units
DEFAULT_BLEND_TOLERANCE_MM = 0.001 * MM_PER_INCH


# --------------------------------------------------------------------------- kinds of values
class Kind:
    """How a value is read: ``parse`` raises ValueError(reason) for a bad one; a number's
    bounds are checked after (``has_bounds``)."""

    description = "text"
    has_bounds = False

    def parse(self, text: str) -> Any:
        return text

    def allowed(self, key: Key) -> str:
        return self.description


class _Real(Kind):
    description = "a number"
    has_bounds = True

    def parse(self, text: str) -> float:
        try:
            return parse_float(text)
        except ValueError:
            raise ValueError("is not a finite number") from None

    def allowed(self, key: Key) -> str:
        return _range(self.description, key)


class _Integer(Kind):
    description = "an integer"
    has_bounds = True

    def parse(self, text: str) -> int:
        try:
            return parse_int(text)
        except ValueError:
            raise ValueError("is not an integer") from None

    def allowed(self, key: Key) -> str:
        return _range(self.description, key)


class _Flag(Kind):
    description = "1 or 0 (yes/no, true/false)"

    def parse(self, text: str) -> bool:
        try:
            return parse_bool(text)
        except ValueError:
            pass
        try:  # LinuxCNC reads a flag as an integer first: any non-zero one is true
            return parse_int(text) != 0
        except ValueError:
            raise ValueError("is not a flag") from None


class _Path(Kind):
    description = "a file name"


class _Choice(Kind):
    """One of some words (any case), each standing for a value; ``numbers`` is an optional
    reader for values given as numbers instead (``LINEAR_UNITS = 1.0``)."""

    def __init__(self, words: dict[str, Any], numbers: Callable[[float], Any] | None) -> None:
        self.words = words
        self.numbers = numbers
        self.description = "one of " + ", ".join(words)

    def parse(self, text: str) -> Any:
        word = text.strip().lower()
        if word in self.words:
            return self.words[word]
        if self.numbers is not None:
            try:
                return self.numbers(parse_float(word))
            except ValueError:
                pass
        raise ValueError("is not allowed")


class _Numbers(Kind):
    """Numbers separated by blanks; ``counts`` are the allowed lengths."""

    def __init__(self, counts: tuple[int, ...]) -> None:
        self.counts = counts
        self.description = f"{' or '.join(map(str, counts))} numbers separated by blanks"

    def parse(self, text: str) -> list[float]:
        words = text.split()
        try:
            values = [parse_float(word) for word in words]
        except ValueError:
            raise ValueError("is not a list of finite numbers") from None
        if len(values) not in self.counts:
            raise ValueError(f"has {len(values)} numbers")
        return values


class _Coordinates(Kind):
    description = f"axis letters from {AXIS_LETTERS} (e.g. X Y Z), blanks between them allowed"

    def parse(self, text: str) -> str:
        letters = "".join(text.split()).upper()
        wrong = sorted({letter for letter in letters if letter not in AXIS_LETTERS})
        if wrong:
            raise ValueError(f"names no axis {', '.join(wrong)}")
        if not letters:
            raise ValueError("names no axis")
        return letters


def _range(noun: str, key: Key) -> str:
    parts = []
    if key.low is not None and key.high is not None:
        return f"{noun} from {key.low:g} to {key.high:g}"
    if key.low is not None:
        parts.append(f">= {key.low:g}")
    if key.above is not None:
        parts.append(f"> {key.above:g}")
    if key.high is not None:
        parts.append(f"<= {key.high:g}")
    if key.below is not None:
        parts.append(f"< {key.below:g}")
    return f"{noun} {' and '.join(parts)}" if parts else noun


REAL, INTEGER, FLAG, TEXT, PATH = _Real(), _Integer(), _Flag(), Kind(), _Path()
COORDINATES = _Coordinates()


def _linear_units(value: float) -> str:
    """LINEAR_UNITS as a number is machine units per millimetre: 1 (mm) or 1/25.4 (inch)."""
    for name, per_mm in (("mm", 1.0), ("inch", 1 / MM_PER_INCH)):
        if abs(value - per_mm) < 1e-6:
            return name
    raise ValueError(value)


def _positive(value: float) -> float:
    if value <= 0:
        raise ValueError(value)
    return value


# machine units per degree (LinuxCNC's table says 0.9 for grad and gon; a grad is 0.9 degree)
ANGULAR_UNITS_PER_DEGREE = {"deg": 1.0, "degree": 1.0, "grad": 10 / 9, "gon": 10 / 9}
ANGULAR_UNITS_PER_DEGREE |= {"rad": math.pi / 180, "radian": math.pi / 180}

LINEAR_UNITS = _Choice(
    {"mm": "mm", "metric": "mm", "in": "inch", "inch": "inch", "imperial": "inch"}, _linear_units
)
ANGULAR_UNITS = _Choice(ANGULAR_UNITS_PER_DEGREE, _positive)
JOINT_TYPE = _Choice({"linear": "LINEAR", "angular": "ANGULAR"}, None)


def choice(*words: str) -> _Choice:
    """Words standing for themselves (any case in the file, upper case as a value)."""
    return _Choice({word.lower(): word for word in words}, None)


# --------------------------------------------------------------------------- keys, sections
class SameAs:
    """A default that is the value of another key of the same section (MIN_FERROR)."""

    def __init__(self, key: str) -> None:
        self.key = key


class Key:
    """One key: its name, kind, default (None: none, the value is None when not written),
    bounds for numbers, whether the machine needs it, whether it may repeat."""

    __slots__ = (
        "above",
        "below",
        "default",
        "high",
        "is_repeatable",
        "is_required",
        "kind",
        "low",
        "max_bytes",
        "max_count",
        "name",
    )

    def __init__(
        self,
        name: str,
        kind: Kind,
        default: Any = None,
        *,
        low: float | None = None,
        high: float | None = None,
        above: float | None = None,
        below: float | None = None,
        required: bool = False,
        repeat: bool = False,
        max_count: int | None = None,
        max_bytes: int | None = None,
    ) -> None:
        self.name = name
        self.kind = kind
        self.default = default
        self.low, self.high, self.above, self.below = low, high, above, below
        self.is_required = required
        self.is_repeatable = repeat or max_count is not None
        self.max_count = max_count
        self.max_bytes = max_bytes

    @property
    def allowed(self) -> str:
        return self.kind.allowed(self)

    def check(self, value: Any) -> str | None:
        """Why ``value`` (already parsed) is out of bounds, or None."""
        is_outside = (
            (self.low is not None and value < self.low)
            or (self.high is not None and value > self.high)
            or (self.above is not None and value <= self.above)
            or (self.below is not None and value >= self.below)
        )
        return "is out of range" if is_outside else None


def real(name: str, default: Any = None, **bounds: Any) -> Key:
    return Key(name, REAL, default, **bounds)


def integer(name: str, default: Any = None, **bounds: Any) -> Key:
    return Key(name, INTEGER, default, **bounds)


def flag(name: str, default: bool = False, **options: Any) -> Key:
    return Key(name, FLAG, default, **options)


def text(name: str, default: str | None = None, **options: Any) -> Key:
    return Key(name, TEXT, default, **options)


def path(name: str, default: str | None = None, **options: Any) -> Key:
    return Key(name, PATH, default, **options)


def hal_only(*names: str) -> list[Key]:
    """Documented keys that only HAL files read (a servo's P, a stepgen's SCALE): known, so
    never warned about, and not checked (the HAL file's pin types decide)."""
    return [Key(name, TEXT) for name in names]


class Section:
    """A section's keys. ``is_open``: the section belongs to other programs (a display, a
    filter list), so keys not declared here are not warned about."""

    def __init__(self, name: str, keys: Iterable[Key], *, is_open: bool = False) -> None:
        self.name = name
        self.keys = {key.name: key for key in keys}
        self.is_open = is_open


# --------------------------------------------------------------------------- the schema
_SECTIONS = [
    Section("EMC", [
        text("VERSION"),  # 1.1 for LinuxCNC 2.9's joints/axes layout
        text("MACHINE", ""),
        integer("DEBUG", 0, low=0),  # a bitmask, often written in hex
        path("NML_FILE"),  # default: the project's configs/common/cnc.nml
        text("RS274NGC_STARTUP_CODE"),  # the old place of [RS274NGC]RS274NGC_STARTUP_CODE
    ]),
    Section("DISPLAY", [
        text("DISPLAY"),
        real("CYCLE_TIME", low=0),  # seconds, or milliseconds for some displays
        Key("POSITION_OFFSET", choice("RELATIVE", "MACHINE"), "RELATIVE"),
        Key("POSITION_FEEDBACK", choice("ACTUAL", "COMMANDED"), "ACTUAL"),
        path("PROGRAM_PREFIX"),
        real("MAX_FEED_OVERRIDE", 1.0, above=0),  # 1.2 allows 120 %
        real("MAX_RAPID_OVERRIDE", low=0),
        real("MIN_SPINDLE_OVERRIDE", low=0),
        real("MAX_SPINDLE_OVERRIDE", low=0),
        real("MIN_SPINDLE_0_OVERRIDE", low=0),
        real("MAX_SPINDLE_0_OVERRIDE", low=0),
        real("DEFAULT_LINEAR_VELOCITY", low=0),  # jog speeds, units per second
        real("MIN_LINEAR_VELOCITY", low=0),
        real("MAX_LINEAR_VELOCITY", low=0),
        real("DEFAULT_ANGULAR_VELOCITY", low=0),
        real("MIN_ANGULAR_VELOCITY", low=0),
        real("MAX_ANGULAR_VELOCITY", low=0),
        real("DEFAULT_SPINDLE_SPEED", low=0),
        real("DEFAULT_SPINDLE_0_SPEED", low=0),
        real("MIN_SPINDLE_0_SPEED", low=0),
        real("MAX_SPINDLE_0_SPEED", low=0),
        real("SPINDLE_INCREMENT", low=0),
    ], is_open=True),
    Section("FILTER", [text("PROGRAM_EXTENSION", repeat=True)], is_open=True),
    Section("RS274NGC", [
        path("PARAMETER_FILE", "rs274ngc.var"),
        text("RS274NGC_STARTUP_CODE"),
        text("SUBROUTINE_PATH"),  # folders separated by ':'
        text("USER_M_PATH"),
        real("ORIENT_OFFSET", 0.0),
        real("CENTER_ARC_RADIUS_TOLERANCE_INCH", 0.00005, low=0.00004, high=0.00005),
        real("CENTER_ARC_RADIUS_TOLERANCE_MM", 0.00127, low=0.001, high=0.00127),
        flag("INI_VARS", True),
        flag("HAL_PIN_VARS", True),
        flag("RETAIN_G43"),
        flag("OWORD_NARGS"),
        flag("NO_DOWNCASE_OWORD"),
        flag("OWORD_WARNONLY"),
        flag("DISABLE_G92_PERSISTENCE"),
        flag("DISABLE_FANUC_STYLE_SUB"),
        integer("FEATURES", 0, low=0),  # the older bitmask of the flags above
        integer("LOG_LEVEL", 0, low=0),
        path("LOG_FILE"),
        text("REMAP", repeat=True),
        text("ON_ABORT_COMMAND"),
        text("WRITABLE_DIRS"),  # ours: where (LOGOPEN) and (PROBEOPEN) may write, ':' between
        text("T_COMMAND"),
        text("M6_COMMAND"),
        text("M61_COMMAND"),
        integer("USER_DEFINED_FUNCTION_MAX_DIRS", low=1),
    ]),
    Section("PYTHON", [
        text("PATH_PREPEND", repeat=True),
        text("PATH_APPEND", repeat=True),
        text("TOPLEVEL"),
        integer("LOG_LEVEL", 0, low=0),
        flag("RELOAD_ON_CHANGE"),
        flag("PYTHON_TASK"),
    ], is_open=True),
    Section("EMCMOT", [
        text("EMCMOT"),
        text("HOMEMOD"),
        integer("BASE_PERIOD", 0, low=0),  # nanoseconds
        integer("SERVO_PERIOD", 1_000_000, above=0),
        integer("TRAJ_PERIOD", low=0),
        real("COMM_TIMEOUT", 1.0, above=0),
        real("COMM_WAIT", low=0),
        text("SHMEM_KEY"),
        real("HEARTBEAT_TIMEOUT", 0.5, above=0, high=60),  # ours: motion's (motion/safety.py)
    ]),
    Section("TASK", [
        text("TASK"),
        real("CYCLE_TIME", 0.010, above=0, high=1.0),  # seconds; <= 0 made LinuxCNC spin
        integer("INTERP_MAX_LEN", 1000, above=0),
        integer("MDI_QUEUED_COMMANDS", 10, above=0),
        text("IO_ERROR"),
        real("HEARTBEAT_TIMEOUT", 1.0, above=0, high=60),  # ours: task's (nml/safety.py)
        real("INTERP_TIMEOUT", 10.0, low=0),  # ours: seconds without motion (0: never)
    ]),
    Section("HAL", [
        text("HALFILE", repeat=True),
        text("HALCMD", repeat=True),
        text("POSTGUI_HALFILE", repeat=True),
        text("POSTGUI_HALCMD", repeat=True),
        text("POSTTASK_HALFILE", repeat=True),
        text("SHUTDOWN"),
        text("HALUI"),
        text("TWOPASS"),
    ]),
    Section("HALUI", [
        Key("MDI_COMMAND", TEXT, max_count=MAX_MDI_COMMANDS, max_bytes=MDI_COMMAND_BYTES),
        real("CYCLE_TIME", 0.02, above=0, high=1.0),  # ours: LinuxCNC's halui polls every 20 ms
        real("HEARTBEAT_TIMEOUT", 1.0, above=0, high=60),  # ours (nml/safety.py)
    ]),
    Section("APPLICATIONS", [real("DELAY", 0.0, low=0), text("APP", repeat=True)], is_open=True),
    Section("TRAJ", [
        Key("COORDINATES", COORDINATES, "XYZ"),
        integer("SPINDLES", 1, low=1, high=MAX_SPINDLES),
        Key("LINEAR_UNITS", LINEAR_UNITS, required=True),
        Key("ANGULAR_UNITS", ANGULAR_UNITS, required=True),
        real("DEFAULT_LINEAR_VELOCITY", 1.0, low=0),
        real("MAX_LINEAR_VELOCITY", HUGE, above=0),
        real("DEFAULT_LINEAR_ACCELERATION", HUGE, above=0),
        real("MAX_LINEAR_ACCELERATION", HUGE, above=0),
        real("DEFAULT_ANGULAR_VELOCITY", low=0),
        real("MAX_ANGULAR_VELOCITY", low=0),
        real("DEFAULT_ANGULAR_ACCELERATION", above=0),
        real("MAX_ANGULAR_ACCELERATION", above=0),
        path("POSITION_FILE"),
        flag("NO_FORCE_HOMING"),
        Key("HOME", _Numbers(tuple(range(1, 10)))),  # world home, X Y Z A B C U V W
        text("TPMOD"),
        flag("NO_PROBE_JOG_ERROR"),
        flag("NO_PROBE_HOME_ERROR"),
        flag("ARC_BLEND_ENABLE", True),
        flag("ARC_BLEND_FALLBACK_ENABLE"),
        integer("ARC_BLEND_OPTIMIZATION_DEPTH", 50, low=0),
        integer("ARC_BLEND_GAP_CYCLES", 4, low=0),
        real("ARC_BLEND_RAMP_FREQ", 100.0, above=0),
        real("ARC_BLEND_KINK_RATIO", 0.1, low=0),
        real("ARC_BLEND_SMOOTHING_THRESHOLD", low=0),
    ]),
    Section("KINS", [
        integer("JOINTS", required=True, low=1, high=MAX_JOINTS),
        text("KINEMATICS"),
    ]),
    Section("AXIS_<L>", [
        Key("TYPE", JOINT_TYPE),  # for displays: X Y Z U V W linear, A B C angular
        real("MIN_LIMIT", -HUGE),
        real("MAX_LIMIT", HUGE),
        real("MAX_VELOCITY", 1.0, above=0),
        real("MAX_ACCELERATION", 1.0, above=0),
        flag("WRAPPED_ROTARY"),
        integer("LOCKING_INDEXER_JOINT", -1, low=-1, below=MAX_JOINTS),
        real("OFFSET_AV_RATIO", 0.0, low=0, high=0.9),
        real("HOME", 0.0),  # older displays
    ]),
    Section("JOINT_<n>", [
        Key("TYPE", JOINT_TYPE, "LINEAR"),
        real("UNITS", above=0),
        real("MIN_LIMIT", -HUGE),
        real("MAX_LIMIT", HUGE),
        real("MAX_VELOCITY", 1.0, above=0),
        real("MAX_ACCELERATION", 1.0, above=0),
        real("BACKLASH", 0.0, low=0),
        path("COMP_FILE"),
        integer("COMP_FILE_TYPE", 0, low=0, high=1),
        real("FERROR", 1.0, above=0),
        real("MIN_FERROR", SameAs("FERROR"), above=0),
        flag("LOCKING_INDEXER"),
        real("HOME", 0.0),
        real("HOME_OFFSET", 0.0),
        real("HOME_SEARCH_VEL", 0.0),
        real("HOME_LATCH_VEL", 0.0),
        real("HOME_FINAL_VEL", -1.0),  # -1: the joint's MAX_VELOCITY
        flag("HOME_USE_INDEX"),
        flag("HOME_INDEX_NO_ENCODER_RESET"),
        flag("HOME_IGNORE_LIMITS"),
        flag("HOME_IS_SHARED"),
        integer("HOME_ABSOLUTE_ENCODER", 0, low=0, high=2),
        integer("HOME_SEQUENCE", None, low=-MAX_JOINTS, high=MAX_JOINTS),  # None: not in home-all
        flag("VOLATILE_HOME"),
        *hal_only("P", "I", "D", "FF0", "FF1", "FF2", "BIAS", "DEADBAND", "MAX_OUTPUT",
                  "OUTPUT_SCALE", "OUTPUT_OFFSET", "INPUT_SCALE", "ENCODER_SCALE", "SCALE",
                  "STEP_SCALE", "STEPGEN_MAXACCEL", "STEPGEN_MAXVEL"),
    ]),
    Section("SPINDLE_<n>", [
        real("MAX_FORWARD_VELOCITY", HUGE, low=0),  # rpm (LinuxCNC: no limit)
        real("MIN_FORWARD_VELOCITY", 0.0, low=0),
        real("MAX_REVERSE_VELOCITY", SameAs("MAX_FORWARD_VELOCITY"), low=0),
        real("MIN_REVERSE_VELOCITY", SameAs("MIN_FORWARD_VELOCITY"), low=0),
        real("INCREMENT", 100.0, above=0),
        real("HOME_SEARCH_VELOCITY", 0.0),
        integer("HOME_SEQUENCE", 0),
    ]),
    Section("EMCIO", [
        text("EMCIO"),
        real("CYCLE_TIME", 0.100, above=0, high=1.0),
        path("TOOL_TABLE", "tool.tbl"),
        text("DB_PROGRAM"),
        Key("TOOL_CHANGE_POSITION", _Numbers((3, 6, 9))),  # X Y Z [A B C [U V W]]
        flag("TOOL_CHANGE_WITH_SPINDLE_ON"),
        flag("TOOL_CHANGE_QUILL_UP"),
        flag("TOOL_CHANGE_AT_G30"),
        flag("RANDOM_TOOLCHANGER"),
        real("HEARTBEAT_TIMEOUT", 1.0, above=0, high=60),  # ours (nml/safety.py)
    ]),
    # ours: the bridges (cnc/bridges), each a process the launcher starts when ENABLE = 1.
    # BROKER, USERNAME, PASSWORD and DRYRUN are also what LinuxCNC's mqtt-publisher
    # examples substitute into their loadusr line.
    Section("MQTT", [
        flag("ENABLE"),  # the machine status publisher
        text("BROKER", "localhost"),
        integer("PORT", 1883, low=1, high=65535),
        text("USERNAME"),
        text("PASSWORD"),
        text("DRYRUN"),  # mqtt-publisher's --dryrun, for HAL files
        text("TOPIC_PREFIX", "cnc"),  # topics: <TOPIC_PREFIX>/<machine name>/...
        text("MACHINE_NAME"),  # default: [EMC]MACHINE, else the instance
        real("CYCLE_TIME", 0.1, above=0, high=10),  # seconds between status polls
        flag("COMMANDS"),  # accept commands on <root>/command (an authenticating broker only)
    ]),
    Section("OPCUA", [
        flag("ENABLE"),  # the OPC UA server
        text("HOST", "127.0.0.1"),  # 0.0.0.0: every interface
        integer("PORT", 4840, low=1, high=65535),
        text("MACHINE_NAME"),  # default: [EMC]MACHINE, else the instance
        text("USERNAME"),  # the one user who may write (overrides); none: no writes
        text("PASSWORD"),
        flag("ALLOW_ANONYMOUS", True),  # anonymous sessions may read, never write
        text("SECURITY", "None Basic256Sha256_Sign Basic256Sha256_SignAndEncrypt"),
        path("CERTIFICATE"),  # for the signed policies; none: made once, next to the INI
        path("PRIVATE_KEY"),
        real("CYCLE_TIME", 0.1, above=0, high=10),
    ]),
]  # fmt: skip
SCHEMA: dict[str, Section] = {section.name: section for section in _SECTIONS}

# the numbered sections (their numbers as nml.emc bounds them) -> their schema
_NUMBERED = {f"JOINT_{n}": SCHEMA["JOINT_<n>"] for n in range(MAX_JOINTS)}
_NUMBERED |= {f"SPINDLE_{n}": SCHEMA["SPINDLE_<n>"] for n in range(MAX_SPINDLES)}
_NUMBERED |= {f"AXIS_{letter}": SCHEMA["AXIS_<L>"] for letter in AXIS_LETTERS}


def schema_section(name: str) -> Section | None:
    """The schema of section ``name`` (``JOINT_3`` -> ``JOINT_<n>``), or None (a custom one)."""
    return SCHEMA.get(name) or _NUMBERED.get(name)


# --------------------------------------------------------------------------- the result
class ConfigError(IniError):
    """Every problem found, one ``file:line: cause`` per line of ``str()``."""

    def __init__(self, errors: list[IniError]) -> None:
        first = errors[0]
        super().__init__(first.file, first.line, first.cause)
        self.errors = errors
        self.args = ("\n".join(str(error) for error in errors),)

    def __str__(self) -> str:
        return self.args[0]


class MachineConfig:
    """An INI file checked against ``SCHEMA``; ``value()`` gives typed values or defaults."""

    def __init__(self, ini: IniFile) -> None:
        self.ini = ini
        self.path = ini.path
        self.folder = Path(os.path.abspath(ini.path)).parent  # not through symlinks
        self.warnings: list[str] = list(ini.warnings)
        self._values: dict[str, dict[str, Any]] = {}
        self._lists: dict[tuple[str, str], list[Any]] = {}  # values of repeatable keys
        self._ended: dict[tuple[str, str], IniValue] = {}  # the empty line ending such a list

    # ------------------------------------------------------------------ values
    def value(self, section: str, key: str) -> Any:
        """The typed value of ``[section]key``, or its default (None if it has none)."""
        values = self._values.get(section)
        if values is None:
            values = self._values[section] = self._defaults(section)
        return values[key]

    def values(self, section: str, key: str) -> list[Any]:
        """Every value of a repeatable key, in file order."""
        return list(self._lists.get((section, key), []))

    def entry(self, section: str, key: str) -> IniValue | None:
        """Where ``[section]key`` is written (None: not written, the default applies)."""
        return self.ini.entry(section, key)

    def is_set(self, section: str, key: str) -> bool:
        """``[section]key`` is written with a value (not left to its default)."""
        found = self.ini.entry(section, key)
        return found is not None and found.value != ""

    def resolve(self, name: str) -> Path:
        """A file named in the INI file: ``~`` expanded, relative to the INI file's folder
        (as LinuxCNC, whose processes run there; the INI path is not resolved through
        symlinks, so a linked INI file finds the files beside the link)."""
        found = Path(os.path.expanduser(name))
        return found if found.is_absolute() else self.folder / found

    def file(self, section: str, key: str) -> Path | None:
        """The file ``[section]key`` names (or its default), resolved; None if none."""
        name = self.value(section, key)
        return None if not name else self.resolve(name)

    @property
    def joints(self) -> int:
        return self.value("KINS", "JOINTS")

    @property
    def coordinates(self) -> str:
        """[TRAJ]COORDINATES as upper-case letters, repeats kept (``XYYZ``)."""
        return self.value("TRAJ", "COORDINATES")

    @property
    def axes(self) -> str:
        """The distinct axis letters of COORDINATES, in XYZABCUVW order."""
        return "".join(letter for letter in AXIS_LETTERS if letter in self.coordinates)

    # ------------------------------------------------------------------ reading
    def _read_section(
        self,
        name: str,
        schema: Section,
        errors: list[IniError],
        used: set[tuple[str, str]],
        is_machine: bool,
    ) -> None:
        values = self._defaults(name)
        seen: dict[str, IniValue] = {}
        for key_name, entry in self.ini.section_entries(name):
            key = schema.keys.get(key_name)
            if key is None:
                if not schema.is_open and (name, key_name) not in used:
                    self.warnings.append(
                        f"{entry.where}: [{name}]{key_name} is unknown: the controller does "
                        "not read it and no HAL file uses it (a typo?)"
                    )
                continue
            first = seen.setdefault(key_name, entry)
            if key.is_repeatable:
                self._read_repeat(name, key, entry, errors)
            elif first is not entry:
                self.warnings.append(
                    f"{entry.where}: [{name}]{key_name} repeated: the first ({first.where}) is used"
                )
            elif entry.value:  # KEY = (empty) is not set, as in LinuxCNC
                value = _parse(name, key, entry, errors)
                if value is not None:
                    values[key_name] = value
        for key_name, key in schema.keys.items():
            listed = self._lists.get((name, key_name))
            if listed:
                values[key_name] = listed[0]
            if isinstance(key.default, SameAs) and key_name not in seen:
                values[key_name] = values[key.default.key]
            is_written = key_name in seen and seen[key_name].value != ""  # (a bad value is told)
            if key.is_required and is_machine and not is_written:
                header = self.ini.header(name) or IniValue("", self.ini.path, 0)
                errors.append(
                    header.error(f"[{name}]{key_name} is missing (required: {key.allowed})")
                )
        self._values[name] = values

    def _read_repeat(self, section: str, key: Key, entry: IniValue, errors: list[IniError]) -> None:
        """One line of a key that may repeat. LinuxCNC reads such a list up to its first
        empty value, so a value after an empty one, silently ignored there, is an error."""
        listed = self._lists.setdefault((section, key.name), [])
        ended = self._ended.get((section, key.name))
        if ended is not None:
            if entry.value and ended.value == "":
                errors.append(
                    entry.error(
                        f"[{section}]{key.name} after an empty one ({ended.where}), where "
                        "LinuxCNC stops reading them: remove the empty line"
                    )
                )
                self._ended[(section, key.name)] = entry  # said once
            return
        if not entry.value:
            self._ended[(section, key.name)] = entry
            return
        value = _parse(section, key, entry, errors)
        if value is None:
            return
        listed.append(value)
        if key.max_count is not None and len(listed) == key.max_count + 1:
            errors.append(entry.error(f"[{section}]{key.name}: more than {key.max_count} lines"))

    def _defaults(self, section: str) -> dict[str, Any]:
        schema = schema_section(section)
        if schema is None:
            raise KeyError(f"[{section}] is not a section of the schema")
        values = {name: key.default for name, key in schema.keys.items()}
        for name, default in values.items():
            if isinstance(default, SameAs):
                values[name] = values[default.key]
        return values


# --------------------------------------------------------------------------- reading
def read_config(
    ini: IniFile, *, hal_keys: set[tuple[str, str]] | None = None, is_machine: bool = True
) -> MachineConfig:
    """Check ``ini`` against the schema; ConfigError lists every bad value.

    ``is_machine``: the file must describe a whole machine (its required keys, one
    [JOINT_n] per joint); False checks only the values written (an INI file for
    ``cnc rs274 -i``).

    ``hal_keys`` are the ``(section, key)`` pairs the HAL files use (default: found by
    reading the [HAL] files named in the INI file): such keys are never warned about.
    """
    config = MachineConfig(ini)
    errors: list[IniError] = []
    used = _hal_references(config) if hal_keys is None else hal_keys
    for name in ini.sections():
        schema = schema_section(name)
        if schema is not None:
            config._read_section(name, schema, errors, used, is_machine)
    for name in ("TRAJ", "KINS", "EMCIO", "TASK", "EMCMOT", "RS274NGC", "EMC", "HALUI"):
        if not ini.has_section(name):
            config._read_section(name, SCHEMA[name], errors, used, is_machine)
    _check_layout(config, errors)
    if not errors and is_machine:  # checks across keys read typed values
        for check in _CHECKS:
            check(config, errors)
    if errors:
        raise ConfigError(errors)
    return config


def load_config(path: str | os.PathLike[str]) -> MachineConfig:
    """Read and check the INI file at ``path`` (IniError if unreadable, ConfigError if bad)."""
    return read_config(IniFile.load(path))


def _parse(section: str, key: Key, entry: IniValue, errors: list[IniError]) -> Any:
    shown = entry.value if len(entry.value) <= 60 else entry.value[:57] + "..."
    try:
        value = key.kind.parse(entry.value)
        problem = key.check(value) if key.kind.has_bounds else None
    except ValueError as exc:
        problem = str(exc)
    if problem is None and key.max_bytes is not None and len(entry.value.encode()) > key.max_bytes:
        problem = f"is longer than {key.max_bytes} bytes"
    if problem is None:
        return value
    cause = f"[{section}]{key.name} = '{shown}' {problem}; allowed: {key.allowed}"
    errors.append(entry.error(cause))
    return None


# --------------------------------------------------------------------------- checks across keys
def _check_joints(config: MachineConfig, errors: list[IniError]) -> None:
    """[KINS]JOINTS = n wants [JOINT_0] .. [JOINT_n-1]. LinuxCNC silently runs a joint
    without its section on defaults (1 unit/s, no soft limits, not homed by home-all): so
    do we, with a warning saying so (none for a trivkins joint whose axis COORDINATES does
    not name, a lathe's Y: it is not used)."""
    ini = config.ini
    count = config.joints
    where = ini.entry("KINS", "JOINTS")
    assert where is not None  # required
    trivial = _trivkins_axes(config)
    missing = []
    for n in range(count):
        if ini.has_section(f"JOINT_{n}"):
            continue
        if trivial is not None and n < len(trivial) and trivial[n] not in config.coordinates:
            config.warnings.append(
                f"{where.where}: there is no [JOINT_{n}]: trivkins joint {n} is axis "
                f"{trivial[n]}, which [TRAJ]COORDINATES does not name, so it is not used"
            )
            continue
        missing.append(f"[JOINT_{n}]")
    if missing:
        config.warnings.append(
            f"{where.where}: [KINS]JOINTS = {count} but {', '.join(missing)} "
            f"{'is' if len(missing) == 1 else 'are'} missing: LinuxCNC's defaults are used "
            "(MAX_VELOCITY 1, MAX_ACCELERATION 1, no soft limits, HOME 0, no HOME_SEQUENCE)"
        )
    for n in range(count, MAX_JOINTS):
        header = ini.header(f"JOINT_{n}")
        if header is not None:
            config.warnings.append(
                f"{header.where}: [JOINT_{n}] is not used: [KINS]JOINTS = {count}"
            )


def _trivkins_axes(config: MachineConfig) -> str | None:
    """The axis letter of each joint when [KINS]KINEMATICS is trivkins (its
    ``coordinates=``, by default one joint per axis in XYZABCUVW order); None otherwise."""
    words = (config.value("KINS", "KINEMATICS") or "").split()
    if not words or words[0] != "trivkins":
        return None
    for word in words[1:]:
        name, _, value = word.partition("=")
        if name == "coordinates":
            return value.upper()
    return AXIS_LETTERS


def _check_axes(config: MachineConfig, errors: list[IniError]) -> None:
    """An axis of COORDINATES without its [AXIS_L] section runs on LinuxCNC's defaults (1
    unit/s, no soft limits), as some sample configs intend: a warning. A section of an axis
    COORDINATES does not name is not used: a warning."""
    ini = config.ini
    entry = ini.entry("TRAJ", "COORDINATES") or ini.header("TRAJ")
    where = entry.where if entry is not None else ini.path
    for letter in config.axes:
        if not ini.has_section(f"AXIS_{letter}"):
            config.warnings.append(
                f"{where}: [TRAJ]COORDINATES names {letter} but there is no [AXIS_{letter}]: "
                f"MAX_VELOCITY and MAX_ACCELERATION are 1, there are no soft limits"
            )
    for letter in AXIS_LETTERS:
        header = ini.header(f"AXIS_{letter}")
        if header is not None and letter not in config.axes:
            config.warnings.append(
                f"{header.where}: [AXIS_{letter}] is not used: [TRAJ]"
                f"COORDINATES = {config.coordinates}"
            )


def _check_layout(config: MachineConfig, errors: list[IniError]) -> None:
    """An INI file from before LinuxCNC 2.8 ([AXIS_0] sections, no [KINS]) is converted by
    LinuxCNC's launcher (update_ini) before it runs; here it is refused, saying so."""
    ini = config.ini
    old = [name for name in ini.sections() if re.fullmatch(r"AXIS_[0-8]", name)]
    if old:
        header = ini.header(old[0])
        assert header is not None
        version = ini.find("EMC", "VERSION") or "(none)"
        errors.append(
            header.error(
                f"[{old[0]}]: an INI file in LinuxCNC's layout before 2.8 ([EMC]VERSION = "
                f"{version}, not 1.1), which LinuxCNC converts with update_ini before running "
                f"it: convert it (update_ini -d {ini.path}) and start the converted file"
            )
        )


def _check_limits(config: MachineConfig, errors: list[IniError]) -> None:
    """MIN_LIMIT <= MAX_LIMIT for each joint and axis; the spindle speeds likewise."""
    pairs = [(f"JOINT_{n}", "MIN_LIMIT", "MAX_LIMIT") for n in range(config.joints)]
    pairs += [(f"AXIS_{letter}", "MIN_LIMIT", "MAX_LIMIT") for letter in config.axes]
    for n in range(config.value("TRAJ", "SPINDLES")):
        pairs += [
            (f"SPINDLE_{n}", f"MIN_{way}_VELOCITY", f"MAX_{way}_VELOCITY")
            for way in ("FORWARD", "REVERSE")
        ]
    for section, low_key, high_key in pairs:
        if not config.ini.has_section(section):
            continue
        low, high = config.value(section, low_key), config.value(section, high_key)
        if low > high:
            where = config.entry(section, low_key) or config.entry(section, high_key)
            assert where is not None
            errors.append(
                where.error(f"[{section}]{low_key} = {low:g} is above {high_key} = {high:g}")
            )


def _check_homing(config: MachineConfig, errors: list[IniError]) -> None:
    """What LinuxCNC's homing refuses only when the joint is homed (HOME_SEARCH_VEL needs a
    HOME_LATCH_VEL; a HOME_LATCH_VEL alone needs HOME_USE_INDEX), refused at start-up."""
    for n in range(config.joints):
        section = f"JOINT_{n}"
        search = config.value(section, "HOME_SEARCH_VEL")
        latch = config.value(section, "HOME_LATCH_VEL")
        if search != 0 and latch == 0:
            where = config.entry(section, "HOME_SEARCH_VEL")
            assert where is not None
            errors.append(
                where.error(
                    f"[{section}]HOME_SEARCH_VEL = {search:g} needs a non-zero HOME_LATCH_VEL"
                )
            )
        elif search == 0 and latch != 0 and not config.value(section, "HOME_USE_INDEX"):
            where = config.entry(section, "HOME_LATCH_VEL")
            assert where is not None
            errors.append(
                where.error(
                    f"[{section}]HOME_LATCH_VEL = {latch:g} without "
                    "HOME_SEARCH_VEL needs HOME_USE_INDEX = YES"
                )
            )


def _check_spindles(config: MachineConfig, errors: list[IniError]) -> None:
    count = config.value("TRAJ", "SPINDLES")
    for n in range(count, MAX_SPINDLES):
        header = config.ini.header(f"SPINDLE_{n}")
        if header is not None:
            config.warnings.append(
                f"{header.where}: [SPINDLE_{n}] is not used: [TRAJ]SPINDLES = {count}"
            )


_CHECKS: list[Callable[[MachineConfig, list[IniError]], None]] = [
    _check_joints,
    _check_axes,
    _check_limits,
    _check_homing,
    _check_spindles,
]


# --------------------------------------------------------------------------- HAL references
_HAL_REFERENCE = re.compile(
    r"\[([A-Za-z0-9_]+)\]\s*\(?([A-Za-z0-9_]+)|\$::([A-Za-z0-9_]+)\(([A-Za-z0-9_]+)\)"
)


def _hal_references(config: MachineConfig) -> set[tuple[str, str]]:
    """``[SECTION]KEY`` (halcmd) and ``$::SECTION(KEY)`` (Tcl) in the HAL files the INI file
    names (those found in its folder; LIB: files only use standard keys)."""
    found: set[tuple[str, str]] = set()
    ini = config.ini
    names = [*ini.findall("HAL", "HALFILE"), *ini.findall("HAL", "POSTGUI_HALFILE")]
    names += [*ini.findall("HAL", "POSTTASK_HALFILE"), *ini.findall("HAL", "SHUTDOWN")]
    names += ini.findall("HAL", "HALCMD") + ini.findall("HAL", "POSTGUI_HALCMD")
    for name in names:
        words = name.split()
        candidate = config.resolve(words[0]) if words else None
        try:
            source = candidate.read_text(errors="replace") if candidate else name
        except OSError:
            source = name  # a HALCMD line, or a file found elsewhere (LIB:)
        for match in _HAL_REFERENCE.finditer(source):
            section = match.group(1) or match.group(3)
            key = match.group(2) or match.group(4)
            found.add((section, key))
    return found


# --------------------------------------------------------------------------- start-up check
def check_machine(path: str | os.PathLike[str]) -> MachineConfig:
    """What the launcher runs before it starts anything: the INI file against the schema,
    then the tool table and the parameter file it names. IniError (a ConfigError listing
    every problem) if the machine must not start; warnings are in ``config.warnings``."""
    config = load_config(path)
    problems = check_tool_table(config) + check_parameter_file(config)
    if problems:
        raise ConfigError(problems)
    return config


def check_tool_table(config: MachineConfig) -> list[IniError]:
    """The tool table ([EMCIO]TOOL_TABLE) read as iocontrol reads it; a problem is
    ``file:line: cause``; lines LinuxCNC skips or accepts oddly are warnings. A missing
    file is none (iocontrol starts with no tools, as LinuxCNC's); nor is a table when
    [EMCIO]DB_PROGRAM supplies the tools."""
    from iocontrol.tooltable import ToolTable, ToolTableError

    table = config.file("EMCIO", "TOOL_TABLE")
    if table is None or not table.exists() or config.value("EMCIO", "DB_PROGRAM"):
        return []
    tools = ToolTable(config.value("EMCIO", "RANDOM_TOOLCHANGER"))
    try:
        tools.load(table)
    except ToolTableError as exc:
        return [IniError(exc.file, exc.line, exc.cause)]
    except OSError as exc:
        return [IniError(str(table), 0, f"cannot read the tool table: {exc.strerror}")]
    config.warnings += [str(warning) for warning in tools.warnings]  # LinuxCNC reads those
    if tools.has_unreadable_lines:
        config.warnings.append(f"{table}: the tool table will not be saved over (lines skipped)")
    return []


def check_parameter_file(config: MachineConfig) -> list[IniError]:
    """The parameter file ([RS274NGC]PARAMETER_FILE) read as task reads it; a problem is
    ``file:line: cause``. A missing file is none (task writes a new one, as LinuxCNC)."""
    from task.varfile import VarFileError, read_var_file

    var_file = config.file("RS274NGC", "PARAMETER_FILE")
    if var_file is None or not var_file.exists():
        return []
    try:
        read_var_file(var_file)
    except VarFileError as exc:
        return [IniError(exc.file, exc.line, exc.cause)]
    return []


def io_program(ini: IniFile) -> str:
    """The I/O program the launcher starts, as LinuxCNC's: ``[IO]IO``, else
    ``[EMCIO]EMCIO``, else ``io``; a key present but empty means none ("": the machine runs
    without iocontrol, e.g. LinuxCNC's orphans/axis_noio.ini)."""
    for section, key in (("IO", "IO"), ("EMCIO", "EMCIO")):
        entry = ini.entry(section, key)
        if entry is not None:
            return entry.value.strip()
    return "io"
