"""``cnc.stat``: LinuxCNC's status object, read from the controller's EMC_STAT.

``poll()`` copies the latest EMC_STAT out of the ``emcStatus`` buffer and nothing else; each
attribute is computed from that copy when first read after a poll, then kept until the next
poll. ``ATTRIBUTES`` is the one table of attribute name -> how it derives from EMC_STAT
(the field paths are those of ``nml.emc``, which keeps LinuxCNC's field names).
"""

from __future__ import annotations

import os
from collections import namedtuple
from collections.abc import Callable
from operator import attrgetter, itemgetter
from typing import Any

from cnc.api.connection import Link
from cnc.api.errors import error
from iocontrol.tooldata import ToolDataError, ToolDataReader
from iocontrol.tooltable import ToolTable
from nml import emc
from nml.channels import EMC_STATUS
from nml.emc import EMC_STAT
from nml.errors import NmlError
from nml.message import Struct

# One tool_table entry, as LinuxCNC's ``linuxcnc.tool`` (a named tuple of 14 fields).
tool = namedtuple(
    "tool",
    "id xoffset yoffset zoffset aoffset boffset coffset uoffset voffset woffset "
    "diameter frontangle backangle orientation",
)

Getter = Callable[[EMC_STAT], Any]


def _field(path: str) -> Getter:
    """A plain value: an int, float, bool or str, as the field's type."""
    return attrgetter(path)


def _pose(path: str) -> Getter:
    """An EmcPose as LinuxCNC's 9-tuple (x, y, z, a, b, c, u, v, w)."""
    get = attrgetter(path)
    return lambda status: tuple(get(status).to_flat())


def _array(path: str) -> Getter:
    """A fixed array of numbers as a tuple."""
    get = attrgetter(path)
    return lambda status: tuple(get(status).tolist())


def _column(path: str, field: str) -> Getter:
    """One field of every struct of an array (``joint[i].homed`` for every joint)."""
    get = attrgetter(path)
    return lambda status: tuple(getattr(item, field) for item in get(status))


def _dicts(path: str, struct: type[Struct], keys: dict[str, str]) -> Getter:
    """Every struct of an array as a dict of LinuxCNC key -> value of field."""
    get = attrgetter(path)
    names = [f.name for f in struct.fields]  # the order of Struct.to_flat()
    pick = itemgetter(*[names.index(field) for field in keys.values()])

    def getter(status: EMC_STAT) -> tuple[dict[str, Any], ...]:
        return tuple(dict(zip(keys, pick(item.to_flat()), strict=True)) for item in get(status))

    return getter


def _limit_bits(status: EMC_STAT) -> tuple[int, ...]:
    """Per joint: 1 min hard limit, 2 max hard limit, 4 min soft limit, 8 max soft limit."""
    return tuple(
        (1 if j.minHardLimit else 0)
        | (2 if j.maxHardLimit else 0)
        | (4 if j.minSoftLimit else 0)
        | (8 if j.maxSoftLimit else 0)
        for j in status.motion.joint
    )


# Keys of LinuxCNC's stat.joint / stat.axis / stat.spindle dicts -> EMC_*_STAT fields.
JOINT_KEYS = {
    "jointType": "jointType",
    "units": "units",
    "backlash": "backlash",
    "min_position_limit": "minPositionLimit",
    "max_position_limit": "maxPositionLimit",
    "max_ferror": "maxFerror",
    "min_ferror": "minFerror",
    "ferror_current": "ferrorCurrent",
    "ferror_highmark": "ferrorHighMark",
    "output": "output",
    "input": "input",
    "velocity": "velocity",
    "inpos": "inpos",
    "homing": "homing",
    "homed": "homed",
    "fault": "fault",
    "enabled": "enabled",
    "min_soft_limit": "minSoftLimit",
    "max_soft_limit": "maxSoftLimit",
    "min_hard_limit": "minHardLimit",
    "max_hard_limit": "maxHardLimit",
    "override_limits": "overrideLimits",
}
AXIS_KEYS = {
    "velocity": "velocity",
    "min_position_limit": "minPositionLimit",
    "max_position_limit": "maxPositionLimit",
}
SPINDLE_KEYS = {
    "brake": "brake",
    "direction": "direction",
    "enabled": "enabled",
    "override_enabled": "spindle_override_enabled",
    "speed": "speed",
    "override": "spindle_scale",
    "homed": "homed",
    "orient_state": "orient_state",
    "orient_fault": "orient_fault",
}

# Every attribute of LinuxCNC 2.9's stat object except tool_table (a property below).
ATTRIBUTES: dict[str, Getter] = {
    # the command being executed (RCS_STAT_MSG of EMC_STAT)
    "echo_serial_number": _field("echo_serial_number"),
    "state": _field("status"),  # RCS_DONE / RCS_EXEC / RCS_ERROR
    # task
    "task_mode": _field("task.mode"),
    "task_state": _field("task.state"),
    "exec_state": _field("task.execState"),
    "interp_state": _field("task.interpState"),
    "call_level": _field("task.callLevel"),
    "read_line": _field("task.readLine"),
    "motion_line": _field("task.motionLine"),
    "current_line": _field("task.currentLine"),
    "file": _field("task.file"),
    "command": _field("task.command"),
    "program_units": _field("task.programUnits"),
    "interpreter_errcode": _field("task.interpreter_errcode"),
    "optional_stop": _field("task.optional_stop_state"),
    "block_delete": _field("task.block_delete_state"),
    "task_paused": _field("task.task_paused"),
    "input_timeout": _field("task.input_timeout"),
    "rotation_xy": _field("task.rotation_xy"),
    "ini_filename": _field("task.ini_filename"),
    "delay_left": _field("task.delayLeft"),
    "queued_mdi_commands": _field("task.queuedMDIcommands"),
    "g5x_index": _field("task.g5x_index"),
    "g5x_offset": _pose("task.g5x_offset"),
    "g92_offset": _pose("task.g92_offset"),
    "tool_offset": _pose("task.toolOffset"),
    "gcodes": _array("task.activeGCodes"),
    "mcodes": _array("task.activeMCodes"),
    "settings": _array("task.activeSettings"),
    # trajectory planner
    "linear_units": _field("motion.traj.linearUnits"),
    "angular_units": _field("motion.traj.angularUnits"),
    "cycle_time": _field("motion.traj.cycleTime"),
    "joints": _field("motion.traj.joints"),
    "spindles": _field("motion.traj.spindles"),
    "axis_mask": _field("motion.traj.axis_mask"),
    "motion_mode": _field("motion.traj.mode"),
    "enabled": _field("motion.traj.enabled"),
    "inpos": _field("motion.traj.inpos"),
    "queue": _field("motion.traj.queue"),
    "active_queue": _field("motion.traj.activeQueue"),
    "queue_full": _field("motion.traj.queueFull"),
    "motion_id": _field("motion.traj.id"),
    "paused": _field("motion.traj.paused"),
    "feedrate": _field("motion.traj.scale"),
    "rapidrate": _field("motion.traj.rapid_scale"),
    "velocity": _field("motion.traj.velocity"),
    "acceleration": _field("motion.traj.acceleration"),
    "max_velocity": _field("motion.traj.maxVelocity"),
    "max_acceleration": _field("motion.traj.maxAcceleration"),
    "probe_tripped": _field("motion.traj.probe_tripped"),
    "probing": _field("motion.traj.probing"),
    "probe_val": _field("motion.traj.probeval"),
    "kinematics_type": _field("motion.traj.kinematics_type"),
    "motion_type": _field("motion.traj.motion_type"),
    "distance_to_go": _field("motion.traj.distance_to_go"),
    "current_vel": _field("motion.traj.current_vel"),
    "feed_override_enabled": _field("motion.traj.feed_override_enabled"),
    "adaptive_feed_enabled": _field("motion.traj.adaptive_feed_enabled"),
    "feed_hold_enabled": _field("motion.traj.feed_hold_enabled"),
    "position": _pose("motion.traj.position"),
    "actual_position": _pose("motion.traj.actualPosition"),
    "probed_position": _pose("motion.traj.probedPosition"),
    "dtg": _pose("motion.traj.dtg"),
    # joints, axes, spindles, I/O of motion
    "joint": _dicts("motion.joint", emc.EMC_JOINT_STAT, JOINT_KEYS),
    "axis": _dicts("motion.axis", emc.EMC_AXIS_STAT, AXIS_KEYS),
    "spindle": _dicts("motion.spindle", emc.EMC_SPINDLE_STAT, SPINDLE_KEYS),
    "joint_position": _column("motion.joint", "output"),
    "joint_actual_position": _column("motion.joint", "input"),
    "homed": _column("motion.joint", "homed"),
    "limit": _limit_bits,
    "din": _array("motion.synch_di"),
    "dout": _array("motion.synch_do"),
    "ain": _array("motion.analog_input"),
    "aout": _array("motion.analog_output"),
    "misc_error": _array("motion.misc_error"),
    "num_extrajoints": _field("motion.numExtraJoints"),
    # iocontrol
    "pocket_prepped": _field("io.tool.pocketPrepped"),
    "tool_in_spindle": _field("io.tool.toolInSpindle"),
    "tool_from_pocket": _field("io.tool.toolFromPocket"),
    "mist": _field("io.coolant.mist"),
    "flood": _field("io.coolant.flood"),
    "estop": _field("io.aux.estop"),
    "lube": _field("io.lube.on"),
    "lube_level": _field("io.lube.level"),
    "debug": _field("debug"),
}


class _ToolData:
    """iocontrol's shared tool table (``iocontrol.tooldata``), read again only when changed."""

    def __init__(self) -> None:
        self._reader: ToolDataReader | None = None
        self._sequence = -1
        self._table: tuple[tool, ...] = ()

    def table(self) -> tuple[tool, ...]:
        try:
            if self._reader is None:
                self._reader = ToolDataReader()
            sequence = self._reader.sequence
            if sequence != self._sequence:
                self._table = _tools(self._reader.read())
                self._sequence = sequence
        except ToolDataError:
            self.close()  # iocontrol not running (yet): LinuxCNC's empty table
            self._sequence, self._table = -1, ()
        return self._table

    def close(self) -> None:
        if self._reader is not None:
            self._reader.close()
            self._reader = None


def _tools(table: ToolTable) -> tuple[tool, ...]:
    """A ToolTable as LinuxCNC's tool_table: one entry per tooldata index, 0 the spindle."""
    entries = []
    for index in range(table.last_index + 1):
        entry = table.get(index)
        entries.append(
            tool(
                entry.toolno,
                *entry.offset,
                entry.diameter,
                entry.frontangle,
                entry.backangle,
                entry.orientation,
            )
        )
    return tuple(entries)


class stat:  # LinuxCNC's name: linuxcnc.stat
    """The controller's status; ``poll()`` refreshes every attribute (``linuxcnc.stat``).

    ``stat(path)`` names an NML or INI file; without it the running machine is found (see
    ``cnc.api.connection``). Before the first ``poll()`` every attribute is zero or empty.
    """

    __slots__ = ("__dict__", "__weakref__", "_link", "_status", "_status_bytes", "_tool_data")

    def __init__(self, source: str | os.PathLike[str] | None = None) -> None:
        self._link = Link(source)
        self._link.close_with(self)
        self._status = EMC_STAT()
        self._status_bytes = self._status.byte_view()  # poll() copies into it in place
        self._tool_data = _ToolData()
        self._link.try_attach(EMC_STATUS)

    def poll(self) -> None:
        """Take the latest status; ``cnc.error`` if the controller is not running. While it
        starts (its buffers made, task not publishing yet: a HAL file's ``loadusr`` program)
        every attribute stays as it was, zero at first, as LinuxCNC's ``poll``."""
        try:
            buffer = self._link.buffer(EMC_STATUS)
            has_status = buffer.peek_into(self._status, self._status_bytes)
        except NmlError as exc:
            raise error(str(exc)) from None
        if has_status:
            self.__dict__.clear()  # attributes are computed again from the new status

    def __getattr__(self, name: str) -> Any:
        getter = ATTRIBUTES.get(name)
        if getter is None:
            raise AttributeError(f"'cnc.stat' object has no attribute '{name}'")
        value = self.__dict__[name] = getter(self._status)
        return value

    @property
    def tool_table(self) -> tuple[tool, ...]:
        """The tool table: index 0 is the tool in the spindle, then one entry per pocket."""
        return self._tool_data.table()

    def close(self) -> None:
        """Detach from the controller now (otherwise when the object is collected)."""
        self._link.close()
        self._tool_data.close()

    def __dir__(self) -> list[str]:
        return sorted({*super().__dir__(), *ATTRIBUTES})
