"""What the web UI takes from the INI file: [DISPLAY], [MDI_COMMAND_LIST], [FILTER].
([DISPLAY] MESSAGE_* and MULTIMESSAGE_* are read by messages.py.)

``Settings.load(path)`` reads every value once at start; ``Settings()`` is a machine without
an INI file (defaults only). ``page_config()`` is the part the page needs, as JSON.
"""

from __future__ import annotations

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
        default_factory=lambda: {"increment": 100.0, "default": 500.0, "min": 0.0, "max": 1e5}
    )
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
        return cls(
            ini_file=str(folder / Path(path).name),
            machine=ini.find("EMC", "MACHINE") or "",
            title=display("TITLE") or "",
            cycle_time_s=cycle_time(display("CYCLE_TIME")),
            units_per_mm=units_per_mm,
            axes="".join(dict.fromkeys(c for c in coordinates if c in AXIS_LETTERS)),
            increments=increments(display("INCREMENTS"), units_per_mm),
            angular_increments=angular_increments(display("ANGULAR_INCREMENTS")),
            jog_speed={
                "default": default_speed,
                "min": number("MIN_LINEAR_VELOCITY", 0.0) * 60,
                "max": number("MAX_LINEAR_VELOCITY", default_speed / 60 * 5) * 60,
            },
            angular_jog_speed={
                "default": number("DEFAULT_ANGULAR_VELOCITY", 6.0) * 60,
                "min": number("MIN_ANGULAR_VELOCITY", 0.0) * 60,
                "max": number("MAX_ANGULAR_VELOCITY", 60.0) * 60,
            },
            max_feed_override=override_percent(display("MAX_FEED_OVERRIDE"), 120.0),
            max_rapid_override=min(override_percent(display("MAX_RAPID_OVERRIDE"), 100.0), 100),
            min_spindle_override=override_percent(
                display("MIN_SPINDLE_0_OVERRIDE") or display("MIN_SPINDLE_OVERRIDE"), 50.0
            ),
            max_spindle_override=override_percent(
                display("MAX_SPINDLE_0_OVERRIDE") or display("MAX_SPINDLE_OVERRIDE"), 120.0
            ),
            spindle={
                "increment": number("SPINDLE_INCREMENT", 100.0),
                "default": number("DEFAULT_SPINDLE_0_SPEED", 500.0),
                "min": number("MIN_SPINDLE_0_SPEED", 0.0),
                "max": number("MAX_SPINDLE_0_SPEED", 100_000.0),
            },
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
            "is_lathe": self.is_lathe,
            "macros": self.macros,
            "limits": self.limits,
        }


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
