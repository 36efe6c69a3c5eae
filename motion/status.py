"""EMC_MOTION_STAT written in place, a few ``struct.pack_into`` per servo period (MOT-066..071).

Setting a status field through its message attribute (``stat.traj.inpos = ...``) costs a
numpy field lookup, and reaching a nested struct (``stat.joint[0]``) makes a view object;
with the ~130 fields motion reports, that was the largest part of a servo period. Here the
fields motion reports are grouped into *runs* of consecutive fields of the record's fixed
layout, each written by one ``struct.pack_into`` of its leaf values in layout order (a
pose as its nine numbers). That is 3x faster than a numpy structured assignment once the
caches are cold, as they are at the start of each period. ``MotionStatusRuns`` makes the
runs of one status record once; ``StatusFilling.fill_status``, a part of
``MotionController`` (motion/controller.py), fills them every period from the
controller's state.

Fields motion does not own are outside every run and keep their value: ``linearUnits``,
``angularUnits``, ``probeval``, the joints' soft-limit flags, the axis records and the RCS
header (``command_type``, ``echo_serial_number``, ``status``: the command handler's).
``tag``, the state tag of the move being carried out (as the move brought it from task),
is copied in only when it changes.
"""

from __future__ import annotations

import functools
import math
import struct

import numpy as np

from motion.modes import COORD
from nml import emc
from nml.axes import NUM_AXES
from nml.message import _flat_codes  # nml's dtype -> struct codes, so both agree

# traj.queueFull is reported while fewer planner slots than this are free (like LinuxCNC's
# TC_QUEUE_MARGIN), so moves task has already sent still fit (see task's MAX_MOTION_IN_FLIGHT)
QUEUE_FULL_MARGIN = 200

# The runs, in layout order (a run must name consecutive fields; checked when made).
TRAJ_STATE = (
    "cycleTime", "joints", "spindles", "axis_mask", "mode", "enabled", "inpos", "queue",
    "activeQueue", "queueFull", "id", "paused", "scale", "rapid_scale", "position",
    "actualPosition", "velocity", "acceleration", "maxVelocity", "maxAcceleration",
    "probedPosition", "probe_tripped", "probing",
)  # fmt: skip
TRAJ_PATH = (
    "kinematics_type", "motion_type", "distance_to_go", "dtg", "current_vel",
    "feed_override_enabled", "adaptive_feed_enabled", "feed_hold_enabled",
)  # fmt: skip
JOINT_STATE = (
    "backlash", "minPositionLimit", "maxPositionLimit", "maxFerror", "minFerror",
    "ferrorCurrent", "ferrorHighMark", "output", "input", "velocity", "inpos", "homing",
    "homed", "fault", "enabled",
)  # fmt: skip
JOINT_SWITCHES = ("minHardLimit", "maxHardLimit", "overrideLimits")
# (a spindle's ``state`` is the RCS header's, which LinuxCNC's spindle status also sets)
SPINDLE_STATE = (
    "state", "speed", "spindle_scale", "css_maximum", "css_factor", "direction", "brake",
    "increasing", "enabled", "orient_state", "orient_fault", "spindle_override_enabled",
    "homed",
)  # fmt: skip


@functools.cache
def _run_layout(dtype: np.dtype, names: tuple[str, ...]) -> tuple[int, struct.Struct]:
    """Offset in a ``dtype`` record of its consecutive fields ``names``, and the packer of
    their leaf values."""
    first = dtype.names.index(names[0])
    if dtype.names[first : first + len(names)] != names:
        raise ValueError(f"{names} are not consecutive fields of {dtype.names}")
    start = dtype.fields[names[0]][1]
    last_type, last_offset = dtype.fields[names[-1]][:2]
    packer = struct.Struct("<" + "".join(c for n in names for c in _flat_codes(dtype[n])))
    if packer.size != last_offset + last_type.itemsize - start:
        raise ValueError(f"{names}: the layout has gaps")  # (nml's layouts are packed)
    return start, packer


class FieldRun:
    """The fields ``names`` of the ``dtype`` record at ``offset`` in ``record``:
    ``write(value, ...)`` sets them all, given every leaf value in layout order."""

    __slots__ = ("_offset", "_pack_into", "_record")

    def __init__(
        self, record: memoryview, offset: int, dtype: np.dtype, names: tuple[str, ...]
    ) -> None:
        start, packer = _run_layout(dtype, names)
        self._record, self._offset, self._pack_into = record, offset + start, packer.pack_into

    def write(self, *values: float | int | bool) -> None:
        self._pack_into(self._record, self._offset, *values)


class MotionStatusRuns:
    """The runs of one EMC_MOTION_STAT record, for ``num_joints`` joints and
    ``num_spindles`` spindles, and its digital and analog I/O arrays."""

    def __init__(self, stat: emc.EMC_MOTION_STAT, num_joints: int, num_spindles: int) -> None:
        self.stat = stat
        record = stat.byte_view()
        fields = stat.dtype.fields
        traj_at = fields["traj"][1]
        traj = emc.EMC_TRAJ_STAT.dtype
        self.traj_state = FieldRun(record, traj_at, traj, TRAJ_STATE)
        self.traj_path = FieldRun(record, traj_at, traj, TRAJ_PATH)
        joint, joints_at = emc.EMC_JOINT_STAT.dtype, fields["joint"][1]
        at = [joints_at + index * joint.itemsize for index in range(num_joints)]
        self.joints = [FieldRun(record, offset, joint, JOINT_STATE) for offset in at]
        self.joint_switches = [FieldRun(record, offset, joint, JOINT_SWITCHES) for offset in at]
        spindle, spindles_at = emc.EMC_SPINDLE_STAT.dtype, fields["spindle"][1]
        self.spindles = [
            FieldRun(record, spindles_at + index * spindle.itemsize, spindle, SPINDLE_STATE)
            for index in range(num_spindles)
        ]
        self._io_arrays = (stat.synch_do, stat.synch_di, stat.analog_output, stat.analog_input)
        self._record = record
        tag_at = traj_at + traj.fields["tag"][1]
        self._tag_bytes = slice(tag_at, tag_at + emc.StateTag.dtype.itemsize)
        self._tag_written: bytes | None = None
        for index in range(num_joints, len(stat.joint)):
            _set_absent_joint_defaults(stat.joint[index])
        self._io_written: list[list | None] = [None] * len(self._io_arrays)

    def write_tag(self, tag: bytes) -> None:
        """``traj.tag``: a move's state tag, as it came (an empty one leaves it as it is)."""
        if tag is not self._tag_written and tag:
            self._record[self._tag_bytes] = tag
            self._tag_written = tag

    def write_io(self, *values: list) -> None:
        """``synch_do``, ``synch_di``, ``analog_output``, ``analog_input`` from the start:
        each only when it differs from what the last call wrote (they seldom change, and
        only this object writes them into its record)."""
        for index, (array, new) in enumerate(zip(self._io_arrays, values, strict=True)):
            if new != self._io_written[index]:
                array[: len(new)] = new
                self._io_written[index] = list(new)


class StatusFilling:
    """The controller's state, written into its EMC_MOTION_STAT every period."""

    _status_runs: MotionStatusRuns | None  # of the last fill_status's record

    def fill_status(self, stat: emc.EMC_MOTION_STAT) -> None:
        """Write the controller's state into an EMC_MOTION_STAT (MOT-066..071), in place
        and in a few assignments (motion/status.py): motmod calls this every period."""
        runs = self._status_runs
        if runs is None or runs.stat is not stat:
            runs = self._status_runs = MotionStatusRuns(stat, len(self.joints), len(self.spindles))
        tp = self.tp
        is_coord = self.mode == COORD
        is_enabled = self.is_enabled
        move = tp.current_move if is_coord else None
        runs.traj_state.write(
            self.period_s,  # cycleTime
            len(self.joints),
            len(self.spindles),
            getattr(self.kins, "axis_mask", 0b111),
            self.mode,
            is_enabled,
            self.is_in_position,  # inpos
            tp.queue_depth,  # queue
            tp.active_queue if is_coord else 0,  # activeQueue
            tp.free_slots < QUEUE_FULL_MARGIN,  # queueFull
            tp.motion_id,  # id
            tp.is_paused,
            tp.feed_scale,  # scale
            tp.rapid_scale,
            *self.carte_pos_cmd.as_tuple(),  # position
            *self.carte_pos_fb.as_tuple(),  # actualPosition
            self.traj_vel,  # velocity
            self.traj_acc,  # acceleration
            _limit_or_unlimited(self.max_vel),  # maxVelocity
            _limit_or_unlimited(self.max_acc),  # maxAcceleration
            *tp.probe_pos.tolist(),  # probedPosition
            tp.probe_tripped,
            move is not None and move.probe is not None,  # probing
        )
        runs.traj_path.write(
            int(self.kins.kinematics_type()),
            _motion_type(move),
            tp.distance_to_go if is_coord else 0.0,
            *(tp.dtg.tolist() if is_coord else _ZERO_POSE),  # dtg
            self.current_vel,
            self.is_feed_override_enabled,
            self.is_adaptive_feed_enabled,
            self.is_feed_hold_enabled,
        )
        is_override_limits = self.is_override_limits
        for joint, fault, out, switches in zip(
            self.joints, self.is_faulted, runs.joints, runs.joint_switches, strict=True
        ):
            out.write(
                joint.backlash,
                _finite_or_zero(joint.min_limit),  # minPositionLimit
                _finite_or_zero(joint.max_limit),  # maxPositionLimit
                _finite_or_zero(joint.ferror_limit),  # maxFerror
                _finite_or_zero(joint.min_ferror_limit),  # minFerror
                joint.ferror,  # ferrorCurrent
                joint.ferror_high_mark,
                joint.pos_cmd,  # output
                joint.pos_fb,  # input
                joint.vel_cmd,  # velocity
                not joint.planner.is_active,  # inpos
                bool(joint.is_homing),  # (bool: set by the homing module, maybe a user's)
                bool(joint.is_homed),
                fault,
                is_enabled,
            )
            switches.write(joint.is_on_neg_limit, joint.is_on_pos_limit, is_override_limits)
        for spindle, out in zip(self.spindles, runs.spindles, strict=True):
            speed = spindle.speed
            is_on = speed != 0
            out.write(
                is_on,  # state
                speed,
                spindle.scale,  # spindle_scale
                abs(speed) if spindle.css_factor else 0.0,  # css_maximum
                spindle.css_factor,
                (speed > 0) - (speed < 0),  # direction
                spindle.is_brake_on,  # brake
                spindle.increasing,
                is_on,  # enabled
                spindle.orient_state,
                spindle.orient_fault,
                spindle.is_override_enabled,
                False,  # homed: spindles are not homed (LinuxCNC reports the same)
            )
        runs.write_io(self.digital_out, self.digital_in, self.analog_out, self.analog_in)
        runs.write_tag(tp.tag)


def _set_absent_joint_defaults(record: emc.EMC_JOINT_STAT) -> None:
    """A joint motion does not have reads as LinuxCNC's EMC_JOINT_STAT starts (its
    constructor's values, which no update overwrites): linear, units 1, limits -1..1,
    following errors 1, in position."""
    record.jointType, record.units = emc.EmcJointType.LINEAR, 1.0
    record.minPositionLimit, record.maxPositionLimit = -1.0, 1.0
    record.minFerror = record.maxFerror = 1.0
    record.inpos = 1


def _motion_type(move) -> int:
    """EMC_TRAJ_STAT.motion_type of the move being executed (0: none)."""
    if move is None:
        return 0
    if move.probe is not None:
        return emc.EMC_MOTION_TYPE.PROBING
    if move.is_rapid:
        return emc.EMC_MOTION_TYPE.TRAVERSE
    is_straight = move.line is not None or move.rigid_tap is not None
    return emc.EMC_MOTION_TYPE.FEED if is_straight else emc.EMC_MOTION_TYPE.ARC


def _finite_or_zero(value: float) -> float:
    return value if math.isfinite(value) else 0.0


UNLIMITED = 1e99  # what LinuxCNC reports for a [TRAJ] limit the INI does not set


def _limit_or_unlimited(value: float) -> float:
    return value if math.isfinite(value) else UNLIMITED


_ZERO_POSE = (0.0,) * NUM_AXES
