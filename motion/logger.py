"""``motion-logger [LOGFILE]``: a stand-in for motion that logs what task tells it.

LinuxCNC's regression tests load it instead of motmod (``loadusr -W motion-logger
out.motion-logger`` in a HAL file), run G-code, and compare the log with the lines LinuxCNC's
own motion-logger wrote: one line per command in LinuxCNC's emcmot vocabulary (``SET_LINE
x=1, y=2, ...``, ``JOINT_ACTIVATE joint=0``, ``ABORT``). It moves nothing: every command is
done at once, the machine is always in position, and the status says so, so task goes on.

It takes motion's place: motion's NML connections (it reads ``motCommand`` and answers on
``motStatus`` as process ``motion``), motion's heartbeat on the safety board, and the HAL
component ``motion-logger`` with one pin, ``motion-logger.reopen-log`` (bit, io): set it,
and the log file is closed and the pin cleared; the next line starts the file afresh (the
tests rename the log in between). Without LOGFILE the lines go to standard output.

Task sends motion EMC_* messages where LinuxCNC's task writes emcmot commands, so each
message is written as the emcmot command(s) LinuxCNC's task makes of it (``CommandLog``):
``EMC_MOTION_ABORT`` is a ``JOG_ABORT`` of every joint then ``ABORT``, as LinuxCNC's
emcMotionAbort; ``EMC_TRAJ_ENABLE`` also enables every joint's amplifier, as motion does
here. LinuxCNC's task also sends motion a few settings that have no NML message, which
motion here takes from its ``loadrt`` line and the INI file, or does not need; the log
shows them, from the INI file ($CNC_INI_FILE, LinuxCNC's defaults without it), where
LinuxCNC's task sends them at start-up (``MotionSettings``). Once the machine shuts down (the
launcher says so on the safety board), nothing more is logged: LinuxCNC's launcher stops
its motion-logger before task.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from dataclasses import dataclass, field
from typing import IO, Any

from hal.api import HAL_BIT, HAL_IO, HalError, component
from nml import emc
from nml.axes import AXIS_LETTERS, NUM_AXES
from nml.channels import MOTION_COMMAND, MOTION_STATUS, Nml, load_config
from nml.commands import Handlers, echo, handler
from nml.errors import NmlError, NmlFormatError, NmlTimeoutError
from nml.message import RCS_STATUS
from nml.safety import SafetyLink

COMPONENT = "motion-logger"
NML_PROCESS = "motion"
IDLE_POLL_S = 0.01  # as LinuxCNC's motion-logger: the reopen pin is looked at this often
STATUS_WRITE_TIMEOUT_S = 0.5
HEARTBEAT_TIMEOUT_S = 0.5  # motion's ([EMCMOT]HEARTBEAT_TIMEOUT's default)
EMCMOT = "emcmot"  # CommandLog's handler table
MOTMOD_NUM_JOINTS = 3  # motmod's num_joints and num_spindles when loadrt gives none
MOTMOD_NUM_SPINDLES = 1

# LinuxCNC's homing flags (emcmotCommand.flags of SET_JOINT_HOMING_PARAMS)
HOME_IGNORE_LIMITS = 1
HOME_USE_INDEX = 2
HOME_IS_SHARED = 4
HOME_UNLOCK_FIRST = 8
HOME_ABSOLUTE_ENCODER = 16
HOME_NO_REHOME = 32
HOME_NO_FINAL_MOVE = 64
HOME_INDEX_NO_ENCODER_RESET = 128


@dataclass
class MotionSettings:
    """What LinuxCNC's task tells motion at start-up without an NML message: motmod's
    joint and spindle counts, and the INI values motion takes itself (LinuxCNC's
    defaults where the INI file has none). The log shows each where LinuxCNC's task sends
    it: SET_NUM_JOINTS and SET_NUM_SPINDLES before the first command; SETUP_ARC_BLENDS,
    SET_MAX_FEED_OVERRIDE, SETUP_SET_PROBE_ERR_INHIBIT and SET_WORLD_HOME after the first
    SET_ACC; JOINT_ACTIVATE and SET_AXIS_LOCKING_JOINT after each joint's and each axis's
    first acceleration limit."""

    num_joints: int = MOTMOD_NUM_JOINTS  # [KINS]JOINTS
    num_spindles: int = MOTMOD_NUM_SPINDLES  # [TRAJ]SPINDLES
    max_feed_override: float = 1.0  # [DISPLAY]MAX_FEED_OVERRIDE
    probe_jog_err_inhibit: int = 0  # [TRAJ]NO_PROBE_JOG_ERROR
    probe_home_err_inhibit: int = 0  # [TRAJ]NO_PROBE_HOME_ERROR
    # [TRAJ]HOME: LinuxCNC's task reads its first three numbers (X Y Z) only
    world_home: tuple[float, ...] = (0.0,) * NUM_AXES
    locking_joints: dict[int, int] = field(default_factory=dict)  # [AXIS_L]LOCKING_INDEXER_JOINT

    @classmethod
    def read(cls, path: str) -> MotionSettings:
        """The settings of the machine's INI file (checked by the launcher already); an
        IniError or OSError if it cannot be read."""
        from cnc.ini import IniFile
        from cnc.inischema import read_config

        config = read_config(IniFile.load(path))
        value = config.value
        home = list(value("TRAJ", "HOME") or [])[:3]
        settings = cls(
            num_joints=config.joints,
            num_spindles=value("TRAJ", "SPINDLES"),
            max_feed_override=value("DISPLAY", "MAX_FEED_OVERRIDE"),
            probe_jog_err_inhibit=int(bool(value("TRAJ", "NO_PROBE_JOG_ERROR"))),
            probe_home_err_inhibit=int(bool(value("TRAJ", "NO_PROBE_HOME_ERROR"))),
            world_home=tuple(home + [0.0] * (NUM_AXES - len(home))),
        )
        for letter in config.axes:
            joint = value(f"AXIS_{letter}", "LOCKING_INDEXER_JOINT")
            settings.locking_joints[AXIS_LETTERS.index(letter)] = joint
        return settings


def _g(value: float) -> str:
    """C's ``%.6g``, as LinuxCNC's motion-logger prints most numbers."""
    return "%.6g" % value  # noqa: UP031  (printf semantics on purpose)


def _pose(pose: emc.EmcPose | tuple[float, ...]) -> str:
    """x=.., y=.., ... w=.. of an EmcPose, as LinuxCNC's motion-logger lists positions."""
    values = pose.values() if isinstance(pose, emc.EmcPose) else pose
    return ", ".join(f"{name}={_g(v)}" for name, v in zip("xyzabcuvw", values, strict=True))


class CommandLog:
    """The emcmot command lines LinuxCNC's task sends motion for each EMC_* message ours
    sends (``lines``), and the little state those lines need: the other position limit
    of a joint or axis (LinuxCNC's task sends both with each), and what was set once."""

    def __init__(self, settings: MotionSettings) -> None:
        self.settings = settings
        # LinuxCNC's task keeps both limits and starts them at 0
        self.joint_limits: dict[int, list[float]] = {}
        self.axis_limits: dict[int, list[float]] = {}
        self.is_started = False  # the first command is logged
        self.has_traj_settings = False  # after the first SET_ACC
        self.activated_joints: set[int] = set()
        self.locked_axes: set[int] = set()
        self.handlers = Handlers(self, table=EMCMOT)

    def lines(self, cmd: emc.NMLmsg) -> list[str]:
        """The lines for ``cmd``: LinuxCNC's words, or ``ERROR: unknown command`` as its
        motion-logger says of a command it does not know."""
        out = []
        if not self.is_started:
            self.is_started = True
            out += [
                f"SET_NUM_JOINTS {self.settings.num_joints}",
                f"SET_NUM_SPINDLES {self.settings.num_spindles}",
            ]
        function = self.handlers.get(type(cmd))
        if function is None:
            out.append(f"ERROR: unknown command {cmd.NAME}")
        else:
            out += function(cmd)
        return out

    # ------------------------------------------------------------------ machine
    @handler(emc.EMC_TRAJ_ABORT, table=EMCMOT)
    def _trajectory_abort(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["ABORT"]

    @handler(emc.EMC_MOTION_ABORT, table=EMCMOT)
    def _motion_abort(self, _cmd: emc.NMLmsg) -> list[str]:
        """LinuxCNC's emcMotionAbort: every possible joint's jog, then the trajectory."""
        return [f"JOG_ABORT joint={n}" for n in range(emc.EMCMOT_MAX_JOINTS)] + ["ABORT"]

    @handler(emc.EMC_TRAJ_ENABLE, table=EMCMOT)
    def _enable(self, _cmd: emc.NMLmsg) -> list[str]:
        """Motion on, and (motion here does it with it) every joint's amplifier."""
        return ["ENABLE"] + ["ENABLE_AMPLIFIER"] * self.settings.num_joints

    @handler(emc.EMC_TRAJ_DISABLE, table=EMCMOT)
    def _disable(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["DISABLE_AMPLIFIER"] * self.settings.num_joints + ["DISABLE"]

    @handler(emc.EMC_JOINT_ENABLE, table=EMCMOT)
    def _amplifier_on(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["ENABLE_AMPLIFIER"]

    @handler(emc.EMC_JOINT_DISABLE, table=EMCMOT)
    def _amplifier_off(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["DISABLE_AMPLIFIER"]

    @handler(emc.EMC_TRAJ_SET_MODE, table=EMCMOT)
    def _mode(self, cmd: emc.EMC_TRAJ_SET_MODE) -> list[str]:
        names = {
            emc.EMC_TRAJ_MODE_ENUM.FREE: "FREE",
            emc.EMC_TRAJ_MODE_ENUM.COORD: "COORD",
            emc.EMC_TRAJ_MODE_ENUM.TELEOP: "TELEOP",
        }
        return [names[cmd.mode]] if cmd.mode in names else []

    @handler(emc.EMC_TRAJ_PAUSE, table=EMCMOT)
    def _pause(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["PAUSE"]

    @handler(emc.EMC_TRAJ_RESUME, table=EMCMOT)
    def _resume(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["RESUME"]

    @handler(emc.EMC_TRAJ_STEP, table=EMCMOT)
    def _step(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["STEP"]

    @handler(emc.EMC_TRAJ_SET_SCALE, table=EMCMOT)
    def _feed_scale(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["FEED_SCALE"]

    @handler(emc.EMC_TRAJ_SET_RAPID_SCALE, table=EMCMOT)
    def _rapid_scale(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["RAPID_SCALE"]

    @handler(emc.EMC_TRAJ_SET_SPINDLE_SCALE, table=EMCMOT)
    def _spindle_scale(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_SCALE"]

    @handler(emc.EMC_TRAJ_SET_FO_ENABLE, table=EMCMOT)
    def _feed_scale_enable(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["FS_ENABLE"]

    @handler(emc.EMC_TRAJ_SET_SO_ENABLE, table=EMCMOT)
    def _spindle_scale_enable(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SS_ENABLE"]

    @handler(emc.EMC_TRAJ_SET_FH_ENABLE, table=EMCMOT)
    def _feed_hold_enable(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["FH_ENABLE"]

    @handler(emc.EMC_MOTION_ADAPTIVE, table=EMCMOT)
    def _adaptive_feed_enable(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["AF_ENABLE"]

    @handler(emc.EMC_JOINT_OVERRIDE_LIMITS, table=EMCMOT)
    def _override_limits(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["OVERRIDE_LIMITS"]

    @handler(emc.EMC_MOTION_SET_DOUT, table=EMCMOT)
    def _digital_out(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SET_DOUT"]

    @handler(emc.EMC_MOTION_SET_AOUT, table=EMCMOT)
    def _analog_out(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SET_AOUT"]

    # Kept by LinuxCNC's task itself: no emcmot command (the motion id goes with the next
    # move, the orient wait is task's timer, units and axes are task's).
    @handler(
        emc.EMC_TRAJ_SET_MAX_ACCELERATION,
        emc.EMC_TRAJ_SET_MOTION_ID,
        emc.EMC_TRAJ_SET_UNITS,
        emc.EMC_TRAJ_SET_AXES,
        emc.EMC_TRAJ_SET_CYCLE_TIME,
        emc.EMC_TRAJ_INIT,
        emc.EMC_TRAJ_HALT,
        emc.EMC_MOTION_INIT,
        emc.EMC_MOTION_HALT,
        emc.EMC_JOINT_INIT,
        emc.EMC_JOINT_HALT,
        emc.EMC_JOINT_SET_JOINT,
        emc.EMC_JOINT_SET_UNITS,
        emc.EMC_SPINDLE_CONSTANT,
        emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE,
        table=EMCMOT,
    )
    def _task_only(self, _cmd: emc.NMLmsg) -> list[str]:
        return []

    # ------------------------------------------------------------------ trajectory settings
    @handler(emc.EMC_TRAJ_SET_VELOCITY, table=EMCMOT)
    def _velocity(self, cmd: emc.EMC_TRAJ_SET_VELOCITY) -> list[str]:
        return [f"SET_VEL vel={_g(cmd.velocity)}, ini_maxvel={_g(cmd.ini_maxvel)}"]

    @handler(emc.EMC_TRAJ_SET_MAX_VELOCITY, table=EMCMOT)
    def _max_velocity(self, cmd: emc.EMC_TRAJ_SET_MAX_VELOCITY) -> list[str]:
        return [f"SET_VEL_LIMIT vel={_g(cmd.velocity)}"]

    @handler(emc.EMC_TRAJ_SET_ACCELERATION, table=EMCMOT)
    def _acceleration(self, cmd: emc.EMC_TRAJ_SET_ACCELERATION) -> list[str]:
        out = [f"SET_ACC acc={_g(cmd.acceleration)}"]
        if not self.has_traj_settings:  # (LinuxCNC's iniTraj goes on with these)
            self.has_traj_settings = True
            s = self.settings
            out += [
                "SETUP_ARC_BLENDS",
                f"SET_MAX_FEED_OVERRIDE {_g(s.max_feed_override)}",
                f"SETUP_SET_PROBE_ERR_INHIBIT {s.probe_jog_err_inhibit} {s.probe_home_err_inhibit}",
                f"SET_WORLD_HOME {_pose(s.world_home)}",
            ]
        return out

    @handler(emc.EMC_TRAJ_SET_HOME, table=EMCMOT)
    def _world_home(self, cmd: emc.EMC_TRAJ_SET_HOME) -> list[str]:
        return [f"SET_WORLD_HOME {_pose(cmd.home)}"]

    @handler(emc.EMC_TRAJ_SET_TERM_COND, table=EMCMOT)
    def _term_cond(self, cmd: emc.EMC_TRAJ_SET_TERM_COND) -> list[str]:
        return [f"SET_TERM_COND termCond={cmd.cond}, tolerance={_g(cmd.tolerance)}"]

    @handler(emc.EMC_TRAJ_SET_OFFSET, table=EMCMOT)
    def _tool_offset(self, cmd: emc.EMC_TRAJ_SET_OFFSET) -> list[str]:
        # (LinuxCNC's line has no comma between c and u)
        x, y, z, a, b, c, u, v, w = (_g(value) for value in cmd.offset.values())
        return [f"SET_OFFSET x={x}, y={y}, z={z}, a={a}, b={b}, c={c} u={u}, v={v}, w={w}"]

    @handler(emc.EMC_TRAJ_SET_SPINDLESYNC, table=EMCMOT)
    def _spindle_sync(self, cmd: emc.EMC_TRAJ_SET_SPINDLESYNC) -> list[str]:
        flags = int(bool(cmd.velocity_mode))
        return ["SET_SPINDLESYNC sync=%06f, flags=0x%08x" % (cmd.feed_per_revolution, flags)]  # noqa: UP031

    @handler(emc.EMC_TRAJ_SET_TELEOP_VECTOR, table=EMCMOT)
    def _teleop_vector(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SET_TELEOP_VECTOR"]

    # ------------------------------------------------------------------ moves
    @handler(emc.EMC_TRAJ_LINEAR_MOVE, table=EMCMOT)
    def _line(self, cmd: emc.EMC_TRAJ_LINEAR_MOVE) -> list[str]:
        return [
            f"SET_LINE {_pose(cmd.end)}, id={cmd.id}, motion_type={cmd.type}, "
            f"vel={_g(cmd.vel)}, ini_maxvel={_g(cmd.ini_maxvel)}, acc={_g(cmd.acc)}, "
            f"turn={cmd.indexer_jnum}"
        ]

    @handler(emc.EMC_TRAJ_CIRCULAR_MOVE, table=EMCMOT)
    def _circle(self, cmd: emc.EMC_TRAJ_CIRCULAR_MOVE) -> list[str]:
        center, normal = cmd.center, cmd.normal
        return [
            "SET_CIRCLE:",
            f"    pos: {_pose(cmd.end)}",
            f"    center: x={_g(center.x)}, y={_g(center.y)}, z={_g(center.z)}",
            f"    normal: x={_g(normal.x)}, y={_g(normal.y)}, z={_g(normal.z)}",
            f"    id={cmd.id}, motion_type={cmd.type}, vel={_g(cmd.vel)}, "
            f"ini_maxvel={_g(cmd.ini_maxvel)}, acc={_g(cmd.acc)}, turn={cmd.turn}",
        ]

    @handler(emc.EMC_TRAJ_PROBE, table=EMCMOT)
    def _probe(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["PROBE"]

    @handler(emc.EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG, table=EMCMOT)
    def _clear_probe(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["CLEAR_PROBE_FLAGS"]

    @handler(emc.EMC_TRAJ_RIGID_TAP, table=EMCMOT)
    def _rigid_tap(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["RIGID_TAP"]

    # ------------------------------------------------------------------ joints and jogs
    @handler(emc.EMC_JOINT_SET_BACKLASH, table=EMCMOT)
    def _backlash(self, cmd: emc.EMC_JOINT_SET_BACKLASH) -> list[str]:
        return [f"SET_JOINT_BACKLASH joint={cmd.joint}, backlash={_g(cmd.backlash)}"]

    @handler(
        emc.EMC_JOINT_SET_MIN_POSITION_LIMIT, emc.EMC_JOINT_SET_MAX_POSITION_LIMIT, table=EMCMOT
    )
    def _joint_limits(self, cmd: emc.NMLmsg) -> list[str]:
        limits = self.joint_limits.setdefault(cmd.joint, [0.0, 0.0])
        limits[isinstance(cmd, emc.EMC_JOINT_SET_MAX_POSITION_LIMIT)] = cmd.limit
        low, high = (_g(value) for value in limits)
        return [f"SET_JOINT_POSITION_LIMITS joint={cmd.joint}, min={low}, max={high}"]

    @handler(emc.EMC_JOINT_SET_FERROR, table=EMCMOT)
    def _max_ferror(self, cmd: emc.EMC_JOINT_SET_FERROR) -> list[str]:
        return [f"SET_JOINT_MAX_FERROR joint={cmd.joint}, maxFerror={_g(cmd.ferror)}"]

    @handler(emc.EMC_JOINT_SET_MIN_FERROR, table=EMCMOT)
    def _min_ferror(self, cmd: emc.EMC_JOINT_SET_MIN_FERROR) -> list[str]:
        return [f"SET_JOINT_MIN_FERROR joint={cmd.joint}, minFerror={_g(cmd.ferror)}"]

    @handler(emc.EMC_JOINT_SET_HOMING_PARAMS, table=EMCMOT)
    def _homing_params(self, cmd: emc.EMC_JOINT_SET_HOMING_PARAMS) -> list[str]:
        return [
            f"SET_JOINT_HOMING_PARAMS joint={cmd.joint}, offset={_g(cmd.offset)} "
            f"home={_g(cmd.home)}, final_vel={_g(cmd.home_final_vel)}, "
            f"search_vel={_g(cmd.search_vel)}, latch_vel={_g(cmd.latch_vel)}, "
            f"flags=0x{homing_flags(cmd):08x}, sequence={cmd.home_sequence}, "
            f"volatile={cmd.volatile_home}"
        ]

    @handler(emc.EMC_JOINT_SET_MAX_VELOCITY, table=EMCMOT)
    def _joint_velocity(self, cmd: emc.EMC_JOINT_SET_MAX_VELOCITY) -> list[str]:
        return [f"SET_JOINT_VEL_LIMIT joint={cmd.joint}, vel={_g(max(cmd.vel, 0.0))}"]

    @handler(emc.EMC_JOINT_SET_MAX_ACCELERATION, table=EMCMOT)
    def _joint_acceleration(self, cmd: emc.EMC_JOINT_SET_MAX_ACCELERATION) -> list[str]:
        out = [f"SET_JOINT_ACC_LIMIT joint={cmd.joint}, acc={_g(max(cmd.acc, 0.0))}"]
        if cmd.joint not in self.activated_joints:  # (LinuxCNC's iniJoint ends with it)
            self.activated_joints.add(cmd.joint)
            out.append(f"JOINT_ACTIVATE joint={cmd.joint}")
        return out

    @handler(emc.EMC_JOINT_ACTIVATE, table=EMCMOT)
    def _activate(self, cmd: emc.NMLmsg) -> list[str]:
        return [f"JOINT_ACTIVATE joint={cmd.joint}"]

    @handler(emc.EMC_JOINT_DEACTIVATE, table=EMCMOT)
    def _deactivate(self, cmd: emc.NMLmsg) -> list[str]:
        return [f"JOINT_DEACTIVATE joint={cmd.joint}"]

    @handler(emc.EMC_JOINT_SET_MOTOR_OFFSET, table=EMCMOT)
    def _motor_offset(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SET_JOINT_MOTOR_OFFSET"]

    @handler(emc.EMC_JOINT_LOAD_COMP, table=EMCMOT)
    def _compensation(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SET_JOINT_COMP"]

    @handler(emc.EMC_JOINT_HOME, table=EMCMOT)
    def _home(self, cmd: emc.NMLmsg) -> list[str]:
        return [f"JOINT_HOME joint={cmd.joint}"]

    @handler(emc.EMC_JOINT_UNHOME, table=EMCMOT)
    def _unhome(self, cmd: emc.NMLmsg) -> list[str]:
        return [f"JOINT_UNHOME joint={cmd.joint}"]

    @handler(emc.EMC_JOINT_ABORT, table=EMCMOT)
    def _joint_abort(self, cmd: emc.NMLmsg) -> list[str]:
        return [f"JOG_ABORT joint={cmd.joint}"]

    @handler(emc.EMC_JOG_STOP, table=EMCMOT)
    def _jog_stop(self, cmd: emc.EMC_JOG_STOP) -> list[str]:
        joint = cmd.joint_or_axis if cmd.jjogmode else -1  # (an axis jog names no joint)
        return [f"JOG_ABORT joint={joint}"]

    @handler(emc.EMC_JOG_CONT, table=EMCMOT)
    def _jog_cont(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["JOG_CONT"]

    @handler(emc.EMC_JOG_INCR, table=EMCMOT)
    def _jog_incr(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["JOG_INCR"]

    @handler(emc.EMC_JOG_ABS, table=EMCMOT)
    def _jog_abs(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["JOG_ABS"]

    # ------------------------------------------------------------------ axes
    @handler(emc.EMC_AXIS_SET_MIN_POSITION_LIMIT, emc.EMC_AXIS_SET_MAX_POSITION_LIMIT, table=EMCMOT)
    def _axis_limits(self, cmd: emc.NMLmsg) -> list[str]:
        limits = self.axis_limits.setdefault(cmd.axis, [0.0, 0.0])
        limits[isinstance(cmd, emc.EMC_AXIS_SET_MAX_POSITION_LIMIT)] = cmd.limit
        low, high = (_g(value) for value in limits)
        return [f"SET_AXIS_POSITION_LIMITS axis={cmd.axis}, min={low}, max={high}"]

    @handler(emc.EMC_AXIS_SET_MAX_VELOCITY, table=EMCMOT)
    def _axis_velocity(self, cmd: emc.EMC_AXIS_SET_MAX_VELOCITY) -> list[str]:
        return [f"SET_AXIS_VEL_LIMIT axis={cmd.axis} vel={_g(max(cmd.vel, 0.0))}"]

    @handler(emc.EMC_AXIS_SET_MAX_ACCELERATION, table=EMCMOT)
    def _axis_acceleration(self, cmd: emc.EMC_AXIS_SET_MAX_ACCELERATION) -> list[str]:
        out = [f"SET_AXIS_ACC_LIMIT axis={cmd.axis}, acc={_g(max(cmd.acc, 0.0))}"]
        if cmd.axis not in self.locked_axes:  # (LinuxCNC's iniAxis ends with it)
            self.locked_axes.add(cmd.axis)
            joint = max(self.settings.locking_joints.get(cmd.axis, -1), -1)
            out.append(f"SET_AXIS_LOCKING_JOINT axis={cmd.axis}, locking_joint={joint}")
        return out

    # ------------------------------------------------------------------ spindles
    @handler(emc.EMC_SPINDLE_SET_PARAMS, table=EMCMOT)
    def _spindle_params(self, cmd: emc.EMC_SPINDLE_SET_PARAMS) -> list[str]:
        # LinuxCNC's order: fastest forward, slowest forward, fastest and slowest reverse
        # (negative: + 0.0 keeps a zero from printing as -0)
        speeds = (cmd.max_forward, cmd.min_forward, -cmd.max_reverse + 0.0, -cmd.min_reverse + 0.0)
        return ["SET_SPINDLE_PARAMS, " + ", ".join("%.2e" % s for s in speeds)]  # noqa: UP031

    @handler(emc.EMC_SPINDLE_ON, emc.EMC_SPINDLE_SPEED, table=EMCMOT)
    def _spindle_on(self, cmd: emc.NMLmsg) -> list[str]:
        speeds = (cmd.speed, cmd.factor, cmd.xoffset)
        return ["SPINDLE_ON speed=%f, css_factor=%f, xoffset=%f" % speeds]  # noqa: UP031

    @handler(emc.EMC_SPINDLE_OFF, table=EMCMOT)
    def _spindle_off(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_OFF"]

    @handler(emc.EMC_SPINDLE_INCREASE, table=EMCMOT)
    def _spindle_increase(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_INCREASE"]

    @handler(emc.EMC_SPINDLE_DECREASE, table=EMCMOT)
    def _spindle_decrease(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_DECREASE"]

    @handler(emc.EMC_SPINDLE_BRAKE_ENGAGE, table=EMCMOT)
    def _brake_on(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_BRAKE_ENGAGE"]

    @handler(emc.EMC_SPINDLE_BRAKE_RELEASE, table=EMCMOT)
    def _brake_off(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_BRAKE_RELEASE"]

    @handler(emc.EMC_SPINDLE_ORIENT, table=EMCMOT)
    def _orient(self, _cmd: emc.NMLmsg) -> list[str]:
        return ["SPINDLE_ORIENT"]


def homing_flags(cmd: emc.EMC_JOINT_SET_HOMING_PARAMS) -> int:
    """LinuxCNC's emcmot homing flags for a joint's homing parameters."""
    flags = 0
    for is_set, flag in (
        (cmd.use_index, HOME_USE_INDEX),
        (cmd.encoder_does_not_reset, HOME_INDEX_NO_ENCODER_RESET),
        (cmd.ignore_limits, HOME_IGNORE_LIMITS),
        (cmd.is_shared, HOME_IS_SHARED),
        (cmd.locking_indexer, HOME_UNLOCK_FIRST),
    ):
        if is_set:
            flags |= flag
    if cmd.absolute_encoder in (1, 2):  # 1: no rehoming; 2: and no final move
        flags |= HOME_ABSOLUTE_ENCODER | HOME_NO_REHOME
    if cmd.absolute_encoder == 2:
        flags |= HOME_NO_FINAL_MOVE
    return flags


_SPINDLE_SPEEDS = (emc.EMC_SPINDLE_ON, emc.EMC_SPINDLE_SPEED, emc.EMC_SPINDLE_OFF)


class MotionState:
    """What the status says of a motion that moves nothing: enabled or not, its mode, the
    homed joints, the spindles' speeds; always in position with an empty queue."""

    def __init__(self, num_joints: int, num_spindles: int) -> None:
        self.num_joints = num_joints
        self.num_spindles = num_spindles
        self.is_enabled = False
        self.mode = emc.EMC_TRAJ_MODE_ENUM.FREE
        self.is_homed = [False] * num_joints
        self.is_volatile_home = [False] * num_joints
        self.spindle_speeds = [0.0] * num_spindles

    def take(self, cmd: emc.NMLmsg) -> None:
        """Follow ``cmd``: the commands whose effect task reads back from the status."""
        if isinstance(cmd, emc.EMC_TRAJ_ENABLE):
            self.is_enabled = True
        elif isinstance(cmd, emc.EMC_TRAJ_DISABLE):
            self.is_enabled = False
        elif isinstance(cmd, emc.EMC_TRAJ_SET_MODE):
            self.mode = cmd.mode
        elif isinstance(cmd, emc.EMC_JOINT_SET_HOMING_PARAMS) and self._has_joint(cmd.joint):
            self.is_volatile_home[cmd.joint] = bool(cmd.volatile_home)
        elif isinstance(cmd, (emc.EMC_JOINT_HOME, emc.EMC_JOINT_UNHOME)):
            is_homed = isinstance(cmd, emc.EMC_JOINT_HOME)
            for joint in self._joints_named(cmd.joint):
                self.is_homed[joint] = is_homed
        elif isinstance(cmd, _SPINDLE_SPEEDS) and 0 <= cmd.spindle < self.num_spindles:
            is_off = isinstance(cmd, emc.EMC_SPINDLE_OFF)
            self.spindle_speeds[cmd.spindle] = 0.0 if is_off else cmd.speed

    def _has_joint(self, joint: int) -> bool:
        return 0 <= joint < self.num_joints

    def _joints_named(self, joint: int) -> list[int]:
        """-1: every joint; -2: the VOLATILE_HOME ones (unhome only); else that joint."""
        if joint == -1:
            return list(range(self.num_joints))
        if joint == -2:
            return [n for n in range(self.num_joints) if self.is_volatile_home[n]]
        return [joint] if self._has_joint(joint) else []

    def fill(self, stat: emc.EMC_MOTION_STAT) -> None:
        traj = stat.traj
        traj.joints, traj.spindles = self.num_joints, self.num_spindles
        traj.enabled, traj.mode = self.is_enabled, self.mode
        traj.inpos, traj.queue, traj.queueFull = True, 0, False
        traj.scale = traj.rapid_scale = 1.0
        traj.feed_override_enabled = traj.feed_hold_enabled = True
        for index in range(self.num_joints):
            joint = stat.joint[index]
            joint.homed, joint.inpos, joint.enabled = self.is_homed[index], 1, self.is_enabled
        for index, speed in enumerate(self.spindle_speeds):
            spindle = stat.spindle[index]
            spindle.speed, spindle.enabled, spindle.state = speed, speed != 0, speed != 0
            spindle.direction = (speed > 0) - (speed < 0)
            spindle.spindle_scale = 1.0
            spindle.spindle_override_enabled = True


class LogFile:
    """Where the lines go: the file (opened, emptied, at the first line after a reopen) or
    standard output; each line flushed at once, as LinuxCNC's motion-logger does."""

    def __init__(self, path: str | None) -> None:
        self.path = path
        self.file: IO[str] | None = None if path else sys.stdout

    def write(self, lines: list[str]) -> None:
        if not lines:
            return
        if self.file is None:
            self.file = open(self.path, "w")  # noqa: SIM115  (kept open between lines)
        self.file.write("".join(f"{line}\n" for line in lines))
        self.file.flush()

    def close(self) -> None:
        """Close the file; the next line opens it again."""
        if self.file is not None and self.file is not sys.stdout:
            self.file.close()
            self.file = None


class MotionLogger:
    """The process: HAL component, NML connections as motion, the safety board."""

    def __init__(self, log: LogFile, settings: MotionSettings) -> None:
        self.log = log
        self.commands = CommandLog(settings)
        self.state = MotionState(settings.num_joints, settings.num_spindles)
        self.status = emc.EMC_MOTION_STAT()
        self.comp: component | None = None
        self.nml: Nml | None = None
        self.safety: SafetyLink | None = None
        self.is_stopping = False

    def open(self) -> None:
        comp = component(COMPONENT)
        comp.newpin("reopen-log", HAL_BIT, HAL_IO)
        comp["reopen-log"] = False
        self.comp = comp
        self.nml = Nml(
            load_config(os.environ.get("CNC_NML_FILE") or None),
            NML_PROCESS,
            [MOTION_COMMAND, MOTION_STATUS],
        )
        self.safety = SafetyLink.open(NML_PROCESS, HEARTBEAT_TIMEOUT_S, is_reporter=False)
        self.publish()
        comp.ready()

    def close(self) -> None:
        self.log.close()
        if self.safety is not None:
            self.safety.close()
            self.safety = None
        if self.comp is not None:
            self.comp.exit()
            self.comp = None
        if self.nml is not None:
            self.nml.close()
            self.nml = None

    def stop(self, *_: Any) -> None:
        """Signal handler: leave the loop at the next wake-up."""
        self.is_stopping = True

    def run(self) -> None:
        assert self.nml is not None
        commands = self.nml[MOTION_COMMAND]
        while not self.is_stopping:
            self._take_safety_requests()
            self._reopen_if_asked()
            try:
                cmd = commands.blocking_read(IDLE_POLL_S)
            except NmlFormatError as exc:
                print(f"{COMPONENT}: bad command ignored: {exc}", file=sys.stderr, flush=True)
                continue
            if cmd is not None:
                self.handle(cmd)

    def handle(self, cmd: emc.NMLmsg) -> None:
        """Log the command (unless the machine is shutting down), follow it, answer DONE."""
        if not self._is_shutting_down():
            self._reopen_if_asked()
            self.log.write(self.commands.lines(cmd))
        self.state.take(cmd)
        echo(self.status, cmd, RCS_STATUS.DONE)
        self.publish()

    def publish(self) -> None:
        assert self.nml is not None
        self.state.fill(self.status)
        self.status.heartbeat = (self.status.heartbeat + 1) & 0xFFFFFFFF
        while not self.is_stopping:  # (task waits for this answer: a busy buffer is retried)
            try:
                self.nml[MOTION_STATUS].write(self.status, timeout=STATUS_WRITE_TIMEOUT_S)
                return
            except NmlTimeoutError:
                continue

    def _reopen_if_asked(self) -> None:
        comp = self.comp
        if comp is not None and comp["reopen-log"]:
            self.log.close()
            comp["reopen-log"] = False

    def _take_safety_requests(self) -> None:
        """Beat motion's heartbeat; an E-stop from the safety board turns motion off, as
        it does motion's (nothing is logged: it is no command)."""
        if self.safety is None:
            return
        tick = self.safety.tick()
        if tick.estop is not None and self.state.is_enabled:
            self.state.is_enabled = False
            self.publish()

    def _is_shutting_down(self) -> bool:
        return self.safety is not None and self.safety.board.is_shutting_down


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="motion-logger", description="log the commands task sends motion (a stand-in)"
    )
    parser.add_argument("logfile", nargs="?", help="the log file (default: standard output)")
    args = parser.parse_args(argv)
    settings = MotionSettings()
    ini_path = os.environ.get("CNC_INI_FILE")
    if ini_path:
        try:
            settings = MotionSettings.read(ini_path)
        except (OSError, ValueError) as exc:  # (IniError is a ValueError)
            print(f"{COMPONENT}: {exc}; LinuxCNC's defaults used", file=sys.stderr, flush=True)
    logger = MotionLogger(LogFile(args.logfile), settings)
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, logger.stop)
    try:
        logger.open()
        logger.run()
    except (NmlError, HalError, OSError) as exc:
        print(f"{COMPONENT}: {exc}", file=sys.stderr, flush=True)
        return 1
    finally:
        logger.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
