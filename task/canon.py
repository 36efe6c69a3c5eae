"""Task's canon: canonical machining calls -> NML messages in machine units (TASK-005).

The equivalent of LinuxCNC's ``emccanon.cc``. The interpreter (``task.interp``) calls the
methods of ``task.interp.canon.Canon`` on a ``TaskCanon``; every call that has an effect on
the machine appends NML messages to ``TaskCanon.out``, in program order, for task to execute
(the interpreter list). Calls that ask about the world (``GET_EXTERNAL_*``) are answered
from the latest ``EMC_STAT`` task gave to ``set_status`` and from the canon's own state.

Units and coordinates
---------------------
The interpreter passes positions in program units (G20/G21) in the active coordinate system,
without G5x, G92 or tool length offsets. The canon keeps its state (offsets, rotation, the
end point of the last move, feed rate, tolerances) in machine units ([TRAJ]LINEAR_UNITS;
degrees for A B C) and turns a program position into a machine position with one transform,
``to_machine``: scale the lengths, add the G92 offset, rotate XY about the origin by the
G5x rotation (G10 L2 R), add the G5x offset and then the tool length offset. ``to_program``
is its inverse, used for the ``GET_EXTERNAL_*`` answers the interpreter's ``synch()`` needs.
Feed rates are program units/minute on the way in and machine units/second on the way out.

Velocity and acceleration of a move are limited per axis along its direction, as
emccanon's getStraightVelocity/getStraightAcceleration do: the time each moving axis needs
at its [AXIS_L]MAX_VELOCITY (MAX_ACCELERATION) gives the longest time, and the path length
over that time is the move's ``ini_maxvel`` (``acc``). Rapids move at that limit; feeds at
the lower of it and the feed rate. Arcs are also limited by the centripetal acceleration
their radius allows.

With naive CAM on (G64 P.. Q..), feed moves (G1, and arcs flat enough) are held back so
that collinear-enough segments are joined into one move: the last one is queued only by the
next canon call that queues anything, or by ``FINISH()``. Task calls ``FINISH()`` after each
MDI command (as LinuxCNC's emcTaskPlanExecute does); the interpreter calls it at the end of
a program. Without naive CAM, a feed is queued at once (emccanon holds every feed back
until the next call; the order of the messages is the same).

Routing assumed for the messages of ``out`` (what task does with them)
-------------------------------------------------------------------------
- motion: EMC_TRAJ_* (moves, EMC_TRAJ_SET_MOTION_ID, term condition, offsets, G5x, G92,
  rotation, spindle sync, override enables, probe flag), EMC_MOTION_SET_DOUT/AOUT,
  EMC_MOTION_ADAPTIVE and EMC_SPINDLE_* — except EMC_TRAJ_DELAY;
- task itself: EMC_TRAJ_DELAY (G4: task waits ``delay`` seconds once motion is done,
  as LinuxCNC does), EMC_TASK_PLAN_PAUSE (M0, M60), EMC_TASK_PLAN_OPTIONAL_STOP (M1: pause
  when the optional stop switch is on), EMC_TASK_PLAN_END (M2, M30), EMC_OPERATOR_DISPLAY
  ((MSG,...)) and EMC_OPERATOR_ERROR (canon errors) to the error channel, EMC_SYSTEM_CMD
  (user M100..M199: run the program and wait for it);
- iocontrol: EMC_TOOL_* (PREPARE for Tn with the tool number, START_CHANGE and LOAD for M6,
  SET_NUMBER for M61 with the tool's tooldata index, SET_OFFSET for G10 L1/L10/L11,
  LOAD_TOOL_TABLE), EMC_COOLANT_*, EMC_AUX_INPUT_WAIT (M66; task waits for the input).

Each move is preceded by EMC_TRAJ_SET_MOTION_ID(id=line) when its interpreter line
differs from the previous move's, so motion reports the line it executes; and each move
carries the interpreter's last state tag (``UPDATE_TAG``, task/interp/statetag.py), which
motion reports while it carries the move out.

World model
-----------
``set_status(stat)`` must be called with a fresh EMC_STAT before the interpreter synchs
(``init()``, and after each queue buster has finished). ``tools`` is the tool table the
canon answers GET_EXTERNAL_TOOL_TABLE and tool number look-ups from: the table given to
the constructor (or assigned to ``tools``), else, as emccanon reads LinuxCNC's tool data,
iocontrol's shared tool data store (``iocontrol.tooldata``), read again whenever iocontrol
has changed it. SET_TOOL_TABLE_ENTRY also writes the entry into it, so a synch before
iocontrol has done so sees a G10 L1 change too.
A new canon's ``out`` already holds one message, INIT_CANON's default blending
(EMC_TRAJ_SET_TERM_COND: blend within 0.001 inch). ``program_units`` is the program's
length unit (G20/G21), for EMC_TASK_STAT.programUnits.

Deviations from emccanon
------------------------
- Every message, including SET_XY_ROTATION, SELECT_TOOL, CHANGE_TOOL_NUMBER and
  TURN_PROBE_ON, is queued after any held-back feed segments, so ``out`` is always in
  program order (emccanon appends some of them ahead of a pending segment).
- RIGID_TAP computes its limits from the end point after the pending segments are queued.
- An axis without a velocity (acceleration) limit (``inf``) takes no time; a move none of
  whose axes is limited moves at [TRAJ]MAX_LINEAR_VELOCITY / MAX_LINEAR_ACCELERATION
  (emccanon has no unlimited axes).
- Hot comments: PROBEOPEN/PROBECLOSE are supported, RPY is not; LOG* write only the log
  file (not stderr).
- UNLOCK_ROTARY/LOCK_ROTARY (indexing rotaries), PLUGIN_CALL and IO_PLUGIN_CALL are not
  part of the interpreter's canon and are not implemented.
"""

from __future__ import annotations

import functools
import math
import os
import struct
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import IO

from cnc.inischema import DEFAULT_BLEND_TOLERANCE_MM
from iocontrol.tooldata import ToolDataError, ToolDataReader
from iocontrol.tooltable import CANON_POCKETS_MAX, ToolEntry, ToolTable
from nml import emc
from nml.axes import NUM_AXES
from nml.message import RCS_CMD_MSG
from task.interp import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from task.interp import statetag

MM_PER_INCH = 25.4
LINEAR_AXES = (0, 1, 2, 6, 7, 8)  # X Y Z U V W
ANGULAR_AXES = (3, 4, 5)  # A B C
# displacements below this (machine units) do not count as motion (posemath's CART_FUZZ)
CART_FUZZ = 1.0e-8
# arcs: smallest angle between start and end before a full circle is meant
MIN_ARC_ANGLE = 1.0e-12
# millimetres per program length unit (G20, G21, and centimetres)
_MM_PER_UNIT = {C.UNITS_INCHES: MM_PER_INCH, C.UNITS_MM: 1.0, C.UNITS_CM: 10.0}
# the axes of each plane: (first axis, second axis, normal axis), X=0 Y=1 Z=2
_PLANE_AXES = {C.PLANE_XY: (0, 1, 2), C.PLANE_YZ: (1, 2, 0), C.PLANE_XZ: (2, 0, 1)}


def _state_tag_layout() -> tuple[struct.Struct, tuple[slice, ...]]:
    """How a tag (task/interp/statetag.py: LinuxCNC's state_tag_t order) packs into
    ``emc.StateTag``'s bytes: the layout, and the tag's slices in the order the struct's
    layout has its three fields (by offset: nml does not keep their declared order,
    ``fields`` being also a name of its Struct)."""
    parts = {
        "fields_float": ("5f", slice(0, statetag.FLOAT_FIELDS)),
        "fields": ("8i", slice(statetag.FLOAT_FIELDS, statetag.FLAGS)),
        "packed_flags": ("Q", slice(statetag.FLAGS, statetag.FLAGS + 1)),
    }
    fields = emc.StateTag.dtype.fields
    order = sorted(parts, key=lambda name: fields[name][1])
    layout = struct.Struct("<" + "".join(parts[name][0] for name in order))
    if layout.size != emc.StateTag.dtype.itemsize:
        raise AssertionError("StateTag's layout is not LinuxCNC's state_tag_t")
    return layout, tuple(parts[name][1] for name in order)


_TAG_LAYOUT, (_TAG_FIRST, _TAG_SECOND, _TAG_THIRD) = _state_tag_layout()
_TAG_SIZE = _TAG_LAYOUT.size
# where each value _TAG_LAYOUT unpacks goes in a tag
_TAG_POSITIONS = tuple(
    index
    for part in (_TAG_FIRST, _TAG_SECOND, _TAG_THIRD)
    for index in range(part.start, part.stop)
)


def state_tag_bytes(tag: tuple) -> bytes:
    """An interpreter's state tag as the bytes of ``emc.StateTag``."""
    return _TAG_LAYOUT.pack(*tag[_TAG_FIRST], *tag[_TAG_SECOND], *tag[_TAG_THIRD])


def state_tag_of(tag: emc.StateTag) -> tuple:
    """The interpreter's form of the state tag a message or a status carries."""
    values = [0] * len(_TAG_POSITIONS)
    for index, value in zip(_TAG_POSITIONS, _TAG_LAYOUT.unpack(tag.to_bytes()), strict=True):
        values[index] = value
    return tuple(values)


@functools.cache
def _tag_offset(message: type[RCS_CMD_MSG]) -> int:
    """Where a move message's ``tag`` starts in its bytes (written in place: assigning the
    struct costs more than the rest of queueing the move)."""
    return message.dtype.fields["tag"][1]


@dataclass
class CanonSetup:
    """The machine as the canon needs it; built by task from the INI file."""

    linear_units: str  # [TRAJ]LINEAR_UNITS: "mm" or "inch" (machine units)
    axis_mask: int  # bit n set for axis n of XYZABCUVW present ([TRAJ]COORDINATES)
    axis_max_vel: list[float]  # 9 values, machine units/s ([AXIS_L]MAX_VELOCITY; inf if absent)
    axis_max_acc: list[float]  # 9 values, machine units/s^2
    max_velocity: float  # [TRAJ]MAX_LINEAR_VELOCITY (machine units/s), inf if absent
    max_acceleration: float  # [TRAJ]MAX_LINEAR_ACCELERATION, inf if absent
    random_toolchanger: bool = False
    # [EMCIO]TOOL_CHANGE_POSITION in machine units: 3, 6 or 9 values (XYZ[ABC[UVW]]), or None
    tool_change_position: list[float] | None = None
    # user M codes: M number (100..199) -> program to run with P and Q as arguments
    user_m_commands: dict[int, str] = field(default_factory=dict)
    # folders (PROBEOPEN), LOGOPEN and LOGAPPEND may write in; None: anywhere
    writable_dirs: list[str] | None = None


@dataclass
class _Straight:
    """Limits of a straight move from the end point: ``t_vel`` (``t_acc``) is the time the
    slowest axis needs at its velocity (acceleration) limit, ``vel`` (``acc``) the path
    velocity (acceleration) that keeps every axis within its limits."""

    is_linear: bool
    is_angular: bool
    vel: float
    acc: float
    t_vel: float
    t_acc: float


@dataclass
class _Spindle:
    speed: float = 0.0  # rpm, or surface speed in CSS mode
    direction: int = 0  # 1 forward, -1 reverse, 0 off
    css_maximum: float = 0.0  # G96 D: maximum rpm; 0 when not in CSS mode
    is_synched: bool = False


def _rotate(x: float, y: float, degrees: float) -> tuple[float, float]:
    t = math.radians(degrees)
    cos_t, sin_t = math.cos(t), math.sin(t)
    return x * cos_t - y * sin_t, x * sin_t + y * cos_t


def _ratio(length: float, seconds: float, fallback: float) -> float:
    """``length / seconds``; ``fallback`` when no axis limit made the move take time."""
    return length / seconds if seconds > 0.0 else fallback


def _seconds(length: float, rate: float) -> float:
    """The time to cover ``length`` at ``rate`` (forever at a zero rate)."""
    if rate == 0.0:
        return math.inf if length else 0.0
    return length / rate


def _chord_deviation(
    sx: float, sy: float, ex: float, ey: float, cx: float, cy: float, rotation: int
) -> tuple[float, float, float]:
    """How far an XY arc strays from its chord, and the arc's middle point (x, y)."""
    th1 = math.atan2(sy - cy, sx - cx)
    th2 = math.atan2(ey - cy, ex - cx)
    radius = math.hypot(sy - cy, sx - cx)
    # twice, for atan2 answering -pi at one end and pi at the other
    for _ in range(2):
        if rotation < 0 and th2 - th1 >= -1e-5:
            th2 -= 2 * math.pi
        elif rotation >= 0 and th2 - th1 <= 1e-5:
            th2 += 2 * math.pi
    included = abs(th2 - th1)
    mid = (th1 + th2) / 2
    deviation = radius * (1 - math.cos(included / 2))
    return deviation, cx + radius * math.cos(mid), cy + radius * math.sin(mid)


def _initial_status(setup: CanonSetup) -> emc.EMC_STAT:
    """The world before task reports one: at rest at zero, nothing prepared, overrides on."""
    stat = emc.EMC_STAT()
    traj = stat.motion.traj
    traj.maxVelocity = setup.max_velocity
    traj.axis_mask = setup.axis_mask
    traj.feed_override_enabled = True
    traj.feed_hold_enabled = True
    for spindle in stat.motion.spindle:
        spindle.spindle_override_enabled = True
    stat.io.tool.pocketPrepped = -1
    return stat


class TaskCanon:
    """Implements ``task.interp.canon.Canon`` for task: queues NML messages in ``out``."""

    def __init__(self, setup: CanonSetup, tools: ToolTable | None = None) -> None:
        self.setup = setup
        self._tools = tools if tools is not None else ToolTable(setup.random_toolchanger)
        self._is_tool_table_given = tools is not None
        self._tool_data: ToolDataReader | None = None
        self._tool_data_sequence = -1
        self.out: deque[RCS_CMD_MSG] = deque()
        self.linetext = lambda: ""  # replaced by the interpreter
        is_inch_machine = setup.linear_units.lower().startswith("in")
        self._machine_mm = MM_PER_INCH if is_inch_machine else 1.0
        self._stat = _initial_status(setup)
        self._probe_file: IO[str] | None = None
        self._last_probed: list[float] | None = None
        self._log_file: IO[str] | None = None
        self._init_canon(C.UNITS_INCHES if is_inch_machine else C.UNITS_MM)

    def _init_canon(self, machine_units: int) -> None:
        """emccanon's INIT_CANON: everything at its start-up value."""
        self.program_units = machine_units
        self.g5x_index = 1
        self.g5x = [0.0] * NUM_AXES
        self.g92 = [0.0] * NUM_AXES
        self.rotation = 0.0  # degrees
        self.tool_offset = [0.0] * NUM_AXES
        self.end_point = [0.0] * NUM_AXES  # machine position where the last move ends
        self.plane = C.PLANE_XY
        self.feed_mode = 0  # 1: feed per revolution (G95), synched to spindle_num
        self.spindle_num = 0
        self.linear_feed_rate = 0.0  # machine units/s; program units/rev in feed_mode
        self.angular_feed_rate = 0.0  # degrees/s
        self.motion_mode = C.CONTINUOUS
        self.motion_tolerance = 0.0  # machine units
        self.naivecam_tolerance = 0.0  # machine units
        self.spindles = [_Spindle() for _ in range(emc.EMC_MAX_SPINDLES)]
        self.is_block_delete_on = True
        self.is_optional_stop_on = True
        self._chain: list[tuple[int, list[float]]] = []  # held-back feeds: (line, end)
        self._tag: tuple | None = None  # the interpreter's last UPDATE_TAG (statetag.py)
        self._chain_tag: tuple | None = None  # ... when the last held-back feed was seen
        self._tag_packed: tuple[tuple | None, bytes] = (None, bytes(_TAG_SIZE))
        self._motion_line: int | None = None  # line of the last EMC_TRAJ_SET_MOTION_ID
        # the default blending tolerance is 0.001 inch (motion starts with it too)
        self.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, DEFAULT_BLEND_TOLERANCE_MM / self._mm_per_unit)

    # ================================================================ world model
    def set_status(self, stat: emc.EMC_STAT) -> None:
        """Feed the world model from task's latest EMC_STAT (TASK-009)."""
        self._stat = stat

    @property
    def tools(self) -> ToolTable:
        """The tool table (machine units): the one given to the canon, else iocontrol's
        shared tool data, read again whenever iocontrol has changed it."""
        if not self._is_tool_table_given:
            self._refresh_tool_data()
        return self._tools

    @tools.setter
    def tools(self, table: ToolTable) -> None:
        self._tools = table
        self._is_tool_table_given = True

    def _refresh_tool_data(self) -> None:
        try:
            if self._tool_data is None:
                self._tool_data = ToolDataReader()
            sequence = self._tool_data.sequence
            if sequence != self._tool_data_sequence:
                self._tools = self._tool_data.read()
                self._tool_data_sequence = sequence
        except ToolDataError:
            pass  # no iocontrol (yet): keep the table we have

    # ================================================================ transforms
    @property
    def _mm_per_unit(self) -> float:
        return _MM_PER_UNIT.get(self.program_units, 1.0)

    @property
    def _scale(self) -> float:
        """Machine length units per program length unit."""
        return self._mm_per_unit / self._machine_mm

    def _from_program(self, values: Sequence[float]) -> list[float]:
        """Program units -> machine units, lengths only (offsets and angles unchanged)."""
        s = self._scale
        return [v if k in ANGULAR_AXES else v * s for k, v in enumerate(values)]

    def _to_program_units(self, values: Sequence[float]) -> list[float]:
        s = self._scale
        return [v if k in ANGULAR_AXES else v / s for k, v in enumerate(values)]

    def to_machine(self, program: Sequence[float]) -> list[float]:
        """A program position (9 axes, active coordinate system) in machine coordinates."""
        p = self._from_program(program)
        p = [p[k] + self.g92[k] for k in range(NUM_AXES)]
        p[0], p[1] = _rotate(p[0], p[1], self.rotation)
        return [p[k] + self.g5x[k] + self.tool_offset[k] for k in range(NUM_AXES)]

    def to_program(self, machine: Sequence[float]) -> list[float]:
        """The inverse of ``to_machine``."""
        p = [machine[k] - self.tool_offset[k] - self.g5x[k] for k in range(NUM_AXES)]
        p[0], p[1] = _rotate(p[0], p[1], -self.rotation)
        p = [p[k] - self.g92[k] for k in range(NUM_AXES)]
        return self._to_program_units(p)

    # ================================================================ queueing
    def _queue(self, msg: RCS_CMD_MSG) -> None:
        """Queue a message after any held-back feed segments."""
        self._flush()
        self.out.append(msg)

    def _queue_move(self, line: int, msg: RCS_CMD_MSG, tag: tuple | None = None) -> None:
        """Queue a move with its state tag (default: the interpreter's last), announcing
        its line to motion when the line changes."""
        if line != self._motion_line:
            self.out.append(emc.EMC_TRAJ_SET_MOTION_ID(id=line))
            self._motion_line = line
        at = _tag_offset(type(msg))
        msg.byte_view()[at : at + _TAG_SIZE] = self._packed_tag(self._tag if tag is None else tag)
        self.out.append(msg)

    def UPDATE_TAG(self, tag: tuple) -> None:
        """The interpreter's modal state (task/interp/statetag.py), which the moves queued
        from now on carry to motion, as emccanon's UPDATE_TAG."""
        self._tag = tag

    def _packed_tag(self, tag: tuple | None) -> bytes:
        """``tag`` as StateTag bytes (packed once per tag: many moves may share one)."""
        packed_from, packed = self._tag_packed
        if tag is not packed_from:
            packed = bytes(_TAG_SIZE) if tag is None else state_tag_bytes(tag)
            self._tag_packed = (tag, packed)
        return packed

    def _error(self, text: str) -> None:
        """emccanon's CANON_ERROR: a message for the operator's error channel."""
        self._queue(emc.EMC_OPERATOR_ERROR(id=0, error=emc.fit_text(text)))

    def CANON_ERROR(self, text: str) -> None:
        """emccanon.CANON_ERROR of Python code: an error message for every UI."""
        self._error(text)

    # ================================================================ limits
    def _straight(self, end: Sequence[float]) -> _Straight:
        """Velocity and acceleration limits of a straight move from the end point to ``end``."""
        mask = self.setup.axis_mask
        d = [abs(end[k] - self.end_point[k]) for k in range(NUM_AXES)]
        d = [dk if mask & (1 << k) and dk >= CART_FUZZ else 0.0 for k, dk in enumerate(d)]
        is_linear = any(d[k] > 0.0 for k in LINEAR_AXES)
        is_angular = any(d[k] > 0.0 for k in ANGULAR_AXES)
        if not (is_linear or is_angular):
            return _Straight(False, False, self.linear_feed_rate, 0.0, 0.0, 0.0)
        max_vel, max_acc = self.setup.axis_max_vel, self.setup.axis_max_acc
        t_vel = max(d[k] / max_vel[k] for k in range(NUM_AXES) if d[k] > 0.0)
        t_acc = max(d[k] / max_acc[k] for k in range(NUM_AXES) if d[k] > 0.0)
        # the path length is XYZ's, else UVW's; a purely rotary move's is ABC's
        if not is_linear:
            length = math.hypot(d[3], d[4], d[5])
        elif d[0] or d[1] or d[2]:
            length = math.hypot(d[0], d[1], d[2])
        else:
            length = math.hypot(d[6], d[7], d[8])
        vel = _ratio(length, t_vel, self.setup.max_velocity)
        acc = _ratio(length, t_acc, self.setup.max_acceleration)
        return _Straight(is_linear, is_angular, vel, acc, t_vel, t_acc)

    def _is_synched(self) -> bool:
        """Whether feed moves now follow a spindle (START_SPEED_FEED_SYNCH)."""
        return any(spindle.is_synched for spindle in self.spindles)

    def _feed_velocity(self, limits: _Straight) -> float:
        """The requested velocity of a feed move: the feed rate, within the axis limits.
        A spindle-synchronised move (G33, G76, G95) asks for the limit: motion takes its
        speed from the spindle."""
        if self._is_synched():
            return limits.vel
        if limits.is_angular and not limits.is_linear:
            return min(limits.vel, self.angular_feed_rate)
        if limits.is_linear:
            return min(limits.vel, self.linear_feed_rate)
        return limits.vel

    # ================================================================ straight moves
    def _traverse_to(self, line: int, end: list[float], motion_type: int) -> None:
        """A rapid to a machine position, outside of spindle synchronisation."""
        self._flush()
        limits = self._straight(end)
        is_feed_synched = self.feed_mode != 0
        if is_feed_synched:
            self.STOP_SPEED_FEED_SYNCH()
        if limits.vel and limits.acc:
            msg = emc.EMC_TRAJ_LINEAR_MOVE(
                type=motion_type,
                end=emc.EmcPose.of(end),
                vel=limits.vel,
                ini_maxvel=limits.vel,
                acc=limits.acc,
                feed_mode=0,
                indexer_jnum=-1,
            )
            self._queue_move(line, msg)
        if is_feed_synched:
            self.START_SPEED_FEED_SYNCH(self.spindle_num, self.linear_feed_rate, True)
        self.end_point = end

    def STRAIGHT_TRAVERSE(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        end = self.to_machine((x, y, z, a, b, c, u, v, w))
        self._traverse_to(line, end, emc.EMC_MOTION_TYPE.TRAVERSE)

    def STRAIGHT_FEED(self, line, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self._see_segment(line, self.to_machine((x, y, z, a, b, c, u, v, w)))

    def _see_segment(self, line: int, end: list[float]) -> None:
        """Hold a feed segment back while naive CAM may join it to the next ones (G64 with
        a Q tolerance); a rotary or UVW move is never held."""
        if self._chain and not self._is_linkable(end):
            self._flush()
        self._chain.append((line, end))
        self._chain_tag = self._tag  # (the joined move carries the last segment's tag)
        if not self._is_naivecam_on() or end[3:] != self.end_point[3:]:
            self._flush()

    def _is_naivecam_on(self) -> bool:
        return self.motion_mode == C.CONTINUOUS and self.naivecam_tolerance > 0.0

    def _is_linkable(self, end: list[float]) -> bool:
        if not self._is_naivecam_on():
            return False
        if len(self._chain) > 100 or end[3:] != self._chain[-1][1][3:]:
            return False
        start = self.end_point[:3]
        m = [end[k] - start[k] for k in range(3)]
        length_sq = sum(mk * mk for mk in m)
        if length_sq == 0.0:
            return False
        for _, point in self._chain:
            p = [point[k] - start[k] for k in range(3)]
            t = min(1.0, max(0.0, sum(p[k] * m[k] for k in range(3)) / length_sq))
            if math.dist(p, [t * mk for mk in m]) > self.naivecam_tolerance:
                return False
        return True

    def _flush(self) -> None:
        """Queue the held-back feed segments as one move to the last one's end."""
        if not self._chain:
            return
        line, end = self._chain[-1]
        self._chain.clear()
        tag = self._chain_tag
        limits = self._straight(end)
        vel = self._feed_velocity(limits)
        if vel and limits.acc:
            msg = emc.EMC_TRAJ_LINEAR_MOVE(
                type=emc.EMC_MOTION_TYPE.FEED,
                end=emc.EmcPose.of(end),
                vel=vel,
                ini_maxvel=limits.vel,
                acc=limits.acc,
                feed_mode=self.feed_mode,
                indexer_jnum=-1,
            )
            self._queue_move(line, msg, tag)
        self.end_point = end

    def _drop(self) -> None:
        self._chain.clear()

    def STRAIGHT_PROBE(self, line, x, y, z, a, b, c, u, v, w, probe_type) -> None:
        end = self.to_machine((x, y, z, a, b, c, u, v, w))
        self._flush()
        limits = self._straight(end)
        vel = self._feed_velocity(limits)
        if vel and limits.acc:
            msg = emc.EMC_TRAJ_PROBE(
                pos=emc.EmcPose.of(end),
                type=emc.EMC_MOTION_TYPE.PROBING,
                vel=vel,
                ini_maxvel=limits.vel,
                acc=limits.acc,
                probe_type=probe_type,
            )
            self._queue_move(line, msg)
        self.end_point = end

    def RIGID_TAP(self, line, x, y, z, scale) -> None:
        """G33.1: to (x, y, z) and back again, so the end point stays where it is."""
        self._flush()
        end = [*self.to_machine((x, y, z, 0, 0, 0, 0, 0, 0))[:3], *self.end_point[3:]]
        limits = self._straight(end)
        if limits.vel and limits.acc:
            msg = emc.EMC_TRAJ_RIGID_TAP(
                pos=emc.EmcPose.of(end),
                vel=limits.vel,
                ini_maxvel=limits.vel,
                acc=limits.acc,
                scale=scale,
            )
            self._queue_move(line, msg)

    # ================================================================ arcs
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
        """An arc (helix) in the active plane, ``rotation`` turns (< 0: clockwise)."""
        if self.plane == C.PLANE_XY and self.motion_mode == C.CONTINUOUS:
            is_chained = self._chain_arc(
                line,
                first_end,
                second_end,
                first_axis,
                second_axis,
                rotation,
                axis_end,
                (a, b, c, u, v, w),
            )
            if is_chained:
                return
        self._flush()
        if self.plane not in _PLANE_AXES:
            self._error("Can't set plane in UVW axes, assuming XY")
        i1, i2, normal_axis = _PLANE_AXES.get(self.plane, _PLANE_AXES[C.PLANE_XY])
        end_prog = [0.0, 0.0, 0.0, a, b, c, u, v, w]
        center_prog = [0.0] * NUM_AXES
        end_prog[i1], end_prog[i2], end_prog[normal_axis] = first_end, second_end, axis_end
        center_prog[i1], center_prog[i2] = first_axis, second_axis
        center_prog[normal_axis] = axis_end
        end = self.to_machine(end_prog)
        center = self.to_machine(center_prog)[:3]
        # the plane's unit vectors, turned by the XY rotation like the points
        basis = []
        for axis in (i1, i2, normal_axis):
            unit = [0.0, 0.0, 0.0]
            unit[axis] = 1.0
            unit[0], unit[1] = _rotate(unit[0], unit[1], self.rotation)
            basis.append(unit)
        plane_x, plane_y, normal = basis

        def in_plane(point: Sequence[float]) -> tuple[float, float]:
            rel = [point[k] - center[k] for k in range(3)]
            return _dot(rel, plane_x), _dot(rel, plane_y)

        start_1, start_2 = in_plane(self.end_point)
        end_1, end_2 = in_plane(end)
        theta_start = math.atan2(start_2, start_1)
        theta_end = math.atan2(end_2, end_1)
        start_radius = math.hypot(start_1, start_2)
        end_radius = math.hypot(end_1, end_2)
        # the end angle past the start angle in the direction of rotation
        if rotation < 0:
            if theta_end + MIN_ARC_ANGLE >= theta_start:
                theta_end -= 2 * math.pi
        elif theta_end - MIN_ARC_ANGLE <= theta_start:
            theta_end += 2 * math.pi
        # rotation 1 or -1 is less than a turn; each unit more is a full turn more
        full_turns = rotation - 1 if rotation > 1 else rotation + 1 if rotation < -1 else 0
        full_angle = theta_end - theta_start + 2 * math.pi * full_turns
        v_max, a_max = self._arc_limits(
            end, (i1, i2, normal_axis), normal, (start_radius, end_radius), full_angle
        )
        vel = v_max if self._is_synched() else min(self.linear_feed_rate, v_max)

        if rotation == 0:
            msg: RCS_CMD_MSG = emc.EMC_TRAJ_LINEAR_MOVE(
                type=emc.EMC_MOTION_TYPE.ARC,
                end=emc.EmcPose.of(end),
                vel=vel,
                ini_maxvel=v_max,
                acc=a_max,
                feed_mode=self.feed_mode,
                indexer_jnum=-1,
            )
        else:
            msg = emc.EMC_TRAJ_CIRCULAR_MOVE(
                end=emc.EmcPose.of(end),
                center=emc.PmCartesian(x=center[0], y=center[1], z=center[2]),
                normal=emc.PmCartesian(x=normal[0], y=normal[1], z=normal[2]),
                turn=rotation - 1 if rotation > 0 else rotation,
                type=emc.EMC_MOTION_TYPE.ARC,
                vel=vel,
                ini_maxvel=v_max,
                acc=a_max,
                feed_mode=self.feed_mode,
            )
        if vel and a_max:
            self._queue_move(line, msg)
        self.end_point = end

    def _arc_limits(
        self,
        end: list[float],
        axes: tuple[int, int, int],
        normal: list[float],
        radii: tuple[float, float],
        full_angle: float,
    ) -> tuple[float, float]:
        """``ini_maxvel`` and ``acc`` of an arc (spiral, helix) from the end point to ``end``
        turning ``full_angle`` radians about ``normal``: within the plane's axis limits and
        the centripetal acceleration its radius allows, and within the limits of the helix
        axis and the other axes like a straight move."""
        i1, i2, normal_axis = axes
        start_radius, end_radius = radii
        spiral = end_radius - start_radius
        min_radius = min(start_radius, end_radius)
        effective_radius = math.hypot(spiral / abs(full_angle), min_radius)
        max_vel, max_acc = self.setup.axis_max_vel, self.setup.axis_max_acc
        v_max_axes = min(max_vel[i1], max_vel[i2])
        a_max_axes = min(max_acc[i1], max_acc[i2])
        if self.rotation and self.plane != C.PLANE_XY and self.setup.axis_mask & (1 << normal_axis):
            # rotated, the plane involves the normal axis too
            v_max_axes = min(v_max_axes, max_vel[normal_axis])
            a_max_axes = min(a_max_axes, max_acc[normal_axis])
        # only part of the acceleration may go to turning (the rest is for speeding up)
        a_max_normal = a_max_axes * math.sqrt(3.0) / 2.0
        v_max_planar = min(math.sqrt(a_max_normal * effective_radius), v_max_axes)

        limits = self._straight(end)  # the helix axis and the other axes
        spiral_length = math.hypot(min_radius * abs(full_angle), spiral)
        axis_length = _dot([end[k] - self.end_point[k] for k in range(3)], normal)
        total_length = math.hypot(spiral_length, axis_length)
        t_vel = max(limits.t_vel, _seconds(spiral_length, v_max_planar))
        t_acc = max(limits.t_acc, _seconds(spiral_length, a_max_axes))
        v_max = _ratio(total_length, t_vel, self.setup.max_velocity)
        a_max = _ratio(total_length, t_acc, self.setup.max_acceleration)
        return v_max, a_max

    def _chain_arc(
        self,
        line: int,
        first_end: float,
        second_end: float,
        first_axis: float,
        second_axis: float,
        rotation: int,
        axis_end: float,
        others: Sequence[float],
    ) -> bool:
        """Naive CAM: an XY arc closer to its chord than the tolerance becomes two feed
        segments (through the arc's middle). False when the arc must stay an arc."""
        if self._chain:
            lx, ly, lz = self._chain[-1][1][:3]
        else:
            lx, ly, lz = self.end_point[:3]
        ex, ey, ez = self.to_machine((first_end, second_end, axis_end, 0, 0, 0, 0, 0, 0))[:3]
        cx, cy = self.to_machine((first_axis, second_axis, 0, 0, 0, 0, 0, 0, 0))[:2]
        deviation, mx, my = _chord_deviation(lx, ly, ex, ey, cx, cy, rotation)
        if deviation >= self.naivecam_tolerance:
            return False
        rest = self.to_machine((0, 0, 0, *others))[3:]
        middle_rest = [(self.end_point[3 + k] + rest[k]) / 2 for k in range(6)]
        self._see_segment(line, [mx, my, (lz + ez) / 2, *middle_rest])
        self._see_segment(line, [ex, ey, ez, *rest])
        return True

    def NURBS_FEED(self, line, points: list[tuple[float, float, float]], order: int) -> None:
        """G5, G5.1, G5.2/G5.3: the XY curve approximated by biarcs, 4 per control point."""
        self._flush()
        n = len(points) - 1
        u_max = n - order + 2
        knots = _knot_vector(n, order)
        divisions = len(points) * 4
        p0 = _nurbs_point(0.0, order, points, knots)
        t0 = _nurbs_tangent(0.0, order, points, knots)
        for i in range(1, divisions + 1):
            u = u_max * i / divisions
            p1 = _nurbs_point(u, order, points, knots)
            t1 = _nurbs_tangent(u, order, points, knots)
            self._biarc(line, p0, t0, p1, t1)
            p0, t0 = p1, t1

    def _biarc(
        self,
        line: int,
        p0: tuple[float, float],
        t0: tuple[float, float],
        p4: tuple[float, float],
        t4: tuple[float, float],
    ) -> None:
        """Two arcs from ``p0`` (tangent ``t0``) to ``p4`` (tangent ``t4``) that meet with a
        common tangent; nothing when the tangents allow no such pair."""
        tsx, tsy = _unit(*t0)
        tex, tey = _unit(*t4)
        vx, vy = p0[0] - p4[0], p0[1] - p4[1]
        c = vx * vx + vy * vy
        b = 2 * (vx * (tsx + tex) + vy * (tsy + tey))
        a = 2 * (tsx * tex + tsy * tey - 1)
        if a == 0:  # parallel tangents: one arc (or line) leaving along the start tangent
            self._biarc_piece(line, p0, p4, (tsx, tsy))
            return
        discriminant = b * b - 4 * a * c
        if discriminant < 0:
            return
        root = math.sqrt(discriminant)
        beta1, beta2 = (-b - root) / 2 / a, (-b + root) / 2 / a
        if beta1 > 0 and beta2 > 0:
            return
        # both arcs reach out the same distance along their end tangents; they meet
        # halfway between those two points
        beta = max(beta1, beta2)
        p1 = (p0[0] + beta * tsx, p0[1] + beta * tsy)
        p3 = (p4[0] - beta * tex, p4[1] - beta * tey)
        p2 = ((p1[0] + p3[0]) / 2, (p1[1] + p3[1]) / 2)
        tm = _unit(p3[0] - p2[0], p3[1] - p2[1])
        self._biarc_piece(line, p0, p2, (tsx, tsy))
        self._biarc_piece(line, p2, p4, tm)

    def _biarc_piece(
        self,
        line: int,
        p0: tuple[float, float],
        p1: tuple[float, float],
        tangent: tuple[float, float],
    ) -> None:
        """The arc from ``p0`` (leaving along ``tangent``) to ``p1``, or a line if straight."""
        rest = self.to_program(self.end_point)[2:]  # Z and the other axes stay
        x, y = p1[0] - p0[0], p1[1] - p0[1]
        dx, dy = tangent
        den = 2 * (y * dx - x * dy)
        if abs(den) > 1e-6:
            r = -(x * x + y * y) / den
            cx, cy = p0[0] + dy * r, p0[1] - dx * r
            self.ARC_FEED(line, p1[0], p1[1], cx, cy, 1 if r < 0 else -1, *rest)
        else:
            self.STRAIGHT_FEED(line, p1[0], p1[1], *rest)

    # ================================================================ settings
    def SET_XY_ROTATION(self, t: float) -> None:
        self._queue(emc.EMC_TRAJ_SET_ROTATION(rotation=t))
        self.rotation = t

    def SET_G5X_OFFSET(self, index, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self.g5x = self._from_program((x, y, z, a, b, c, u, v, w))
        self.g5x_index = index
        self._flush()
        self._update_css_spindles()
        self._queue(emc.EMC_TRAJ_SET_G5X(g5x_index=index, origin=emc.EmcPose.of(self.g5x)))

    def SET_G92_OFFSET(self, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0) -> None:
        self.g92 = self._from_program((x, y, z, a, b, c, u, v, w))
        self._flush()
        self._update_css_spindles()
        self._queue(emc.EMC_TRAJ_SET_G92(origin=emc.EmcPose.of(self.g92)))

    def USE_LENGTH_UNITS(self, units: int) -> None:
        self.program_units = units

    def SET_TRAVERSE_RATE(self, rate: float) -> None:
        """Nothing to do: rapids move at the axis limits."""

    def SET_FEED_MODE(self, spindle: int, mode: int) -> None:
        self._flush()
        self.feed_mode = mode
        self.spindle_num = spindle
        if mode == 0:
            self.STOP_SPEED_FEED_SYNCH()

    def SET_FEED_RATE(self, rate: float) -> None:
        if self.feed_mode:
            # G95: the rate is per spindle revolution; motion follows the spindle
            self.START_SPEED_FEED_SYNCH(self.spindle_num, rate, True)
            self.linear_feed_rate = rate
            return
        linear, angular = rate / 60.0 * self._scale, rate / 60.0
        if (linear, angular) != (self.linear_feed_rate, self.angular_feed_rate):
            self._flush()
        self.linear_feed_rate, self.angular_feed_rate = linear, angular

    def SET_FEED_REFERENCE(self, reference: int) -> None:
        """Nothing to do: feeds are always along the path."""

    def SET_MOTION_CONTROL_MODE(self, mode: int, tolerance: float) -> None:
        self._flush()  # the held-back segments blend the old way
        self.motion_mode = mode
        self.motion_tolerance = tolerance * self._scale
        if mode == C.CONTINUOUS:
            msg = emc.EMC_TRAJ_SET_TERM_COND(
                cond=emc.EMC_TRAJ_TERM_COND.BLEND, tolerance=self.motion_tolerance
            )
        elif mode == C.EXACT_PATH:
            msg = emc.EMC_TRAJ_SET_TERM_COND(cond=emc.EMC_TRAJ_TERM_COND.EXACT)
        else:
            msg = emc.EMC_TRAJ_SET_TERM_COND(cond=emc.EMC_TRAJ_TERM_COND.STOP)
        self._queue(msg)

    def SET_NAIVECAM_TOLERANCE(self, tolerance: float) -> None:
        self.naivecam_tolerance = tolerance * self._scale

    def SELECT_PLANE(self, plane: int) -> None:
        self.plane = plane

    def START_SPEED_FEED_SYNCH(self, spindle: int, sync: float, vel: bool) -> None:
        msg = emc.EMC_TRAJ_SET_SPINDLESYNC(
            spindle=spindle, feed_per_revolution=sync * self._scale, velocity_mode=vel
        )
        self._queue(msg)
        self.spindles[spindle].is_synched = True

    def STOP_SPEED_FEED_SYNCH(self) -> None:
        msg = emc.EMC_TRAJ_SET_SPINDLESYNC(
            spindle=self.spindle_num, feed_per_revolution=0.0, velocity_mode=False
        )
        self._queue(msg)
        self.spindles[self.spindle_num].is_synched = False

    def DWELL(self, seconds: float) -> None:
        self._queue(emc.EMC_TRAJ_DELAY(delay=seconds))

    # ================================================================ spindle
    def _spindle_speed(self, s: int) -> tuple[float, float, float]:
        """``speed``, ``factor`` and ``xoffset`` of a spindle message: the rpm, or in CSS
        mode (G96) the maximum rpm and the surface speed factor for motion."""
        spindle = self.spindles[s]
        if not spindle.css_maximum:
            return spindle.direction * spindle.speed, 0.0, 0.0
        # surface speed (feet or metres per minute) -> machine units per minute, over 2 pi
        if self.program_units == C.UNITS_INCHES:
            per_minute = 12 * MM_PER_INCH / self._machine_mm
        else:
            per_minute = 1000 / self._machine_mm
        factor = per_minute / (2 * math.pi) * spindle.speed
        xoffset = self.g5x[0] + self.g92[0] + self.tool_offset[0]
        return spindle.direction * spindle.css_maximum, spindle.direction * factor, xoffset

    def _update_css_spindles(self) -> None:
        """In CSS mode the X offset is part of the speed: send the speed again."""
        for s, spindle in enumerate(self.spindles):
            if spindle.css_maximum:
                self.SET_SPINDLE_SPEED(s, spindle.speed)

    def _start_spindle(self, s: int, direction: int) -> None:
        self.spindles[s].direction = direction
        speed, factor, xoffset = self._spindle_speed(s)
        msg = emc.EMC_SPINDLE_ON(
            spindle=s, speed=speed, factor=factor, xoffset=xoffset, wait_for_spindle_at_speed=1
        )
        self._queue(msg)

    def SET_SPINDLE_MODE(self, spindle: int, arg: float) -> None:
        self.spindles[spindle].css_maximum = abs(arg)

    def START_SPINDLE_CLOCKWISE(self, spindle: int) -> None:
        self._start_spindle(spindle, 1)

    def START_SPINDLE_COUNTERCLOCKWISE(self, spindle: int) -> None:
        self._start_spindle(spindle, -1)

    def SET_SPINDLE_SPEED(self, spindle: int, rpm: float) -> None:
        self.spindles[spindle].speed = abs(rpm)
        speed, factor, xoffset = self._spindle_speed(spindle)
        self._queue(
            emc.EMC_SPINDLE_SPEED(spindle=spindle, speed=speed, factor=factor, xoffset=xoffset)
        )

    def STOP_SPINDLE_TURNING(self, spindle: int) -> None:
        self._queue(emc.EMC_SPINDLE_OFF(spindle=spindle, wait_for_spindle_at_speed=1))
        self.spindles[spindle].direction = 0

    def ORIENT_SPINDLE(self, spindle: int, orientation: float, mode: int) -> None:
        self._queue(emc.EMC_SPINDLE_ORIENT(spindle=spindle, orientation=orientation, mode=mode))

    def WAIT_SPINDLE_ORIENT_COMPLETE(self, spindle: int, timeout: float) -> None:
        self._queue(emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE(spindle=spindle, timeout=timeout))

    # ================================================================ tools
    def SET_TOOL_TABLE_ENTRY(
        self, idx, toolno, offset, diameter, frontangle, backangle, orientation
    ) -> None:
        """G10 L1/L10/L11: offsets and diameter in machine units, as the table keeps them."""
        msg = emc.EMC_TOOL_SET_OFFSET(
            pocket=idx,
            toolno=toolno,
            offset=emc.EmcPose.of(offset),
            diameter=diameter,
            frontangle=frontangle,
            backangle=backangle,
            orientation=orientation,
        )
        self._queue(msg)
        entry = self.tools.get(idx)
        entry.toolno, entry.offset, entry.diameter = toolno, list(offset), diameter
        entry.frontangle, entry.backangle, entry.orientation = frontangle, backangle, orientation
        if entry.pocketno == -1:
            entry.pocketno = idx
        self.tools.put(idx, entry)

    def USE_TOOL_LENGTH_OFFSET(self, offset: list[float]) -> None:
        self._flush()
        self.tool_offset = self._from_program(offset)
        self._update_css_spindles()
        self._queue(emc.EMC_TRAJ_SET_OFFSET(offset=emc.EmcPose.of(self.tool_offset)))

    def CHANGE_TOOL(self, slot: int) -> None:
        """M6: rapid to [EMCIO]TOOL_CHANGE_POSITION if there is one, then load the tool."""
        self._flush()
        position = self.setup.tool_change_position
        if position:
            end = [*position, *self.end_point[len(position) :]]
            self._traverse_to(-1, end, emc.EMC_MOTION_TYPE.TOOLCHANGE)
        self._queue(emc.EMC_TOOL_LOAD())

    def SELECT_TOOL(self, tool: int) -> None:
        """Tn: iocontrol finds the tool's pocket (LinuxCNC 2.9 sends the tool number)."""
        self._queue(emc.EMC_TOOL_PREPARE(tool=tool))

    def CHANGE_TOOL_NUMBER(self, tool: int) -> None:
        """M61: ``tool`` is the tooldata index of the tool now in the spindle."""
        self._queue(emc.EMC_TOOL_SET_NUMBER(tool=tool))

    def RELOAD_TOOLDATA(self) -> None:
        self._queue(emc.EMC_TOOL_LOAD_TOOL_TABLE(file=""))

    def START_CHANGE(self) -> None:
        self._queue(emc.EMC_TOOL_START_CHANGE())

    # ================================================================ comments, messages
    def COMMENT(self, text: str) -> None:
        """Hot comments: (PROBEOPEN file) records each probed point in ``file`` until
        (PROBECLOSE); every other comment is ignored."""
        if text.startswith("PROBEOPEN"):
            self._close_probe_file()
            name = text[len("PROBEOPEN") :].strip()
            if not self._may_write(name, "PROBEOPEN"):
                return
            try:
                self._probe_file = open(name, "w", encoding="utf-8")  # noqa: SIM115
            except OSError:
                self.MESSAGE(f"can't open probe file {name}")
        elif text.startswith("PROBECLOSE"):
            self._close_probe_file()

    def _close_probe_file(self) -> None:
        if self._probe_file is not None:
            self._probe_file.close()
            self._probe_file = None

    def MESSAGE(self, text: str) -> None:
        self._queue(emc.EMC_OPERATOR_DISPLAY(id=0, display=emc.fit_text(text)))

    def LOG(self, text: str) -> None:
        self._flush()
        if self._log_file is not None:
            self._log_file.write(text + "\n")
            self._log_file.flush()

    def _may_write(self, name: str, what: str) -> bool:
        """G-code may write files only in the writable folders (task may run as root: a
        program must not be able to overwrite /etc/passwd); a refusal is an error."""
        allowed = self.setup.writable_dirs
        if allowed is None:
            return True
        target = os.path.realpath(name)
        for folder in allowed:
            root = os.path.realpath(folder)
            if os.path.commonpath([root, target]) == root:
                return True
        self._error(
            f"({what} {name}): refused, G-code writes files only in "
            f"{', '.join(allowed)} ([RS274NGC]WRITABLE_DIRS adds folders)"
        )
        return False

    def _open_log(self, name: str, mode: str) -> None:
        self.LOGCLOSE()
        if not self._may_write(name, "LOGOPEN" if mode == "w" else "LOGAPPEND"):
            return
        try:
            self._log_file = open(name, mode, encoding="utf-8")  # noqa: SIM115
        except OSError:
            self._log_file = None

    def LOGOPEN(self, text: str) -> None:
        self._open_log(text, "w")

    def LOGAPPEND(self, text: str) -> None:
        self._open_log(text, "a")

    def LOGCLOSE(self) -> None:
        if self._log_file is not None:
            self._log_file.close()
            self._log_file = None

    def PRINT_LINE(self, text: str) -> None:
        """(PRINT,...): straight to task's standard output."""
        print(text, flush=True)

    # ================================================================ enables, coolant
    def DISABLE_ADAPTIVE_FEED(self) -> None:
        self._queue(emc.EMC_MOTION_ADAPTIVE(status=0))

    def ENABLE_ADAPTIVE_FEED(self) -> None:
        self._queue(emc.EMC_MOTION_ADAPTIVE(status=1))

    def DISABLE_FEED_HOLD(self) -> None:
        self._queue(emc.EMC_TRAJ_SET_FH_ENABLE(mode=0))

    def ENABLE_FEED_HOLD(self) -> None:
        self._queue(emc.EMC_TRAJ_SET_FH_ENABLE(mode=1))

    def DISABLE_FEED_OVERRIDE(self) -> None:
        self._queue(emc.EMC_TRAJ_SET_FO_ENABLE(mode=0))

    def ENABLE_FEED_OVERRIDE(self) -> None:
        self._queue(emc.EMC_TRAJ_SET_FO_ENABLE(mode=1))

    def DISABLE_SPEED_OVERRIDE(self, spindle: int) -> None:
        self._queue(emc.EMC_TRAJ_SET_SO_ENABLE(spindle=spindle, mode=0))

    def ENABLE_SPEED_OVERRIDE(self, spindle: int) -> None:
        self._queue(emc.EMC_TRAJ_SET_SO_ENABLE(spindle=spindle, mode=1))

    def FLOOD_OFF(self) -> None:
        self._queue(emc.EMC_COOLANT_FLOOD_OFF())

    def FLOOD_ON(self) -> None:
        self._queue(emc.EMC_COOLANT_FLOOD_ON())

    def MIST_OFF(self) -> None:
        self._queue(emc.EMC_COOLANT_MIST_OFF())

    def MIST_ON(self) -> None:
        self._queue(emc.EMC_COOLANT_MIST_ON())

    def PALLET_SHUTTLE(self) -> None:
        """No pallet changer: nothing to do (as in emccanon)."""

    def TURN_PROBE_ON(self) -> None:
        self._queue(emc.EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG())

    def TURN_PROBE_OFF(self) -> None:
        """Nothing to do: the probe move itself ends probing."""

    # ================================================================ program flow
    def PROGRAM_STOP(self) -> None:
        self._queue(emc.EMC_TASK_PLAN_PAUSE())

    def OPTIONAL_PROGRAM_STOP(self) -> None:
        self._queue(emc.EMC_TASK_PLAN_OPTIONAL_STOP())

    def PROGRAM_END(self) -> None:
        self._queue(emc.EMC_TASK_PLAN_END())

    def FINISH(self) -> None:
        self._flush()

    def ON_RESET(self) -> None:
        self._drop()
        self._motion_line = None  # announce the line again after an abort

    def GET_BLOCK_DELETE(self) -> bool:
        return self.is_block_delete_on

    def SET_BLOCK_DELETE(self, state: bool) -> None:
        self.is_block_delete_on = state

    def GET_OPTIONAL_PROGRAM_STOP(self) -> bool:
        return self.is_optional_stop_on

    def SET_OPTIONAL_PROGRAM_STOP(self, state: bool) -> None:
        self.is_optional_stop_on = state

    # ================================================================ inputs, outputs
    def _set_dout(self, index: int, value: int, now: int) -> None:
        self._queue(emc.EMC_MOTION_SET_DOUT(index=index, start=value, end=value, now=now))

    def _set_aout(self, index: int, value: float, now: int) -> None:
        self._queue(emc.EMC_MOTION_SET_AOUT(index=index, start=value, end=value, now=now))

    def SET_MOTION_OUTPUT_BIT(self, index: int) -> None:
        self._set_dout(index, 1, now=0)  # with the next move (M62)

    def CLEAR_MOTION_OUTPUT_BIT(self, index: int) -> None:
        self._set_dout(index, 0, now=0)

    def SET_AUX_OUTPUT_BIT(self, index: int) -> None:
        self._set_dout(index, 1, now=1)  # at once (M64)

    def CLEAR_AUX_OUTPUT_BIT(self, index: int) -> None:
        self._set_dout(index, 0, now=1)

    def SET_MOTION_OUTPUT_VALUE(self, index: int, value: float) -> None:
        self._set_aout(index, value, now=0)

    def SET_AUX_OUTPUT_VALUE(self, index: int, value: float) -> None:
        self._set_aout(index, value, now=1)

    def WAIT(self, index: int, input_type: int, wait_type: int, timeout: float) -> int:
        """M66: queue the wait; -1 for an input that does not exist."""
        count = emc.EMC_MAX_DIO if input_type == C.DIGITAL_INPUT else emc.EMC_MAX_AIO
        if not 0 <= index < count:
            return -1
        msg = emc.EMC_AUX_INPUT_WAIT(
            index=index, input_type=input_type, wait_type=wait_type, timeout=timeout
        )
        self._queue(msg)
        return 0

    def USER_DEFINED_FUNCTION(self, index: int, p: float, q: float) -> bool:
        """M100..M199: run the configured program with P and Q; False if there is none."""
        program = self.setup.user_m_commands.get(index)
        if program is None:
            return False
        command = emc.fit_text(f"{program} {p:f} {q:f}", emc.EMC_SYSTEM_CMD_LEN)
        self._queue(emc.EMC_SYSTEM_CMD(string=command))
        return True

    # ================================================================ GET_EXTERNAL_*
    def GET_EXTERNAL_POSITION(self) -> list[float]:
        """Where motion is (commanded, without external offsets), in program coordinates.
        Also where the next move starts: held-back segments are dropped (a synch follows
        an executed queue or an abort)."""
        self._drop()
        motion = self._stat.motion
        position = list(motion.traj.position.values())
        if motion.external_offsets_applied:
            eoffset = list(motion.eoffset_pose.values())
            position = [position[k] - eoffset[k] for k in range(NUM_AXES)]
        self.end_point = position
        return self.to_program(position)

    def GET_EXTERNAL_PROBE_POSITION(self) -> list[float]:
        self._flush()
        position = self.to_program(list(self._stat.motion.traj.probedPosition.values()))
        if self._probe_file is not None and position != self._last_probed:
            self._probe_file.write(" ".join(f"{v:f}" for v in position) + "\n")
            self._last_probed = position
        return position

    def GET_EXTERNAL_PROBE_TRIPPED_VALUE(self) -> int:
        return int(self._stat.motion.traj.probe_tripped)

    def GET_EXTERNAL_LENGTH_UNITS(self) -> float:
        """Machine length units per millimetre."""
        return 1.0 / self._machine_mm

    def GET_EXTERNAL_ANGLE_UNITS(self) -> float:
        return 1.0

    def GET_EXTERNAL_LENGTH_UNIT_TYPE(self) -> int:
        return self.program_units

    def GET_EXTERNAL_MOTION_CONTROL_MODE(self) -> int:
        return self.motion_mode

    def GET_EXTERNAL_MOTION_CONTROL_TOLERANCE(self) -> float:
        return self.motion_tolerance / self._scale

    def GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE(self) -> float:
        return self.naivecam_tolerance / self._scale

    def GET_EXTERNAL_TOOL_SLOT(self) -> int:
        """The tooldata index of the tool in the spindle."""
        return self.tools.find_index_for_tool(self._stat.io.tool.toolInSpindle)

    def GET_EXTERNAL_SELECTED_TOOL_SLOT(self) -> int:
        """The index iocontrol has prepared (-1: none)."""
        return self._stat.io.tool.pocketPrepped

    def GET_EXTERNAL_FEED_RATE(self) -> float:
        """Program units per minute (per revolution in feed per revolution mode)."""
        if self.feed_mode:
            return self.linear_feed_rate
        return self.linear_feed_rate / self._scale * 60.0

    def GET_EXTERNAL_TRAVERSE_RATE(self) -> float:
        return self._stat.motion.traj.maxVelocity / self._scale * 60.0

    def GET_EXTERNAL_FLOOD(self) -> int:
        return self._stat.io.coolant.flood

    def GET_EXTERNAL_MIST(self) -> int:
        return self._stat.io.coolant.mist

    def GET_EXTERNAL_PLANE(self) -> int:
        return self.plane

    def GET_EXTERNAL_FEED_OVERRIDE_ENABLE(self) -> int:
        return int(self._stat.motion.traj.feed_override_enabled)

    def GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(self, spindle: int) -> int:
        return int(self._stat.motion.spindle[spindle].spindle_override_enabled)

    def GET_EXTERNAL_ADAPTIVE_FEED_ENABLE(self) -> int:
        return int(self._stat.motion.traj.adaptive_feed_enabled)

    def GET_EXTERNAL_FEED_HOLD_ENABLE(self) -> int:
        return int(self._stat.motion.traj.feed_hold_enabled)

    def GET_EXTERNAL_SPEED(self, spindle: int) -> float:
        """The programmed speed (rpm), as the canon last set it."""
        return self.spindles[spindle].speed

    def GET_EXTERNAL_SPINDLE(self, spindle: int) -> int:
        speed = self._stat.motion.spindle[spindle].speed
        if speed == 0:
            return C.STOPPED
        return C.CLOCKWISE if speed > 0 else C.COUNTERCLOCKWISE

    def GET_EXTERNAL_TOOL_TABLE(self, idx: int) -> ToolEntry:
        """A tool record, in machine units; toolno -1 for an index out of range."""
        if not 0 <= idx < CANON_POCKETS_MAX:
            return ToolEntry(pocketno=0)
        return self.tools.get(idx)

    def GET_EXTERNAL_TOOL_LENGTH_OFFSET(self) -> list[float]:
        return self._to_program_units(self.tool_offset)

    def GET_EXTERNAL_DIGITAL_INPUT(self, index: int, default: int) -> int:
        """The input's value, or -1 for a bad index or after an M66 timeout."""
        if not 0 <= index < emc.EMC_MAX_DIO or self._stat.task.input_timeout:
            return -1
        return 1 if self._stat.motion.synch_di[index] else 0

    def GET_EXTERNAL_ANALOG_INPUT(self, index: int, default: float) -> float:
        if not 0 <= index < emc.EMC_MAX_AIO or self._stat.task.input_timeout:
            return -1.0
        return float(self._stat.motion.analog_input[index])

    def GET_EXTERNAL_QUEUE_EMPTY(self) -> int:
        self._flush()
        return 1 if self._stat.motion.traj.queue == 0 else 0

    def GET_EXTERNAL_TC_FAULT(self) -> int:
        return self._stat.io.fault

    def GET_EXTERNAL_TC_REASON(self) -> int:
        return self._stat.io.reason

    def GET_EXTERNAL_AXIS_MASK(self) -> int:
        return self.setup.axis_mask

    def find_tool_index(self, toolno: int) -> int:
        return self.tools.find_index_for_tool(toolno)


# ==================================================================== geometry helpers
def _dot(p: Sequence[float], q: Sequence[float]) -> float:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _unit(x: float, y: float) -> tuple[float, float]:
    h = math.hypot(x, y)
    return (x / h, y / h) if h else (x, y)


def _knot_vector(n: int, order: int) -> list[int]:
    """Clamped uniform knots for n + 1 control points of the given order."""
    return [
        0 if i < order else i - order + 1 if i <= n else n - order + 2 for i in range(n + order + 1)
    ]


def _basis(i: int, order: int, u: float, knots: list[int]) -> float:
    """The B-spline basis function N(i, order) at u (Cox-de Boor; closed knot spans, as
    LinuxCNC evaluates them)."""
    if order == 1:
        return 1.0 if knots[i] <= u <= knots[i + 1] else 0.0
    left_span = knots[i + order - 1] - knots[i]
    right_span = knots[i + order] - knots[i + 1]
    value = 0.0
    if left_span:
        value += (u - knots[i]) * _basis(i, order - 1, u, knots) / left_span
    if right_span:
        value += (knots[i + order] - u) * _basis(i + 1, order - 1, u, knots) / right_span
    return value


def _nurbs_point(
    u: float, order: int, points: list[tuple[float, float, float]], knots: list[int]
) -> tuple[float, float]:
    weights = [_basis(i, order, u, knots) * p[2] for i, p in enumerate(points)]
    total = sum(weights)
    x = sum(wt * p[0] for wt, p in zip(weights, points, strict=True)) / total
    y = sum(wt * p[1] for wt, p in zip(weights, points, strict=True)) / total
    return x, y


def _nurbs_tangent(
    u: float, order: int, points: list[tuple[float, float, float]], knots: list[int]
) -> tuple[float, float]:
    """The curve's unit tangent at u, by a central difference."""
    du = 1e-5
    u_max = len(points) - 1 - order + 2
    low, high = max(0.0, u - du), min(u_max, u + du)
    x1, y1 = _nurbs_point(low, order, points, knots)
    x3, y3 = _nurbs_point(high, order, points, knots)
    return _unit((x3 - x1) / (high - low), (y3 - y1) / (high - low))
