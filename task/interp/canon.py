"""The canon interface: the canonical machining calls the interpreter makes (INTERP-022/023).

``Canon`` is the Protocol every back-end implements: "do it" calls (moves, spindle, coolant,
tools, messages ...) and "give me information" calls (``GET_EXTERNAL_*``), which the
interpreter uses to synchronise with the world (TASK-009).

``PrintingCanon`` is the standalone back-end (LinuxCNC's saicanon): it prints every call in
``rs274``'s format, ``%5d N..... NAME(args)``, and keeps the same small world model, so that
the interpreter sees exactly what it would see inside ``rs274``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from iocontrol.tooltable import ToolEntry, ToolTable

# Type checkers take this constant for typing.TYPE_CHECKING; at run time Canon is a plain
# class, because importing typing would cost ``cnc rs274`` 2 ms of its start-up.
TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Protocol
else:
    Protocol = object

# CANON_PLANE
PLANE_XY, PLANE_YZ, PLANE_XZ, PLANE_UV, PLANE_VW, PLANE_UW = 1, 2, 3, 4, 5, 6
# CANON_UNITS
UNITS_INCHES, UNITS_MM, UNITS_CM = 1, 2, 3
# CANON_MOTION_MODE
EXACT_STOP, EXACT_PATH, CONTINUOUS = 1, 2, 3
# CANON_DIRECTION
STOPPED, CLOCKWISE, COUNTERCLOCKWISE = 1, 2, 3
# CANON_SIDE
SIDE_RIGHT, SIDE_LEFT, SIDE_OFF = 1, 2, 3
# feed reference
CANON_WORKPIECE, CANON_XYZ = 1, 2
# WAIT input types
DIGITAL_INPUT, ANALOG_INPUT = 1, 0

_PLANE_NAMES = {PLANE_XY: "XY", PLANE_YZ: "YZ", PLANE_XZ: "XZ"}
_AXIS_NAMES = {
    0: "CANON_AXIS_X",
    1: "CANON_AXIS_Y",
    2: "CANON_AXIS_Z",
    3: "CANON_AXIS_A",
    4: "CANON_AXIS_B",
    5: "CANON_AXIS_C",
}


class Canon(Protocol):
    """Canonical calls; positions are program units with offsets applied by the canon.

    Optional: ``UPDATE_TAG(tag)``, the interpreter's modal state for the moves that follow
    (task/interp/statetag.py); only a canon that has it is given tags (task's does).
    """

    # representation
    def SET_XY_ROTATION(self, t: float) -> None: ...
    def SET_G5X_OFFSET(
        self,
        index: int,
        x: float,
        y: float,
        z: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
    ) -> None: ...
    def SET_G92_OFFSET(
        self,
        x: float,
        y: float,
        z: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
    ) -> None: ...
    def USE_LENGTH_UNITS(self, units: int) -> None: ...
    # motion
    def SET_TRAVERSE_RATE(self, rate: float) -> None: ...
    def STRAIGHT_TRAVERSE(
        self,
        line: int,
        x: float,
        y: float,
        z: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
    ) -> None: ...
    def STRAIGHT_FEED(
        self,
        line: int,
        x: float,
        y: float,
        z: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
    ) -> None: ...
    def ARC_FEED(
        self,
        line: int,
        first_end: float,
        second_end: float,
        first_axis: float,
        second_axis: float,
        rotation: int,
        axis_end: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
    ) -> None: ...
    def STRAIGHT_PROBE(
        self,
        line: int,
        x: float,
        y: float,
        z: float,
        a: float,
        b: float,
        c: float,
        u: float,
        v: float,
        w: float,
        probe_type: int,
    ) -> None: ...
    def RIGID_TAP(self, line: int, x: float, y: float, z: float, scale: float) -> None: ...
    def NURBS_FEED(
        self, line: int, points: list[tuple[float, float, float]], order: int
    ) -> None: ...
    def DWELL(self, seconds: float) -> None: ...
    def SET_FEED_MODE(self, spindle: int, mode: int) -> None: ...
    def SET_FEED_RATE(self, rate: float) -> None: ...
    def SET_FEED_REFERENCE(self, reference: int) -> None: ...
    def SET_MOTION_CONTROL_MODE(self, mode: int, tolerance: float) -> None: ...
    def SET_NAIVECAM_TOLERANCE(self, tolerance: float) -> None: ...
    def SELECT_PLANE(self, plane: int) -> None: ...
    def START_SPEED_FEED_SYNCH(self, spindle: int, sync: float, vel: bool) -> None: ...
    def STOP_SPEED_FEED_SYNCH(self) -> None: ...
    # spindle
    def SET_SPINDLE_MODE(self, spindle: int, arg: float) -> None: ...
    def START_SPINDLE_CLOCKWISE(self, spindle: int) -> None: ...
    def START_SPINDLE_COUNTERCLOCKWISE(self, spindle: int) -> None: ...
    def SET_SPINDLE_SPEED(self, spindle: int, rpm: float) -> None: ...
    def STOP_SPINDLE_TURNING(self, spindle: int) -> None: ...
    def ORIENT_SPINDLE(self, spindle: int, orientation: float, mode: int) -> None: ...
    def WAIT_SPINDLE_ORIENT_COMPLETE(self, spindle: int, timeout: float) -> None: ...
    # tools
    def SET_TOOL_TABLE_ENTRY(
        self,
        idx: int,
        toolno: int,
        offset: list[float],
        diameter: float,
        frontangle: float,
        backangle: float,
        orientation: int,
    ) -> None: ...
    def USE_TOOL_LENGTH_OFFSET(self, offset: list[float]) -> None: ...
    def CHANGE_TOOL(self, slot: int) -> None: ...
    def SELECT_TOOL(self, tool: int) -> None: ...
    def CHANGE_TOOL_NUMBER(self, tool: int) -> None: ...
    def RELOAD_TOOLDATA(self) -> None: ...
    def START_CHANGE(self) -> None: ...
    # misc
    def COMMENT(self, text: str) -> None: ...
    def MESSAGE(self, text: str) -> None: ...
    def CANON_ERROR(self, text: str) -> None: ...
    def LOG(self, text: str) -> None: ...
    def LOGOPEN(self, text: str) -> None: ...
    def LOGAPPEND(self, text: str) -> None: ...
    def LOGCLOSE(self) -> None: ...
    def PRINT_LINE(self, text: str) -> None: ...
    def DISABLE_ADAPTIVE_FEED(self) -> None: ...
    def ENABLE_ADAPTIVE_FEED(self) -> None: ...
    def DISABLE_FEED_HOLD(self) -> None: ...
    def ENABLE_FEED_HOLD(self) -> None: ...
    def DISABLE_FEED_OVERRIDE(self) -> None: ...
    def ENABLE_FEED_OVERRIDE(self) -> None: ...
    def DISABLE_SPEED_OVERRIDE(self, spindle: int) -> None: ...
    def ENABLE_SPEED_OVERRIDE(self, spindle: int) -> None: ...
    def FLOOD_OFF(self) -> None: ...
    def FLOOD_ON(self) -> None: ...
    def MIST_OFF(self) -> None: ...
    def MIST_ON(self) -> None: ...
    def PALLET_SHUTTLE(self) -> None: ...
    def TURN_PROBE_OFF(self) -> None: ...
    def TURN_PROBE_ON(self) -> None: ...
    def PROGRAM_STOP(self) -> None: ...
    def OPTIONAL_PROGRAM_STOP(self) -> None: ...
    def PROGRAM_END(self) -> None: ...
    def SET_MOTION_OUTPUT_BIT(self, index: int) -> None: ...
    def CLEAR_MOTION_OUTPUT_BIT(self, index: int) -> None: ...
    def SET_MOTION_OUTPUT_VALUE(self, index: int, value: float) -> None: ...
    def SET_AUX_OUTPUT_BIT(self, index: int) -> None: ...
    def CLEAR_AUX_OUTPUT_BIT(self, index: int) -> None: ...
    def SET_AUX_OUTPUT_VALUE(self, index: int, value: float) -> None: ...
    def WAIT(self, index: int, input_type: int, wait_type: int, timeout: float) -> int: ...
    def FINISH(self) -> None: ...
    def ON_RESET(self) -> None: ...
    def USER_DEFINED_FUNCTION(self, index: int, p: float, q: float) -> bool: ...
    # world model
    def GET_EXTERNAL_POSITION(self) -> list[float]: ...
    def GET_EXTERNAL_PROBE_POSITION(self) -> list[float]: ...
    def GET_EXTERNAL_PROBE_TRIPPED_VALUE(self) -> int: ...
    def GET_EXTERNAL_LENGTH_UNITS(self) -> float: ...
    def GET_EXTERNAL_ANGLE_UNITS(self) -> float: ...
    def GET_EXTERNAL_LENGTH_UNIT_TYPE(self) -> int: ...
    def GET_EXTERNAL_MOTION_CONTROL_MODE(self) -> int: ...
    def GET_EXTERNAL_MOTION_CONTROL_TOLERANCE(self) -> float: ...
    def GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE(self) -> float: ...
    def GET_EXTERNAL_TOOL_SLOT(self) -> int: ...
    def GET_EXTERNAL_SELECTED_TOOL_SLOT(self) -> int: ...
    def GET_EXTERNAL_FEED_RATE(self) -> float: ...
    def GET_EXTERNAL_FLOOD(self) -> int: ...
    def GET_EXTERNAL_MIST(self) -> int: ...
    def GET_EXTERNAL_PLANE(self) -> int: ...
    def GET_EXTERNAL_TRAVERSE_RATE(self) -> float: ...
    def GET_EXTERNAL_FEED_OVERRIDE_ENABLE(self) -> int: ...
    def GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(self, spindle: int) -> int: ...
    def GET_EXTERNAL_ADAPTIVE_FEED_ENABLE(self) -> int: ...
    def GET_EXTERNAL_FEED_HOLD_ENABLE(self) -> int: ...
    def GET_EXTERNAL_SPEED(self, spindle: int) -> float: ...
    def GET_EXTERNAL_SPINDLE(self, spindle: int) -> int: ...
    def GET_EXTERNAL_TOOL_TABLE(self, idx: int) -> ToolEntry: ...
    def GET_EXTERNAL_TOOL_LENGTH_OFFSET(self) -> list[float]: ...
    def GET_EXTERNAL_DIGITAL_INPUT(self, index: int, default: int) -> int: ...
    def GET_EXTERNAL_ANALOG_INPUT(self, index: int, default: float) -> float: ...
    def GET_EXTERNAL_QUEUE_EMPTY(self) -> int: ...
    def GET_EXTERNAL_TC_FAULT(self) -> int: ...
    def GET_EXTERNAL_TC_REASON(self) -> int: ...
    def GET_EXTERNAL_AXIS_MASK(self) -> int: ...
    def GET_BLOCK_DELETE(self) -> bool: ...
    def SET_BLOCK_DELETE(self, state: bool) -> None: ...
    def GET_OPTIONAL_PROGRAM_STOP(self) -> bool: ...
    def SET_OPTIONAL_PROGRAM_STOP(self, state: bool) -> None: ...
    def find_tool_index(self, toolno: int) -> int: ...


_N_START = frozenset("\t /nN")


def _nline(text: str) -> str:
    """The N column: ``N`` + the block's N digits padded to 6, or ``N.....``."""
    if text[:1] not in _N_START:
        return "N..... "
    k = 0
    n = len(text)
    while k < n and k < 256 and text[k] in "\t /":
        k += 1
    if k < n and text[k] in "nN":
        k += 1
        m = k
        while m < n and m < 256 and "0" <= text[m] <= "9":
            m += 1
        digits = text[k:m]
        return "N" + digits + " " * max(0, 6 - len(digits))
    if k < 256:
        return "N..... "
    return ""


class PrintingCanon:
    """Prints canonical calls in rs274's format and keeps saicanon's world model."""

    def __init__(
        self,
        write: Callable[[str], object],
        tools: ToolTable | None = None,
        flush: Callable[[], object] = lambda: None,
    ) -> None:
        """``write`` takes each output line; ``flush`` is called every 4096 calls, so
        that a program that never ends (rs274 runs them forever too) does not pile up."""
        self.write = write
        self.flush = flush
        self.counter = 1
        self.linetext: Callable[[], str] = lambda: ""
        self._last_text: str | None = None
        self._last_prefix = "N..... "
        self.tools = tools if tools is not None else ToolTable()
        self.reset_world()

    def reset_world(self) -> None:
        self.active_plane = PLANE_XY
        self.active_slot = 1
        self.feed_mode = 0
        self.feed_rate = 0.0
        self.flood = 0
        self.mist = 0
        self.length_unit_type = UNITS_MM
        self.motion_mode = CONTINUOUS
        self.motion_tolerance = 0.0
        self.naivecam_tolerance = 0.0
        self.probe_position = [0.0] * 6
        self.g5x = [0.0] * 6
        self.g92 = [0.0] * 6
        self.position = [0.0] * 6
        self.spindle_speed = [0.0] * 8
        self.spindle_turning = [STOPPED] * 8
        self.traverse_rate = 0.0
        self.tool_offset = [0.0] * 9
        self.block_delete = True
        self.optional_program_stop = True
        self.fo_enable = 1
        self.so_enable = 1

    # ---------------------------------------------------------------- printing
    def emit(self, text: str) -> None:
        line = self.linetext()
        if line is not self._last_text:
            self._last_text = line
            self._last_prefix = _nline(line)
        self.write(f"{self.counter:5d} {self._last_prefix}{text}\n")
        self.counter += 1
        if not self.counter & 4095:
            self.flush()

    # ---------------------------------------------------------- representation
    def SET_XY_ROTATION(self, t: float) -> None:
        self.emit(f"SET_XY_ROTATION({t:.4f})")

    def SET_G5X_OFFSET(self, index, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self.emit(f"SET_G5X_OFFSET({index}, {x:.4f}, {y:.4f}, {z:.4f}, {a:.4f}, {b:.4f}, {c:.4f})")
        new = (x, y, z, a, b, c)
        pos, old = self.position, self.g5x
        for k in range(6):
            pos[k] = pos[k] + old[k] - new[k]
        self.g5x = list(new)

    def SET_G92_OFFSET(self, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self.emit(f"SET_G92_OFFSET({x:.4f}, {y:.4f}, {z:.4f}, {a:.4f}, {b:.4f}, {c:.4f})")
        new = (x, y, z, a, b, c)
        pos, old = self.position, self.g92
        for k in range(6):
            pos[k] = pos[k] + old[k] - new[k]
        self.g92 = list(new)

    def USE_LENGTH_UNITS(self, units: int) -> None:
        if units == UNITS_INCHES:
            self.emit("USE_LENGTH_UNITS(CANON_UNITS_INCHES)")
            if self.length_unit_type == UNITS_MM:
                self.length_unit_type = UNITS_INCHES
                self._scale(1 / 25.4, divide=25.4)
        elif units == UNITS_MM:
            self.emit("USE_LENGTH_UNITS(CANON_UNITS_MM)")
            if self.length_unit_type == UNITS_INCHES:
                self.length_unit_type = UNITS_MM
                self._scale(25.4, divide=None)
        else:
            self.emit("USE_LENGTH_UNITS(UNKNOWN)")

    def _scale(self, factor: float, divide: float | None) -> None:
        for vec in (self.position, self.g5x, self.g92):
            for k in range(3):
                vec[k] = vec[k] / divide if divide else vec[k] * factor

    # ------------------------------------------------------------------ motion
    def SET_TRAVERSE_RATE(self, rate: float) -> None:
        self.emit(f"SET_TRAVERSE_RATE({rate:.4f})")
        self.traverse_rate = rate

    # the two calls of nearly every line print inline (emit() unrolled) for speed
    def STRAIGHT_TRAVERSE(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        text = self.linetext()
        if text is not self._last_text:
            self._last_text = text
            self._last_prefix = _nline(text)
        self.write(
            f"{self.counter:5d} {self._last_prefix}STRAIGHT_TRAVERSE({x:.4f}, {y:.4f}, "
            f"{z:.4f}, {a:.4f}, {b:.4f}, {c:.4f})\n"
        )
        self.counter += 1
        if not self.counter & 4095:
            self.flush()
        self.position = [x, y, z, a, b, c]

    def STRAIGHT_FEED(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        text = self.linetext()
        if text is not self._last_text:
            self._last_text = text
            self._last_prefix = _nline(text)
        self.write(
            f"{self.counter:5d} {self._last_prefix}STRAIGHT_FEED({x:.4f}, {y:.4f}, "
            f"{z:.4f}, {a:.4f}, {b:.4f}, {c:.4f})\n"
        )
        self.counter += 1
        if not self.counter & 4095:
            self.flush()
        self.position = [x, y, z, a, b, c]

    def ARC_FEED(
        self,
        line,
        first_end,
        second_end,
        first_axis,
        second_axis,
        rotation,
        axis_end,
        a,
        b,
        c,
        u=0.0,
        v=0.0,
        w=0.0,
    ) -> None:
        self.emit(
            f"ARC_FEED({first_end:.4f}, {second_end:.4f}, {first_axis:.4f}, "
            f"{second_axis:.4f}, {rotation}, {axis_end:.4f}, {a:.4f}, {b:.4f}, {c:.4f})"
        )
        if self.active_plane == PLANE_XY:
            self.position = [first_end, second_end, axis_end, a, b, c]
        elif self.active_plane == PLANE_YZ:
            self.position = [axis_end, first_end, second_end, a, b, c]
        else:
            self.position = [second_end, axis_end, first_end, a, b, c]

    def STRAIGHT_PROBE(self, line, x, y, z, a, b, c, u, v, w, probe_type) -> None:
        pos = self.position
        dx, dy, dz = pos[0] - x, pos[1] - y, pos[2] - z
        distance = math.sqrt(dx * dx + dy * dy + dz * dz)
        self.emit(f"STRAIGHT_PROBE({x:.4f}, {y:.4f}, {z:.4f}, {a:.4f}, {b:.4f}, {c:.4f})")
        self.probe_position = [x, y, z, a, b, c]
        if distance != 0:
            backoff = 0.254 if self.length_unit_type == UNITS_MM else 0.01
            pos[0] = x + backoff * (dx / distance)
            pos[1] = y + backoff * (dy / distance)
            pos[2] = z + backoff * (dz / distance)
        pos[3], pos[4], pos[5] = a, b, c

    def NURBS_FEED(self, line, points: list[tuple[float, float, float]], order: int) -> None:
        """G5/G5.1/G5.2: saicanon prints only the number of control points."""
        self.emit(f"NURBS_FEED({len(points)}, ...)")
        # saicanon reads the point one past the end (undefined); the last one is our guess
        self.position[0], self.position[1] = points[-1][0], points[-1][1]

    def RIGID_TAP(self, line, x, y, z, scale) -> None:
        self.emit(f"RIGID_TAP({x:.4f}, {y:.4f}, {z:.4f})")

    def DWELL(self, seconds: float) -> None:
        self.emit(f"DWELL({seconds:.4f})")

    def SET_FEED_MODE(self, spindle: int, mode: int) -> None:
        self.emit(f"SET_FEED_MODE({spindle}, {mode})")
        self.feed_mode = mode

    def SET_FEED_RATE(self, rate: float) -> None:
        self.emit(f"SET_FEED_RATE({rate:.4f})")
        self.feed_rate = rate

    def SET_FEED_REFERENCE(self, reference: int) -> None:
        name = "CANON_WORKPIECE" if reference == CANON_WORKPIECE else "CANON_XYZ"
        self.emit(f"SET_FEED_REFERENCE({name})")

    def SET_MOTION_CONTROL_MODE(self, mode: int, tolerance: float) -> None:
        self.motion_tolerance = 0.0
        if mode == EXACT_STOP:
            self.emit("SET_MOTION_CONTROL_MODE(CANON_EXACT_STOP)")
            self.motion_mode = EXACT_STOP
        elif mode == EXACT_PATH:
            self.emit("SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)")
            self.motion_mode = EXACT_PATH
        elif mode == CONTINUOUS:
            self.motion_tolerance = tolerance
            self.emit(f"SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, {tolerance:f})")
            self.motion_mode = CONTINUOUS
        else:
            self.emit("SET_MOTION_CONTROL_MODE(UNKNOWN)")

    def SET_NAIVECAM_TOLERANCE(self, tolerance: float) -> None:
        self.naivecam_tolerance = tolerance
        self.emit(f"SET_NAIVECAM_TOLERANCE({tolerance:.4f})")

    def SELECT_PLANE(self, plane: int) -> None:
        self.emit(f"SELECT_PLANE(CANON_PLANE_{_PLANE_NAMES.get(plane, 'UNKNOWN')})")
        self.active_plane = plane

    def START_SPEED_FEED_SYNCH(self, spindle: int, sync: float, vel: bool) -> None:
        self.emit(f"START_SPEED_FEED_SYNC({sync:f},{int(vel)})")

    def STOP_SPEED_FEED_SYNCH(self) -> None:
        self.emit("STOP_SPEED_FEED_SYNCH()")

    # ----------------------------------------------------------------- spindle
    def SET_SPINDLE_MODE(self, spindle: int, arg: float) -> None:
        self.emit(f"SET_SPINDLE_MODE({spindle} {arg:.4f})")

    def START_SPINDLE_CLOCKWISE(self, spindle: int) -> None:
        self.emit(f"START_SPINDLE_CLOCKWISE({spindle})")
        if self._is_modelled(spindle):
            self.spindle_turning[spindle] = (
                STOPPED if self.spindle_speed[spindle] == 0 else CLOCKWISE
            )

    def START_SPINDLE_COUNTERCLOCKWISE(self, spindle: int) -> None:
        self.emit(f"START_SPINDLE_COUNTERCLOCKWISE({spindle})")
        if self._is_modelled(spindle):
            self.spindle_turning[spindle] = (
                STOPPED if self.spindle_speed[spindle] == 0 else COUNTERCLOCKWISE
            )

    def SET_SPINDLE_SPEED(self, spindle: int, rpm: float) -> None:
        self.emit(f"SET_SPINDLE_SPEED({spindle}, {rpm:.4f})")
        if self._is_modelled(spindle):
            self.spindle_speed[spindle] = rpm

    def STOP_SPINDLE_TURNING(self, spindle: int) -> None:
        self.emit(f"STOP_SPINDLE_TURNING({spindle})")
        if self._is_modelled(spindle):
            self.spindle_turning[spindle] = STOPPED

    def _is_modelled(self, spindle: int) -> bool:
        """Whether the world model keeps this spindle (the interpreter checks spindle
        numbers; a replayed call from canterp may name any)."""
        return 0 <= spindle < len(self.spindle_speed)

    def ORIENT_SPINDLE(self, spindle: int, orientation: float, mode: int) -> None:
        self.emit(f"ORIENT_SPINDLE({spindle}, {orientation:.4f}, {mode})")

    def WAIT_SPINDLE_ORIENT_COMPLETE(self, spindle: int, timeout: float) -> None:
        self.emit(f"SPINDLE.{spindle}.WAIT_ORIENT_COMPLETE({timeout:.4f})")

    # ------------------------------------------------------------------- tools
    def SET_TOOL_TABLE_ENTRY(
        self, idx, toolno, offset, diameter, frontangle, backangle, orientation
    ) -> None:
        entry = self.tools.get(idx)
        entry.toolno = toolno
        entry.offset = list(offset)
        entry.diameter = diameter
        entry.frontangle = frontangle
        entry.backangle = backangle
        entry.orientation = orientation
        self.tools.put(idx, entry)
        o = offset
        self.emit(
            f"SET_TOOL_TABLE_ENTRY({idx}, {toolno}, {o[0]:.4f} {o[1]:.4f} {o[2]:.4f} "
            f"{o[3]:.4f} {o[4]:.4f} {o[5]:.4f} {o[6]:.4f} {o[7]:.4f} {o[8]:.4f}, "
            f"{frontangle:.4f}, {backangle:.4f}, {orientation})"
        )

    def USE_TOOL_LENGTH_OFFSET(self, offset: list[float]) -> None:
        self.tool_offset = list(offset)
        o = offset
        self.emit(
            f"USE_TOOL_LENGTH_OFFSET({o[0]:.4f} {o[1]:.4f} {o[2]:.4f}, {o[3]:.4f} {o[4]:.4f} "
            f"{o[5]:.4f}, {o[6]:.4f} {o[7]:.4f} {o[8]:.4f})"
        )

    def CHANGE_TOOL(self, slot: int) -> None:
        self.emit(f"CHANGE_TOOL({slot})")
        self.active_slot = slot
        self.tools.put(0, self.tools.get(slot))

    def SELECT_TOOL(self, tool: int) -> None:
        self.emit(f"SELECT_TOOL({tool})")

    def CHANGE_TOOL_NUMBER(self, tool: int) -> None:
        self.emit(f"CHANGE_TOOL_NUMBER({tool})")
        self.active_slot = tool

    def RELOAD_TOOLDATA(self) -> None:
        self.emit("RELOAD_TOOLDATA()")

    def START_CHANGE(self) -> None:
        self.emit("START_CHANGE()")

    # -------------------------------------------------------------------- misc
    def COMMENT(self, text: str) -> None:
        self.emit(f'COMMENT("{text}")')

    def MESSAGE(self, text: str) -> None:
        self.emit(f'MESSAGE("{text}")')

    def CANON_ERROR(self, text: str) -> None:
        self.emit(f"CANON_ERROR({text})")

    def LOG(self, text: str) -> None:
        self.emit(f'LOG("{text}")')

    def LOGOPEN(self, text: str) -> None:
        self.emit(f'LOGOPEN("{text}")')

    def LOGAPPEND(self, text: str) -> None:
        self.emit(f'LOGAPPEND("{text}")')

    def LOGCLOSE(self) -> None:
        self.emit("LOGCLOSE()")

    def PRINT_LINE(self, text: str) -> None:
        """``(PRINT,...)``: rs274 writes the text straight to stdout."""
        self.write(text + "\n")

    def DISABLE_ADAPTIVE_FEED(self) -> None:
        self.emit("DISABLE_ADAPTIVE_FEED()")

    def ENABLE_ADAPTIVE_FEED(self) -> None:
        self.emit("ENABLE_ADAPTIVE_FEED()")

    def DISABLE_FEED_HOLD(self) -> None:
        self.emit("DISABLE_FEED_HOLD()")

    def ENABLE_FEED_HOLD(self) -> None:
        self.emit("ENABLE_FEED_HOLD()")

    def DISABLE_FEED_OVERRIDE(self) -> None:
        self.emit("DISABLE_FEED_OVERRIDE()")
        self.fo_enable = 0

    def ENABLE_FEED_OVERRIDE(self) -> None:
        self.emit("ENABLE_FEED_OVERRIDE()")
        self.fo_enable = 1

    def DISABLE_SPEED_OVERRIDE(self, spindle: int) -> None:
        self.emit(f"DISABLE_SPEED_OVERRIDE({spindle})")
        self.so_enable = 0

    def ENABLE_SPEED_OVERRIDE(self, spindle: int) -> None:
        self.emit(f"ENABLE_SPEED_OVERRIDE({spindle})")
        self.so_enable = 1

    def FLOOD_OFF(self) -> None:
        self.emit("FLOOD_OFF()")
        self.flood = 0

    def FLOOD_ON(self) -> None:
        self.emit("FLOOD_ON()")
        self.flood = 1

    def MIST_OFF(self) -> None:
        self.emit("MIST_OFF()")
        self.mist = 0

    def MIST_ON(self) -> None:
        self.emit("MIST_ON()")
        self.mist = 1

    def PALLET_SHUTTLE(self) -> None:
        self.emit("PALLET_SHUTTLE()")

    def TURN_PROBE_OFF(self) -> None:
        self.emit("TURN_PROBE_OFF()")

    def TURN_PROBE_ON(self) -> None:
        self.emit("TURN_PROBE_ON()")

    def PROGRAM_STOP(self) -> None:
        self.emit("PROGRAM_STOP()")

    def OPTIONAL_PROGRAM_STOP(self) -> None:
        self.emit("OPTIONAL_PROGRAM_STOP()")

    def PROGRAM_END(self) -> None:
        self.emit("PROGRAM_END()")

    def SET_MOTION_OUTPUT_BIT(self, index: int) -> None:
        self.emit(f"SET_MOTION_OUTPUT_BIT({index})")

    def CLEAR_MOTION_OUTPUT_BIT(self, index: int) -> None:
        self.emit(f"CLEAR_MOTION_OUTPUT_BIT({index})")

    def SET_MOTION_OUTPUT_VALUE(self, index: int, value: float) -> None:
        self.emit(f"SET_MOTION_OUTPUT_VALUE({index},{value:f})")

    def SET_AUX_OUTPUT_BIT(self, index: int) -> None:
        self.emit(f"SET_AUX_OUTPUT_BIT({index})")

    def CLEAR_AUX_OUTPUT_BIT(self, index: int) -> None:
        self.emit(f"CLEAR_AUX_OUTPUT_BIT({index})")

    def SET_AUX_OUTPUT_VALUE(self, index: int, value: float) -> None:
        self.emit(f"SET_AUX_OUTPUT_VALUE({index},{value:f})")

    def WAIT(self, index: int, input_type: int, wait_type: int, timeout: float) -> int:
        return 0

    def FINISH(self) -> None:
        self.emit("FINISH()")

    def ON_RESET(self) -> None:
        self.emit("ON_RESET()")

    def USER_DEFINED_FUNCTION(self, index: int, p: float, q: float) -> bool:
        """M100..M199: rs274 has no user functions, so every one is unknown."""
        return False

    # ------------------------------------------------------------- world model
    def GET_EXTERNAL_POSITION(self) -> list[float]:
        return [*self.position, 0.0, 0.0, 0.0]

    def GET_EXTERNAL_PROBE_POSITION(self) -> list[float]:
        return [*self.probe_position, 0.0, 0.0, 0.0]

    def GET_EXTERNAL_PROBE_TRIPPED_VALUE(self) -> int:
        return 0

    def GET_EXTERNAL_LENGTH_UNITS(self) -> float:
        return 0.03937007874016

    def GET_EXTERNAL_ANGLE_UNITS(self) -> float:
        return 1.0

    def GET_EXTERNAL_LENGTH_UNIT_TYPE(self) -> int:
        return self.length_unit_type

    def GET_EXTERNAL_MOTION_CONTROL_MODE(self) -> int:
        return self.motion_mode

    def GET_EXTERNAL_MOTION_CONTROL_TOLERANCE(self) -> float:
        return self.motion_tolerance

    def GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE(self) -> float:
        return self.naivecam_tolerance

    def GET_EXTERNAL_TOOL_SLOT(self) -> int:
        return self.active_slot

    def GET_EXTERNAL_SELECTED_TOOL_SLOT(self) -> int:
        return 0

    def GET_EXTERNAL_FEED_RATE(self) -> float:
        return self.feed_rate

    def GET_EXTERNAL_FLOOD(self) -> int:
        return self.flood

    def GET_EXTERNAL_MIST(self) -> int:
        return self.mist

    def GET_EXTERNAL_PLANE(self) -> int:
        return self.active_plane

    def GET_EXTERNAL_TRAVERSE_RATE(self) -> float:
        return self.traverse_rate

    def GET_EXTERNAL_FEED_OVERRIDE_ENABLE(self) -> int:
        return self.fo_enable

    def GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(self, spindle: int) -> int:
        return self.so_enable

    def GET_EXTERNAL_ADAPTIVE_FEED_ENABLE(self) -> int:
        return 0

    def GET_EXTERNAL_FEED_HOLD_ENABLE(self) -> int:
        return 1

    def GET_EXTERNAL_SPEED(self, spindle: int) -> float:
        return self.spindle_speed[spindle]

    def GET_EXTERNAL_SPINDLE(self, spindle: int) -> int:
        return self.spindle_turning[spindle]

    def GET_EXTERNAL_TOOL_TABLE(self, idx: int) -> ToolEntry:
        return self.tools.get(idx)

    def GET_EXTERNAL_TOOL_LENGTH_OFFSET(self) -> list[float]:
        return list(self.tool_offset)

    def GET_EXTERNAL_DIGITAL_INPUT(self, index: int, default: int) -> int:
        return default

    def GET_EXTERNAL_ANALOG_INPUT(self, index: int, default: float) -> float:
        return default

    def GET_EXTERNAL_QUEUE_EMPTY(self) -> int:
        return 1

    def GET_EXTERNAL_TC_FAULT(self) -> int:
        return 0

    def GET_EXTERNAL_TC_REASON(self) -> int:
        return 0

    def GET_EXTERNAL_AXIS_MASK(self) -> int:
        return 0x3F

    def GET_BLOCK_DELETE(self) -> bool:
        return self.block_delete

    def SET_BLOCK_DELETE(self, state: bool) -> None:
        self.block_delete = state

    def GET_OPTIONAL_PROGRAM_STOP(self) -> bool:
        return self.optional_program_stop

    def SET_OPTIONAL_PROGRAM_STOP(self, state: bool) -> None:
        self.optional_program_stop = state

    def find_tool_index(self, toolno: int) -> int:
        return self.tools.find_index_for_tool(toolno)
