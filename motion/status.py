"""EMC_MOTION_STAT written in place, a few ``struct.pack_into`` per servo period (MOT-066..071).

Setting a status field through its message attribute (``stat.traj.inpos = ...``) costs a
numpy field lookup, and reaching a nested struct (``stat.joint[0]``) makes a view object;
with the ~130 fields motion reports, that was the largest part of a servo period. Here the
fields motion reports are grouped into *runs* of consecutive fields of the record's fixed
layout, each written by one ``struct.pack_into`` of its leaf values in layout order (a
pose as its nine numbers). That is 3x faster than a numpy structured assignment once the
caches are cold, as they are at the start of each period. ``MotionStatusRuns`` makes the
runs of one status record once; the controller fills them every period
(``MotionController.fill_status``).

Fields motion does not own are outside every run and keep their value: ``linearUnits``,
``angularUnits``, ``probeval``, ``tag``, the joints' soft-limit flags, the axis records and
the RCS header (``command_type``, ``echo_serial_number``, ``status``: the command handler's).
"""

from __future__ import annotations

import functools
import struct

import numpy as np

from nml import emc
from nml.message import _flat_codes  # nml's dtype -> struct codes, so both agree

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
        self._io_written: list[list | None] = [None] * len(self._io_arrays)

    def write_io(self, *values: list) -> None:
        """``synch_do``, ``synch_di``, ``analog_output``, ``analog_input`` from the start:
        each only when it differs from what the last call wrote (they seldom change, and
        only this object writes them into its record)."""
        for index, (array, new) in enumerate(zip(self._io_arrays, values, strict=True)):
            if new != self._io_written[index]:
                array[: len(new)] = new
                self._io_written[index] = list(new)
