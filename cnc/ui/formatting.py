"""Controller status as text, for ``cnc top`` and ``cnc sh``; numbers typed by the operator.

Every function takes a polled ``cnc.stat`` (or any object with its attributes) and returns
lines of plain printable text. Odd values (an unknown state number, NaN, a G-code array the
interpreter has not filled yet, control characters in a file name) are shown as they are,
never raised: a status view must keep running whatever the controller publishes.

Display follows LinuxCNC's GUIs: only the axes of ``axis_mask`` and joints ``0..joints-1``
(GUI-021), work coordinates as AXIS computes them, active codes as "G1 G17 G21 ...", numbers
with a ``.`` whatever the locale (GUI-004).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import cnc
from nml.axes import AXIS_LETTERS

Status = Any  # a polled cnc.stat, or any object with its attribute names


TASK_STATES = {
    cnc.STATE_ESTOP: "ESTOP",
    cnc.STATE_ESTOP_RESET: "ESTOP_RESET",
    cnc.STATE_OFF: "OFF",
    cnc.STATE_ON: "ON",
}
TASK_MODES = {cnc.MODE_MANUAL: "MANUAL", cnc.MODE_AUTO: "AUTO", cnc.MODE_MDI: "MDI"}
EXEC_STATES = {
    cnc.EXEC_ERROR: "ERROR",
    cnc.EXEC_DONE: "DONE",
    cnc.EXEC_WAITING_FOR_MOTION: "WAITING_FOR_MOTION",
    cnc.EXEC_WAITING_FOR_MOTION_QUEUE: "WAITING_FOR_MOTION_QUEUE",
    cnc.EXEC_WAITING_FOR_IO: "WAITING_FOR_IO",
    cnc.EXEC_WAITING_FOR_MOTION_AND_IO: "WAITING_FOR_MOTION_AND_IO",
    cnc.EXEC_WAITING_FOR_DELAY: "WAITING_FOR_DELAY",
    cnc.EXEC_WAITING_FOR_SYSTEM_CMD: "WAITING_FOR_SYSTEM_CMD",
    cnc.EXEC_WAITING_FOR_SPINDLE_ORIENTED: "WAITING_FOR_SPINDLE_ORIENTED",
}
INTERP_STATES = {
    cnc.INTERP_IDLE: "IDLE",
    cnc.INTERP_READING: "READING",
    cnc.INTERP_PAUSED: "PAUSED",
    cnc.INTERP_WAITING: "WAITING",
}
RCS_STATES = {cnc.RCS_DONE: "DONE", cnc.RCS_EXEC: "EXEC", cnc.RCS_ERROR: "ERROR"}
MOTION_MODES = {
    cnc.TRAJ_MODE_FREE: "FREE",
    cnc.TRAJ_MODE_COORD: "COORD",
    cnc.TRAJ_MODE_TELEOP: "TELEOP",
}
MOTION_TYPES = {
    0: "none",
    cnc.MOTION_TYPE_TRAVERSE: "TRAVERSE",
    cnc.MOTION_TYPE_FEED: "FEED",
    cnc.MOTION_TYPE_ARC: "ARC",
    cnc.MOTION_TYPE_TOOLCHANGE: "TOOLCHANGE",
    cnc.MOTION_TYPE_PROBING: "PROBING",
    cnc.MOTION_TYPE_INDEXROTARY: "INDEXROTARY",
}
MESSAGE_KINDS = {
    cnc.OPERATOR_ERROR: "error",
    cnc.NML_ERROR: "error",
    cnc.OPERATOR_TEXT: "text",
    cnc.NML_TEXT: "text",
    cnc.OPERATOR_DISPLAY: "display",
    cnc.NML_DISPLAY: "display",
}
# Bits of stat.limit[joint] -> how the joint table shows them.
LIMIT_FLAGS = ((1, "-H"), (2, "+H"), (4, "-S"), (8, "+S"))

_DECIMAL = re.compile(r"[+-]?([0-9]+[.,]?[0-9]*|[.,][0-9]+)")  # "-1", "1,5", ".5", "2."
_LINE_BREAKS = re.compile(r"[\t\n\r\v\f]+")
_UNPRINTABLE = re.compile(r"[\x00-\x1f\x7f-\x9f]")


# ------------------------------------------------------------------ single values
def name_of(names: dict[int, str], value: object) -> str:
    """The name of an enumerated value, or ``unknown(value)``."""
    try:
        return names[value]  # type: ignore[index]
    except (KeyError, TypeError):
        return f"unknown({clean(value)})"


def clean(value: object) -> str:
    """``value`` as one line of printable text: line breaks and tabs become a space, other
    control characters (which could drive the terminal) '?'."""
    return _UNPRINTABLE.sub("?", _LINE_BREAKS.sub(" ", str(value)))


def on_off(value: object) -> str:
    return "on" if value else "off"


def yes_no(value: object) -> str:
    return "yes" if value else "no"


def number(value: object, decimals: int = 4, width: int = 0) -> str:
    """A float with ``decimals`` digits after '.', right-aligned to ``width``."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return f"{clean(value):>{width}}"
    if math.isfinite(x) and abs(x) < 1e9:
        return f"{x:{width}.{decimals}f}"
    return f"{x:{width}.3e}"  # nan, inf, or too wide for a column


def percent(scale: object) -> str:
    """An override scale (1.0 = 100 %) as ``100%``."""
    try:
        return f"{number(float(scale) * 100, 0)}%"  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return clean(scale)


def decimals_for(s: Status) -> int:
    """Digits shown after '.' for lengths: 3 for mm machines, 4 otherwise (as AXIS)."""
    try:
        is_mm = abs(float(s.linear_units) - 1.0) < 1e-6
    except (TypeError, ValueError):
        is_mm = False
    return 3 if is_mm else 4


def pose(value: object) -> list[float]:
    """A 9-tuple pose as floats (missing or odd entries as NaN)."""
    try:
        items = list(value)  # type: ignore[call-overload]
    except TypeError:
        items = []
    result = []
    for index in range(9):
        try:
            result.append(float(items[index]))
        except (IndexError, TypeError, ValueError, OverflowError):
            result.append(math.nan)
    return result


def count(value: object, limit: int) -> int:
    """A count from the status clamped to 0..limit (how many joints, spindles ...)."""
    try:
        return max(0, min(int(value), limit))  # type: ignore[call-overload]
    except (TypeError, ValueError, OverflowError):
        return 0


def item(values: object, index: int, default: Any = None) -> Any:
    """``values[index]``, or ``default`` when the status has no such entry."""
    try:
        return values[index]  # type: ignore[index]
    except (IndexError, KeyError, TypeError):
        return default


# ------------------------------------------------------------------ input
def parse_float(text: str) -> float:
    """A number typed by the operator: digits with '.' or ',' as decimal separator, at most
    one of them, spaces allowed as thousands separators (GUI-003); ValueError otherwise."""
    compact = text.strip().replace(" ", "")
    if compact.count(".") + compact.count(",") > 1:
        raise ValueError(f"'{text}' is not a number (use one '.' or ',' as decimal separator)")
    if not _DECIMAL.fullmatch(compact):
        raise ValueError(f"'{text}' is not a number")
    return float(compact.replace(",", "."))


# ------------------------------------------------------------------ codes
def _is_filled(codes: Sequence[Any]) -> bool:
    """Whether the interpreter has reported these codes (an all-zero array is unfilled:
    every group but the motion mode has a non-zero code once the interpreter runs)."""
    return any(code != 0 for code in codes)


def g_codes(gcodes: object) -> str:
    """stat.gcodes as LinuxCNC's GUIs show them: "G1 G17 G40 G21 ..." (entry 0, the line
    number, and -1 entries, groups without a code, are left out)."""
    codes = _ints(gcodes)[1:]
    if not _is_filled(codes):
        return ""
    words = []
    for code in codes:
        if code >= 0:
            words.append(f"G{code // 10}" if code % 10 == 0 else f"G{code // 10}.{code % 10}")
    return " ".join(words)


def m_codes(mcodes: object) -> str:
    """stat.mcodes as "M5 M9 M48 ..." (entry 0, the line number, and -1 entries left out)."""
    codes = _ints(mcodes)[1:]
    if not _is_filled(codes):
        return ""
    return " ".join(f"M{code}" for code in codes if code >= 0)


def feed_and_speed(settings: object) -> str:
    """stat.settings as "F500 S1200" (programmed feed and spindle speed)."""
    feed, speed = item(settings, 1, math.nan), item(settings, 2, math.nan)
    return f"F{_short(feed)} S{_short(speed)}"


def _short(value: object) -> str:
    try:
        return f"{float(value):g}"  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return clean(value)


def _ints(values: object) -> list[int]:
    result = []
    try:
        for value in values:  # type: ignore[attr-defined]
            try:
                result.append(int(value))
            except (TypeError, ValueError, OverflowError):
                result.append(-1)
    except TypeError:
        pass
    return result


def active_codes(s: Status) -> list[str]:
    """The active G codes, then the M codes with F and S, as two lines."""
    return [
        f"G-codes {g_codes(s.gcodes) or '-'}",
        f"M-codes {m_codes(s.mcodes) or '-'}   {feed_and_speed(s.settings)}",
    ]


# ------------------------------------------------------------------ positions
def axes(s: Status) -> list[tuple[int, str]]:
    """(index, letter) of the axes of ``axis_mask`` (GUI-021)."""
    try:
        mask = int(s.axis_mask)
    except (TypeError, ValueError, OverflowError):
        mask = 0
    return [(index, letter) for index, letter in enumerate(AXIS_LETTERS) if mask & (1 << index)]


def work_position(s: Status) -> list[float]:
    """The commanded position in work coordinates, as AXIS computes it: machine position
    minus G5x and tool offsets, rotated by -rotation_xy, minus the G92 offset."""
    position, g5x, tool, g92 = (
        pose(s.position),
        pose(s.g5x_offset),
        pose(s.tool_offset),
        pose(s.g92_offset),
    )
    relative = [p - o - t for p, o, t in zip(position, g5x, tool, strict=True)]
    try:
        angle = math.radians(-float(s.rotation_xy))
    except (TypeError, ValueError, OverflowError):
        angle = 0.0
    if angle:
        x, y = relative[0], relative[1]
        relative[0] = x * math.cos(angle) - y * math.sin(angle)
        relative[1] = x * math.sin(angle) + y * math.cos(angle)
    return [r - g for r, g in zip(relative, g92, strict=True)]


def position_lines(s: Status) -> list[str]:
    """One line per axis: work and machine coordinates (commanded) and distance to go."""
    places = decimals_for(s)
    work, machine, to_go = work_position(s), pose(s.position), pose(s.dtg)
    lines = [f"{'Axis':<4} {'Work':>11} {'Machine':>11} {'To go':>11}"]
    for index, letter in axes(s):
        lines.append(
            f"{letter:<4} {number(work[index], places, 11)} "
            f"{number(machine[index], places, 11)} {number(to_go[index], places, 11)}"
        )
    return lines


def offset_lines(s: Status) -> list[str]:
    """The G5x and G92 offsets and the XY rotation."""
    return [
        f"{_coordinate_system(s.g5x_index)} {_axis_words(s, s.g5x_offset)}   "
        f"rotation {number(s.rotation_xy, 1)}",
        f"G92 {_axis_words(s, s.g92_offset)}",
    ]


def _axis_words(s: Status, value: object) -> str:
    """A pose as "X1.000 Y2.000 Z3.000" on the axes of ``axis_mask``."""
    places, values = decimals_for(s), pose(value)
    return " ".join(f"{letter}{number(values[index], places)}" for index, letter in axes(s))


def _coordinate_system(index: object) -> str:
    """The name of stat.g5x_index: 1 = G54 ... 6 = G59, 7 = G59.1, 8 = G59.2, 9 = G59.3."""
    names = {1: "G54", 2: "G55", 3: "G56", 4: "G57", 5: "G58", 6: "G59"}
    names.update({7: "G59.1", 8: "G59.2", 9: "G59.3"})
    return names.get(index, f"G5x({clean(index)})")  # type: ignore[call-overload]


def limit_flags(bits: object) -> str:
    """A joint's limit bits as "-H +S" (hard and soft, min and max), "ok" if none."""
    try:
        value = int(bits)  # type: ignore[call-overload]
    except (TypeError, ValueError, OverflowError):
        return clean(bits)
    return " ".join(name for bit, name in LIMIT_FLAGS if value & bit) or "ok"


def joint_lines(s: Status) -> list[str]:
    """One line per joint: commanded position, homed, limits, fault."""
    places = decimals_for(s)
    joints = s.joint
    lines = [f"{'Joint':<5} {'Position':>11} {'Homed':<6} Limits"]
    for index in range(count(s.joints, len(joints))):
        joint = item(joints, index, {})
        joint = joint if isinstance(joint, dict) else {}
        homed = "homing" if joint.get("homing") else yes_no(joint.get("homed"))
        flags = limit_flags(item(s.limit, index, 0))
        fault = " FAULT" if joint.get("fault") else ""
        position = number(item(s.joint_position, index), places, 11)
        lines.append(f"{index:<5} {position} {homed:<6} {flags:<11}{fault}".rstrip())
    return lines


def side_by_side(left: list[str], right: list[str], gap: int = 3) -> list[str]:
    """Two blocks of lines as columns."""
    width = max((len(line) for line in left), default=0) + gap
    rows = max(len(left), len(right))
    left, right = left + [""] * (rows - len(left)), right + [""] * (rows - len(right))
    return [f"{a:<{width}}{b}".rstrip() for a, b in zip(left, right, strict=True)]


# ------------------------------------------------------------------ task, machine
def state_lines(s: Status) -> list[str]:
    """Task state and mode, interpreter, execution, the last command's status, motion."""
    return [
        f"Task {name_of(TASK_STATES, s.task_state)}  mode {name_of(TASK_MODES, s.task_mode)}  "
        f"interp {name_of(INTERP_STATES, s.interp_state)}  command {name_of(RCS_STATES, s.state)}",
        f"Exec {name_of(EXEC_STATES, s.exec_state)}  e-stop {yes_no(s.estop)}  "
        f"enabled {yes_no(s.enabled)}",
        f"Motion {name_of(MOTION_MODES, s.motion_mode)} {name_of(MOTION_TYPES, s.motion_type)}  "
        f"in position {yes_no(s.inpos)}  velocity {number(s.current_vel, decimals_for(s))}",
    ]


def program_lines(s: Status) -> list[str]:
    """The open program, its lines (current, motion, read) and the motion queue."""
    return [
        f"File {clean(s.file) or '-'}",
        f"Line current {clean(s.current_line)}  motion {clean(s.motion_line)}  "
        f"read {clean(s.read_line)}  queue {clean(s.queue)} (active {clean(s.active_queue)})  "
        f"paused {yes_no(s.paused)}",
    ]


def override_lines(s: Status) -> list[str]:
    """Feed and rapid overrides, optional stop and block delete, coolant and lube."""
    return [
        f"Feed {percent(s.feedrate)}  rapid {percent(s.rapidrate)}  "
        f"optional stop {on_off(s.optional_stop)}  block delete {on_off(s.block_delete)}",
        f"Coolant flood {on_off(s.flood)}  mist {on_off(s.mist)}  lube {on_off(s.lube)}",
    ]


def spindle_lines(s: Status) -> list[str]:
    """Each spindle's direction, speed, override and brake."""
    lines = []
    spindles = s.spindle
    for index in range(max(1, count(s.spindles, len(spindles)))):
        spindle = item(spindles, index, {})
        spindle = spindle if isinstance(spindle, dict) else {}
        direction = {1: "forward", -1: "reverse", 0: "stopped"}.get(
            spindle.get("direction"), f"direction {clean(spindle.get('direction'))}"
        )
        lines.append(
            f"Spindle {index} {direction}  speed {number(spindle.get('speed'), 0)} rpm  "
            f"override {percent(spindle.get('override'))}  "
            f"brake {on_off(spindle.get('brake'))}"
        )
    return lines


def tool_lines(s: Status) -> list[str]:
    """The tool in the spindle (with its diameter), the prepared pocket, the tool offset."""
    entry = item(s.tool_table, 0)
    diameter = getattr(entry, "diameter", None)
    size = f"  diameter {number(diameter, decimals_for(s))}" if diameter is not None else ""
    return [
        f"Tool {clean(s.tool_in_spindle)} in spindle{size}  "
        f"prepared pocket {clean(s.pocket_prepped)}",
        f"Tool offset {_axis_words(s, s.tool_offset) or '-'}",
    ]


def message_line(kind: object, text: object) -> str:
    """An operator message as "error: text" (or "text: ...", "display: ...")."""
    return f"{name_of(MESSAGE_KINDS, kind)}: {clean(text)}"
