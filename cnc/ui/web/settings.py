"""What the web UI takes from the INI file: [DISPLAY], [MDI_COMMAND_LIST], [FILTER], the
spindle's speed range ([SPINDLE_0]), the tool setter ([TOOLSENSOR], as gmoccapy has it).
([DISPLAY] MESSAGE_* and MULTIMESSAGE_* are read by messages.py.)

Keys of our own, in [DISPLAY]:

- ``WEB_ALLOWED_HOSTS = cnc.local shop-pc``: host names (besides the bound address and
  ``localhost``) by which the page may be reached: any other Host header is refused, so a
  web page elsewhere cannot reach the machine by DNS rebinding.
- ``JOB_HISTORY_FILE = job_history.json``: where the history of program runs is kept
  (relative to the INI's folder, as MDI_HISTORY_FILE; the default is that name).

``Settings.load(path)`` reads every value once at start; ``Settings()`` is a machine without
an INI file (defaults only). ``page_config()`` is the part the page needs, as JSON.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cnc
from cnc.ini import IniFile
from cnc.inischema import MachineConfig, read_config
from cnc.ui.formatting import AXIS_LETTERS
from cnc.ui.web.messages import MessagePin, read_message_pins

DEFAULT_CYCLE_TIME_S = 0.1
DEFAULT_INCREMENTS = "continuous, 10 mm, 1 mm, 0.1 mm, 0.01 mm"
DEFAULT_ANGULAR_INCREMENTS = "continuous, 90, 45, 15, 1, 0.1"
DEFAULT_EXTENSIONS = (".ngc", ".nc", ".tap")
DEFAULT_JOB_HISTORY_FILE = "job_history.json"
MIN_JOG_FRACTION = 0.01  # the jog speed slider's lowest value, of its highest, at least
MM_PER_INCH = 25.4
_INCREMENT = re.compile(r"\s*([0-9.]+)\s*(mm|inch|in|cm|um|mil)?\s*", re.IGNORECASE)
_UNIT_MM = {"mm": 1.0, "cm": 10.0, "um": 0.001, "inch": MM_PER_INCH, "in": MM_PER_INCH}
_UNIT_MM["mil"] = MM_PER_INCH / 1000


def cycle_time(value: str | None) -> float:
    """[DISPLAY]CYCLE_TIME in seconds: values >= 1 are milliseconds, < 1 seconds (GUI-007)."""
    try:
        number = float(value) if value else DEFAULT_CYCLE_TIME_S
    except ValueError:
        return DEFAULT_CYCLE_TIME_S
    if number <= 0:
        return DEFAULT_CYCLE_TIME_S
    return number / 1000.0 if number >= 1 else number


def increments(text: str | None, units_per_mm: float) -> list[dict[str, Any]]:
    """[DISPLAY]INCREMENTS as [{"label": "1 mm", "distance": 1.0 (machine units)}, ...],
    "continuous" (distance 0) always first (GUI-009); unreadable entries are skipped."""
    found = [{"label": "continuous", "distance": 0.0}]
    for word in (text or DEFAULT_INCREMENTS).split(","):
        word = word.strip()
        match = _INCREMENT.fullmatch(word)
        if word.lower() == "continuous" or match is None:
            continue
        value, unit = float(match.group(1)), (match.group(2) or "").lower()
        distance = value * _UNIT_MM[unit] * units_per_mm if unit else value
        if distance > 0:
            found.append({"label": word, "distance": distance})
    return found


def angular_increments(text: str | None) -> list[dict[str, Any]]:
    """[DISPLAY]ANGULAR_INCREMENTS (degrees) as increments(), "continuous" first (GUI-009)."""
    found = [{"label": "continuous", "distance": 0.0}]
    for word in (text or DEFAULT_ANGULAR_INCREMENTS).split(","):
        word = word.strip()
        try:
            distance = float(word.removesuffix("deg").removesuffix("degree").strip())
        except ValueError:
            continue  # "continuous", or unreadable
        if distance > 0:
            found.append(
                {"label": f"{word}°" if word[-1].isdigit() else word, "distance": distance}
            )
    return found


def override_percent(value: str | None, default: float) -> float:
    """An override limit in percent: "120" is percent, "1.2" a factor (LinuxCNC's INIs use
    both)."""
    try:
        number = float(value) if value else default
    except ValueError:
        return default
    return number if number > 10 else number * 100.0


def macros(values: list[str]) -> list[dict[str, str]]:
    """[MDI_COMMAND_LIST]MDI_COMMAND_MACRO<n> as [{"label", "commands"}] (GUI-014):
    "G0 Z25;X0 Y0, Goto\\nZero" -> commands "G0 Z25;X0 Y0", label "Goto\\nZero"."""
    found = []
    for value in values:
        commands, _, label = value.partition(",")
        label = label.strip().replace("\\n", "\n") or commands.strip()
        found.append({"label": label, "commands": commands.strip()})
    return found


def ini_path(value: str | None, folder: Path) -> Path | None:
    """A file path key (GUI-008): relative to the INI's folder, ~ expanded, or absolute."""
    if not value:
        return None
    return folder / os.path.expanduser(value)


@dataclass
class Settings:
    ini_file: str | None = None
    machine: str = ""
    title: str = ""  # [DISPLAY]TITLE (GUI-006)
    cycle_time_s: float = DEFAULT_CYCLE_TIME_S
    units_per_mm: float = 1.0
    axes: str = "XYZ"
    increments: list[dict[str, Any]] = field(default_factory=lambda: increments(None, 1.0))
    angular_increments: list[dict[str, Any]] = field(
        default_factory=lambda: angular_increments(None)
    )
    jog_speed: dict[str, float] = field(
        default_factory=lambda: {"default": 600.0, "min": 0.0, "max": 3000.0}
    )
    angular_jog_speed: dict[str, float] = field(
        default_factory=lambda: {"default": 360.0, "min": 0.0, "max": 3600.0}
    )
    max_feed_override: float = 120.0
    max_rapid_override: float = 100.0
    min_spindle_override: float = 50.0
    max_spindle_override: float = 120.0
    spindle: dict[str, float] = field(
        default_factory=lambda: {"increment": 100.0, "default": 500.0, "min": 0.0, "max": 1e5,
                                 "max_reverse": 1e5}
    )  # fmt: skip
    spindle_limit_keys: dict[str, str] = field(default_factory=dict)  # "max": "[SPINDLE_0]..."
    is_lathe: bool = False  # [DISPLAY]MACHINE_TYPE_HINT = LATHE or LATHE = 1 (GUI-010)
    is_position_relative: bool = True
    is_position_actual: bool = True
    macros: list[dict[str, str]] = field(default_factory=list)
    program_prefix: Path | None = None
    extensions: tuple[str, ...] = DEFAULT_EXTENSIONS
    mdi_history_file: Path | None = None
    parameter_file: Path | None = None  # [RS274NGC]PARAMETER_FILE, for the preview
    tool_table: Path | None = None  # [EMCIO]TOOL_TABLE, for the preview and tool edits
    is_random_toolchanger: bool = False  # [EMCIO]RANDOM_TOOLCHANGER: pockets are indexes
    limits: dict[str, list[float]] = field(default_factory=dict)  # axis -> [min, max]
    filters: dict[str, str] = field(default_factory=dict)  # [FILTER] extension -> program
    message_pins: list[MessagePin] = field(default_factory=list)  # GUI-018/019
    allowed_hosts: tuple[str, ...] = ()  # [DISPLAY]WEB_ALLOWED_HOSTS, lower case
    job_history_file: Path | None = None  # [DISPLAY]JOB_HISTORY_FILE
    # [TOOLSENSOR] X Y Z (machine coordinates of the tool setter, where probing starts),
    # MAXPROBE (how far down it probes), SEARCH_VEL and PROBE_VEL (units per minute)
    tool_sensor: dict[str, float] | None = None
    problems: list[str] = field(default_factory=list)  # "file:line: cause", shown to pages

    @classmethod
    def load(cls, path: str) -> Settings:
        """The settings of the INI file at ``path``; ``cnc.error`` if it cannot be read,
        ``IniError`` for a bad value that cannot be ignored."""
        ini = cnc.ini(path)
        folder = Path(os.path.abspath(path)).parent  # not through symlinks, as LinuxCNC
        parsed = IniFile.load(path)
        config = read_config(parsed, is_machine=False)  # the machine's keys, typed and checked

        def display(key: str) -> str | None:
            return ini.find("DISPLAY", key)

        def number(key: str, default: float) -> float:
            try:
                return float(display(key) or default)
            except ValueError:
                return default

        units_per_mm = 1.0 if config.value("TRAJ", "LINEAR_UNITS") != "inch" else 1 / MM_PER_INCH
        coordinates = config.coordinates
        # [DISPLAY] jog velocities are in units per second; the page shows units per minute.
        default_speed = number("DEFAULT_LINEAR_VELOCITY", 10.0) * 60
        extensions = []
        for entry in ini.findall("FILTER", "PROGRAM_EXTENSION"):
            patterns = entry.split()[0] if entry.split() else ""
            extensions += [ext.strip().lower() for ext in patterns.split(",") if ext.strip()]
        prefix = ini_path(display("PROGRAM_PREFIX"), folder)
        message_pins, problems = read_message_pins(parsed)
        spindle, spindle_keys = _spindle(parsed)
        jog_max = number("MAX_LINEAR_VELOCITY", default_speed / 60 * 5) * 60
        angular_max = number("MAX_ANGULAR_VELOCITY", 60.0) * 60
        history = display("JOB_HISTORY_FILE") or DEFAULT_JOB_HISTORY_FILE
        return cls(
            ini_file=str(folder / Path(path).name),
            machine=ini.find("EMC", "MACHINE") or "",
            title=display("TITLE") or "",
            cycle_time_s=cycle_time(display("CYCLE_TIME")),
            units_per_mm=units_per_mm,
            axes="".join(dict.fromkeys(c for c in coordinates if c in AXIS_LETTERS)),
            increments=increments(display("INCREMENTS"), units_per_mm),
            angular_increments=angular_increments(display("ANGULAR_INCREMENTS")),
            jog_speed=_jog_range(default_speed, number("MIN_LINEAR_VELOCITY", 0.0) * 60, jog_max),
            angular_jog_speed=_jog_range(
                number("DEFAULT_ANGULAR_VELOCITY", 6.0) * 60,
                number("MIN_ANGULAR_VELOCITY", 0.0) * 60,
                angular_max,
            ),
            max_feed_override=override_percent(display("MAX_FEED_OVERRIDE"), 120.0),
            max_rapid_override=min(override_percent(display("MAX_RAPID_OVERRIDE"), 100.0), 100),
            min_spindle_override=override_percent(
                display("MIN_SPINDLE_0_OVERRIDE") or display("MIN_SPINDLE_OVERRIDE"), 50.0
            ),
            max_spindle_override=override_percent(
                display("MAX_SPINDLE_0_OVERRIDE") or display("MAX_SPINDLE_OVERRIDE"), 120.0
            ),
            spindle=spindle,
            spindle_limit_keys=spindle_keys,
            is_lathe=_is_lathe(display("MACHINE_TYPE_HINT"), display("LATHE")),
            is_position_relative=(display("POSITION_OFFSET") or "RELATIVE").upper() != "MACHINE",
            is_position_actual=(display("POSITION_FEEDBACK") or "ACTUAL").upper() != "COMMANDED",
            macros=macros(_numbered(ini, "MDI_COMMAND_LIST", "MDI_COMMAND_MACRO")),
            program_prefix=prefix if prefix is not None else folder,
            extensions=tuple(extensions) or DEFAULT_EXTENSIONS,
            mdi_history_file=ini_path(display("MDI_HISTORY_FILE"), folder),
            parameter_file=ini_path(ini.find("RS274NGC", "PARAMETER_FILE"), folder),
            tool_table=ini_path(ini.find("EMCIO", "TOOL_TABLE"), folder),
            is_random_toolchanger=config.value("EMCIO", "RANDOM_TOOLCHANGER"),
            limits=_limits(config),
            filters=_filters(parsed),
            message_pins=message_pins,
            problems=problems,
            allowed_hosts=tuple(
                word.lower()
                for word in (display("WEB_ALLOWED_HOSTS") or "").replace(",", " ").split()
            ),
            job_history_file=ini_path(history, folder),
            tool_sensor=_tool_sensor(parsed, problems),
        )

    def page_config(self) -> dict[str, Any]:
        """What the page shows and offers, sent once when it connects."""
        return {
            "machine": self.machine,
            "title": self.title or self.machine,
            "is_position_relative": self.is_position_relative,
            "axes": self.axes,
            "places": 3 if self.units_per_mm == 1.0 else 4,  # digits shown, as AXIS
            "increments": self.increments,
            "angular_increments": self.angular_increments,
            "jog_speed": self.jog_speed,
            "angular_jog_speed": self.angular_jog_speed,
            "overrides": {
                "feed_max": self.max_feed_override,
                "rapid_max": self.max_rapid_override,
                "spindle_min": self.min_spindle_override,
                "spindle_max": self.max_spindle_override,
            },
            "spindle": self.spindle,
            "units": "mm" if self.units_per_mm == 1.0 else "inch",
            "program_prefix": str(self.program_prefix) if self.program_prefix else None,
            "has_tool_table": self.tool_table is not None,
            "tool_sensor": self.tool_sensor,
            "is_lathe": self.is_lathe,
            "macros": self.macros,
            "limits": self.limits,
        }


def _jog_range(default: float, low: float, high: float) -> dict[str, float]:
    """A jog speed slider's range (units per minute): never down to 0, which is no jog
    (motion refuses a zero jog velocity)."""
    high = high if high > 0 else max(default, 1.0)
    low = max(low, high * MIN_JOG_FRACTION)
    return {"default": min(max(default, low), high), "min": low, "max": high}


def _spindle(ini: IniFile) -> tuple[dict[str, float], dict[str, str]]:
    """The manual spindle controls' range (GUI-013): [DISPLAY] MIN/MAX_SPINDLE_0_SPEED
    within [SPINDLE_0] MIN/MAX_FORWARD_VELOCITY and MAX_REVERSE_VELOCITY (rpm), and which
    key set each bound (for the messages)."""

    def value(section: str, key: str) -> float | None:
        try:
            found = ini.find(section, key)
            return None if found is None else abs(float(found))
        except ValueError:
            return None

    def lowest(*keys: tuple[str, str]) -> tuple[float, str]:
        found = [(v, f"[{s}]{k}") for s, k in keys if (v := value(s, k)) is not None]
        return min(found) if found else (100_000.0, "")

    display_max = (("DISPLAY", "MAX_SPINDLE_0_SPEED"), ("DISPLAY", "MAX_SPINDLE_SPEED"))
    high, high_key = lowest(*display_max, ("SPINDLE_0", "MAX_FORWARD_VELOCITY"))
    # LinuxCNC: the reverse maximum is the forward one unless given
    has_reverse = value("SPINDLE_0", "MAX_REVERSE_VELOCITY") is not None
    reverse_key = "MAX_REVERSE_VELOCITY" if has_reverse else "MAX_FORWARD_VELOCITY"
    reverse, reverse_key = lowest(*display_max, ("SPINDLE_0", reverse_key))
    low_values = [
        value("DISPLAY", "MIN_SPINDLE_0_SPEED"),
        value("SPINDLE_0", "MIN_FORWARD_VELOCITY"),
    ]
    low = max([v for v in low_values if v is not None], default=0.0)
    default = value("DISPLAY", "DEFAULT_SPINDLE_0_SPEED") or value(
        "DISPLAY", "DEFAULT_SPINDLE_SPEED"
    )
    spindle = {
        "increment": value("DISPLAY", "SPINDLE_INCREMENT") or 100.0,
        "default": min(max(default if default is not None else 500.0, low), high),
        "min": low,
        "max": high,
        "max_reverse": reverse,
    }
    return spindle, {"max": high_key, "max_reverse": reverse_key}


def _tool_sensor(ini: IniFile, problems: list[str]) -> dict[str, float] | None:
    """[TOOLSENSOR] (gmoccapy's keys, plus SEARCH_VEL and PROBE_VEL), or None if absent."""
    if not ini.has_section("TOOLSENSOR"):
        return None
    found: dict[str, float] = {}
    defaults = {"X": None, "Y": None, "Z": None, "MAXPROBE": None, "SEARCH_VEL": 200.0,
                "PROBE_VEL": 20.0}  # fmt: skip
    for key, default in defaults.items():
        entry = ini.entry("TOOLSENSOR", key)
        try:
            number = float(entry.value) if entry is not None else default
        except ValueError:
            number = None
        if number is None or not math.isfinite(number):
            where = f"{entry.file}:{entry.line}" if entry is not None else ini.path
            problems.append(f"{where}: [TOOLSENSOR]{key} must be a number: tool setter off")
            return None
        found[key.lower()] = number
    return found


def _numbered(ini: Any, section: str, prefix: str) -> list[str]:
    """Values of keys ``prefix0``, ``prefix1`` ... (also ``prefix01``) in number order."""
    found = []
    for number in range(100):
        for key in (f"{prefix}{number}", f"{prefix}{number:02d}"):
            value = ini.find(section, key)
            if value is not None:
                found.append(value)
                break
    return found


def _limits(config: MachineConfig) -> dict[str, list[float]]:
    """[AXIS_L]MIN_LIMIT and MAX_LIMIT of each axis that has both, in machine units."""
    found = {}
    for letter in config.axes:
        section = f"AXIS_{letter}"
        if config.is_set(section, "MIN_LIMIT") and config.is_set(section, "MAX_LIMIT"):
            found[letter] = [config.value(section, "MIN_LIMIT"), config.value(section, "MAX_LIMIT")]
    return found


def _filters(ini: IniFile) -> dict[str, str]:
    """[FILTER] ``<ext> = <program>`` lines (GUI-015): ".png" -> "image-to-gcode"."""
    found = {}
    for key, value in ini.items("FILTER"):
        if key != "PROGRAM_EXTENSION" and value.strip():
            found["." + key.lower().lstrip(".")] = value.strip()
    return found


def _is_lathe(hint: str | None, old_switch: str | None) -> bool:
    return (hint or "").strip().upper() == "LATHE" or (old_switch or "").strip() in ("1", "true")
