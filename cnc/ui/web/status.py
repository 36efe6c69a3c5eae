"""The status the page shows, as a flat JSON-ready dict, and the diff between two of them.

``snapshot(s, settings)`` reads a polled ``cnc.stat`` once; only axes of ``axis_mask`` and
joints ``0..joints-1`` are included (GUI-021). Positions are rounded to the places the page
shows, so a diff carries only what visibly changed.
"""

from __future__ import annotations

import math
import types
from typing import Any

from cnc.ui import formatting as fmt
from cnc.ui.web.settings import Settings

PLACES = 4  # digits kept after '.' for lengths (the page shows 3 or 4)
# stat.g5x_index -> its name: 1 = G54 ... 6 = G59, 7..9 = G59.1..G59.3
G5X_NAMES = {1: "G54", 2: "G55", 3: "G56", 4: "G57", 5: "G58", 6: "G59"}
G5X_NAMES.update({7: "G59.1", 8: "G59.2", 9: "G59.3"})


def _rounded(values: list[float], indexes: list[int]) -> list[float | None]:
    """The entries at ``indexes``, rounded; NaN and infinities as None (not JSON)."""
    result: list[float | None] = []
    for index in indexes:
        value = values[index]
        result.append(round(value, PLACES) if math.isfinite(value) else None)
    return result


def _number(value: object, places: int = PLACES) -> float | None:
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return None
    return round(x, places) if math.isfinite(x) else None


def snapshot(s: Any, settings: Settings) -> dict[str, Any]:
    """What the page shows of the polled status ``s``."""
    axes = fmt.axes(s)
    indexes = [index for index, _ in axes]
    position = s.actual_position if settings.is_position_actual else s.position
    shown = types.SimpleNamespace(
        position=position,
        g5x_offset=s.g5x_offset,
        tool_offset=s.tool_offset,
        g92_offset=s.g92_offset,
        rotation_xy=s.rotation_xy,
    )
    joint_count = fmt.count(s.joints, len(s.joint))
    joints = [fmt.item(s.joint, index, {}) for index in range(joint_count)]
    joints = [joint if isinstance(joint, dict) else {} for joint in joints]
    spindle = fmt.item(s.spindle, 0, {})
    spindle = spindle if isinstance(spindle, dict) else {}
    joint_position = s.joint_actual_position if settings.is_position_actual else s.joint_position
    return {
        "is_connected": True,
        "task_state": fmt.name_of(fmt.TASK_STATES, s.task_state),
        "task_mode": fmt.name_of(fmt.TASK_MODES, s.task_mode),
        "interp_state": fmt.name_of(fmt.INTERP_STATES, s.interp_state),
        "exec_state": fmt.name_of(fmt.EXEC_STATES, s.exec_state),
        "is_estop": bool(s.estop),
        "is_enabled": bool(s.enabled),
        "axes": "".join(letter for _, letter in axes),
        "work": _rounded(fmt.work_position(shown), indexes),
        "machine": _rounded(fmt.pose(position), indexes),
        "dtg": _rounded(fmt.pose(s.dtg), indexes),
        "joint_position": _rounded(fmt.pose(joint_position), list(range(min(joint_count, 9)))),
        "homed": [bool(joint.get("homed")) for joint in joints],
        "homing": [bool(joint.get("homing")) for joint in joints],
        "is_all_homed": bool(joints) and all(joint.get("homed") for joint in joints),
        "limit": [fmt.limit_flags(fmt.item(s.limit, index, 0)) for index in range(joint_count)],
        "g5x": G5X_NAMES.get(s.g5x_index, f"G5x({s.g5x_index})"),
        "gcodes": fmt.g_codes(s.gcodes),
        "mcodes": fmt.m_codes(s.mcodes),
        # the interpreter's modal F and S: read ahead of the machine, as its G and M codes
        "feed": _number(fmt.item(s.settings, 1), 3),
        "speed": _number(fmt.item(s.settings, 2), 1),
        # the machine's: tool velocity now (units/min), spindle as motion drives it
        "velocity": _number(float(s.current_vel) * 60, 1),
        "tool": s.tool_in_spindle,
        "tool_offset": _rounded(fmt.pose(s.tool_offset), indexes),
        "feedrate": _number(float(s.feedrate) * 100, 1),
        "rapidrate": _number(float(s.rapidrate) * 100, 1),
        "spindle_override": _number(float(spindle.get("override", 1.0)) * 100, 1),
        "spindle_speed": _number(abs(float(spindle.get("speed", 0.0))), 1),
        "spindle_direction": spindle.get("direction", 0),
        "is_flood": bool(s.flood),
        "is_mist": bool(s.mist),
        "file": fmt.clean(s.file),
        "current_line": s.current_line,
        "motion_line": s.motion_line,
        "is_optional_stop": bool(s.optional_stop),
        "is_block_delete": bool(s.block_delete),
        "is_paused": bool(s.paused) or bool(s.task_paused),
        # task paused by the program (M0, M1, M60, a step's end) rather than by the operator
        # (feed hold): both pause motion (as LinuxCNC's), but a program stops only once
        # motion's queue is empty, and a feed hold keeps the move it holds queued
        "is_program_stop": bool(s.task_paused) and s.queue == 0,
        "program_units": {1: "inch", 2: "mm", 3: "cm"}.get(s.program_units, "mm"),
        "rotation_xy": _number(s.rotation_xy, 4),
        "queued_mdi": s.queued_mdi_commands,
    }


# Every field of a snapshot (the API's status fields; the hub adds "job")
FIELDS = (
    "is_connected",
    "task_state",
    "task_mode",
    "interp_state",
    "exec_state",
    "is_estop",
    "is_enabled",
    "axes",
    "work",
    "machine",
    "dtg",
    "joint_position",
    "homed",
    "homing",
    "is_all_homed",
    "limit",
    "g5x",
    "gcodes",
    "mcodes",
    "feed",
    "speed",
    "velocity",
    "tool",
    "tool_offset",
    "feedrate",
    "rapidrate",
    "spindle_override",
    "spindle_speed",
    "spindle_direction",
    "is_flood",
    "is_mist",
    "file",
    "current_line",
    "motion_line",
    "is_optional_stop",
    "is_block_delete",
    "is_paused",
    "is_program_stop",
    "program_units",
    "rotation_xy",
    "queued_mdi",
)


DISCONNECTED: dict[str, Any] = {"is_connected": False}


def diff(old: dict[str, Any], new: dict[str, Any]) -> dict[str, Any]:
    """The entries of ``new`` that differ from ``old`` (keys missing from ``new`` stay as
    they were: the page keeps the last value shown)."""
    return {key: value for key, value in new.items() if old.get(key, diff) != value}
