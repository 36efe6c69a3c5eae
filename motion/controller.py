"""The motion controller: commands in, one servo period at a time, joint commands out.

``MotionController`` is what ``loadrt motmod`` runs (``motion/motmod.py`` connects it to HAL
pins and NML buffers). It owns the joints, the free-mode planners, the coordinated-mode
trajectory planner and the kinematics, and follows LinuxCNC's position flow (MOT-001..007):

    coord:  trajectory planner -> carte_pos_cmd -> inverse kinematics -> joint pos_cmd
    teleop: axis jogs + teleop vector, slowed within the joint limits -> carte_pos_cmd
            -> inverse kinematics -> joint pos_cmd (motion/teleop.py)
    free:   per-joint planners -> joint pos_cmd -> forward kinematics -> carte_pos_cmd
    both:   motor_pos_cmd = pos_cmd + motor_offset;  pos_fb = motor_pos_fb - motor_offset

Its parts, one concern each: ``motion/spindle.py`` (spindle commands, pins and feedback,
MOT-065), ``motion/wheels.py`` (MPG wheels and the jog-stop inputs), ``motion/status.py``
(EMC_MOTION_STAT filled every period), ``motion/teleop.py`` (teleop mode: its planners,
the teleop vector command and each teleop period) and ``motion/modes.py`` (FREE, COORD,
TELEOP).

Commands are NML messages (``nml.emc``), each carried out by the ``@handler`` method that
names it (``nml/commands.py``); ``handle(cmd)`` returns ``None`` when the command was
carried out, or the reason it was refused (MOT-019: where LinuxCNC ignores a command
silently, we refuse it and say why). Faults found during a period (following error, hard
limits, planner errors) are queued in ``errors`` for the caller to report.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from motion.eoffsets import EoffsetInputs, ExternalOffsets
from motion.extrajoints import ExtraJoints
from motion.free import FreePlanner, JogLimitError, check_finite
from motion.homing import Homing, HomingConfig, HomingError
from motion.indexer import LockingIndexers
from motion.joint import Joint
from motion.kinematics import Kinematics, KinematicsError, KinematicsType
from motion.modes import COORD, FREE, TELEOP
from motion.spindle import OrientState, Spindle, SpindleControl, SpindleInputs
from motion.status import QUEUE_FULL_MARGIN, MotionStatusRuns, StatusFilling
from motion.teleop import JointLimiter, TeleopControl, TeleopPlanner
from motion.tp import TermCond, TrajectoryPlanner
from motion.tp.planner import ProbeType
from motion.wheels import JogWheels, WheelInputs
from nml import emc
from nml.axes import AXIS_LETTERS, NUM_AXES
from nml.commands import Handlers, Refused, handler
from nml.pose import Pose

_TERM_CONDS = {
    emc.EMC_TRAJ_TERM_COND.STOP: TermCond.STOP,
    emc.EMC_TRAJ_TERM_COND.EXACT: TermCond.EXACT,
    emc.EMC_TRAJ_TERM_COND.BLEND: TermCond.BLEND,
}
DEFAULT_JOINT_VEL = 1.0
DEFAULT_JOINT_ACC = 1.0


@dataclass
class Inputs:
    """HAL inputs of one servo period."""

    motor_pos_fb: list[float]
    pos_limit: list[bool]
    neg_limit: list[bool]
    amp_fault: list[bool]
    home_switch: list[bool] = field(default_factory=list)
    index_enable: list[bool] = field(default_factory=list)  # cleared by the encoder at index
    probe: bool = False
    enable: bool = True  # motion.enable
    digital_in: list[bool] = field(default_factory=list)
    analog_in: list[float] = field(default_factory=list)
    spindles: list[SpindleInputs] = field(default_factory=list)
    joint_wheels: list[WheelInputs] = field(default_factory=list)  # one per joint
    is_jog_inhibited: bool = False  # motion.jog-inhibit
    is_jog_stop: bool = False  # motion.jog-stop: stop jogs at the acceleration limit
    is_jog_stop_immediate: bool = False  # motion.jog-stop-immediate
    axis_wheels: dict[int, WheelInputs] = field(default_factory=dict)  # axis index -> wheel
    eoffsets: dict[int, EoffsetInputs] = field(default_factory=dict)  # axis.L.eoffset-*
    posthome_cmd: list[float] = field(default_factory=list)  # of the extra joints


@dataclass
class JogLease:
    """A continuous jog's requester: its heartbeat slot on the safety board and pid (pid 0:
    none, the jog runs ``periods_left`` periods unless a new EMC_JOG_CONT renews it)."""

    name: str  # "joint 0", "axis X": for the message when it is stopped
    slot: int
    pid: int
    periods_left: int = -1  # set by the first check of an unleased jog


class MotionController(SpindleControl, JogWheels, TeleopControl, StatusFilling):
    def __init__(
        self,
        kinematics: Kinematics,
        num_joints: int,
        period_s: float,
        num_spindles: int = 1,
        num_dio: int = 4,
        num_aio: int = 4,
        planner_factory: Callable[..., TrajectoryPlanner] = TrajectoryPlanner,
        homing_class: type[Homing] = Homing,
        num_extrajoints: int = 0,
        unlock_joints_mask: int = 0,
    ) -> None:
        if not 1 <= num_joints <= emc.EMCMOT_MAX_JOINTS:
            raise ValueError(f"num_joints must be 1..{emc.EMCMOT_MAX_JOINTS}, got {num_joints}")
        if not 0 <= num_extrajoints < num_joints:
            raise ValueError(f"num_extrajoints must be 0..{num_joints - 1}, got {num_extrajoints}")
        num_kins_joints = num_joints - num_extrajoints
        if getattr(kinematics, "num_joints", num_kins_joints) != num_kins_joints:
            raise ValueError(
                f"kinematics maps {kinematics.num_joints} joints, motmod has {num_kins_joints}"
                + (f" (and {num_extrajoints} extra joints)" if num_extrajoints else "")
            )
        self.kins = kinematics
        self.period_s = period_s
        self.joints = [Joint(DEFAULT_JOINT_VEL, DEFAULT_JOINT_ACC) for _ in range(num_joints)]
        self.kins_joints = self.joints[:num_kins_joints]  # the joints kinematics maps
        # --- hooks: extra joints, locking indexers, external offsets (their own modules)
        self.extra_joints = ExtraJoints(self.joints, num_extrajoints)
        self.indexers = LockingIndexers(self.joints, unlock_joints_mask)
        self.is_faulted = [False] * num_joints
        self.homing_class = homing_class  # ARCH-007/008: default or a user's homing module
        self.homing_configs = [HomingConfig() for _ in range(num_joints)]
        self.homing = self.homing_class(self.joints, self.homing_configs)
        self.spindles = [Spindle() for _ in range(num_spindles)]
        self.digital_out = [False] * num_dio
        self.analog_out = [0.0] * num_aio
        self.digital_in = [False] * num_dio
        self.analog_in = [0.0] * num_aio
        self.axis_max_vel = [math.inf] * NUM_AXES
        self.axis_max_acc = [math.inf] * NUM_AXES
        self.axis_min_limit = [-math.inf] * NUM_AXES
        self.axis_max_limit = [math.inf] * NUM_AXES
        self.eoffsets = ExternalOffsets(self.axis_min_limit, self.axis_max_limit)
        self.tp = planner_factory(self.axis_max_vel, self.axis_max_acc, cycle_time=period_s)
        # teleop: one planner per world axis, as LinuxCNC 2.9 jogs axes (MOT-016, MOT-046)
        self.axis_planners = [
            FreePlanner(DEFAULT_JOINT_VEL, DEFAULT_JOINT_ACC) for _ in range(NUM_AXES)
        ]
        # ... plus the teleop vector (MOT-055); their sum is kept within the joint limits
        self.teleop = TeleopPlanner(
            self.axis_max_vel, self.axis_max_acc, self.axis_min_limit, self.axis_max_limit
        )
        self.joint_limiter = JointLimiter(self._inverse_array)
        self.mode = FREE
        # homing that leaves every joint homed ends free mode: world axes jog from then
        # on, as LinuxCNC's motion switches to teleop mode by itself once in position
        self.is_teleop_after_homing = False
        self.was_all_homed = False  # (free mode's last period)
        self.is_enabled = False
        self.is_override_limits = False
        self.carte_pos_cmd = Pose()
        self.carte_pos_fb = Pose()
        # EMC_TRAJ_SET_VELOCITY / _ACCELERATION, only reported (traj.velocity, acceleration):
        # 0 until task sends one, as LinuxCNC's motion starts
        self.traj_vel = 0.0
        self.traj_acc = 0.0
        self.max_vel = math.inf
        self.max_acc = math.inf
        self.term_cond = TermCond.BLEND
        self.tolerance = 0.0
        self.next_motion_id = 0
        # A refused move leaves a hole in the path: what task queued after it must not run
        # (it would start from the wrong place), so every command is refused, quietly,
        # until task, which sees the refusal, aborts (LinuxCNC's task aborts the program)
        # or motion starts afresh (_ENDS_A_REFUSED_PROGRAM).
        self.is_after_refused_move = False
        self.motion_type = 0
        self.tool_offset = Pose()
        self.is_feed_override_enabled = True
        self.is_feed_hold_enabled = True
        self.is_adaptive_feed_enabled = False
        self.errors: list[str] = []
        self.sync_spindle = 0  # the spindle synchronised moves follow (SET_SPINDLESYNC)
        self._wheel_counts: dict[tuple[str, int], int] = {}  # last jog-counts seen
        self.is_jog_inhibited = False
        self._jog_stops = (False, False)  # jog-stop, jog-stop-immediate last period
        self._orient_wait: tuple[int, float] | None = None  # (spindle, seconds left)
        self._is_last_move_rapid = True
        self._pending_douts: list[tuple[int, bool]] = []
        self._pending_aouts: list[tuple[int, float]] = []
        self._status_runs: MotionStatusRuns | None = None  # of the last fill_status's record
        # continuous jogs and who asked for them: (is joint, index) -> lease (motion/safety.py)
        self.jog_leases: dict[tuple[bool, int], JogLease] = {}
        self.handlers = Handlers(self)  # the @handler methods below

    # ================================================================ commands
    def handle(self, cmd: emc.NMLmsg) -> str | None:
        """Carry out one command; ``None`` if done, else why it was refused ("" when it
        says nothing new: a command after a refused move, see ``is_after_refused_move``).
        Handlers (``@handler``) raise ``Refused``; a ValueError or a kinematics error is a
        refusal too, naming the command. Any other exception goes to the caller (motmod:
        an internal error, motion off)."""
        function = self.handlers.get(type(cmd))
        if function is None:
            return f"motion does not handle {cmd.NAME}"
        if self.is_after_refused_move:
            if type(cmd) not in _ENDS_A_REFUSED_PROGRAM:
                return ""
            self.is_after_refused_move = False
        is_move = isinstance(cmd, emc.MOVES_WITH_MOTION_ID)
        if is_move and cmd.id:  # task stamps the line into the move (emcmotCommand.id)
            self.next_motion_id = cmd.id  # (0: the last EMC_TRAJ_SET_MOTION_ID's stays)
        try:
            function(cmd)
            return None
        except Refused as refusal:
            problem = refusal.reason
        except (ValueError, KinematicsError) as exc:
            problem = f"{cmd.NAME}: {exc}"
        if is_move:
            self.is_after_refused_move = True
        return problem

    def _joint(self, index: int) -> Joint:
        if not 0 <= index < len(self.joints):
            raise ValueError(f"joint {index} does not exist (0..{len(self.joints) - 1})")
        return self.joints[index]

    @handler(emc.EMC_TRAJ_ENABLE)
    def _enable(self, _cmd: emc.NMLmsg) -> None:
        self.is_enabled = True
        self.is_faulted = [False] * len(self.joints)
        for joint in self.joints:
            joint.hold_position()
        if self.eoffsets.reset():  # hook: offsets zero at machine on, the pose keeps them
            self.tp.set_position(list(self.carte_pos_cmd))
            self._reset_teleop()

    @handler(emc.EMC_TRAJ_DISABLE)
    def _disable(self, _cmd: emc.NMLmsg | None = None) -> None:
        """Motion off: everything stops where it is, the queue is emptied (MOT-021)."""
        self.is_enabled = False
        self._stop_everything_now()
        self.indexers.release_all()  # hook: no unlock request with motion off

    def estop(self) -> None:
        """E-stop from the safety board: motion off at once and every spindle stopped,
        whatever task does (task says why, or the process that asked for it)."""
        self._disable()
        self.stop_spindles()

    def abort_all(self) -> None:
        """Abort from the safety board: as task's abort, every spindle stops too."""
        self._abort(None)
        self.stop_spindles()

    def fault(self, message: str) -> None:
        """A fault (found during a period, or motmod's report of an internal error): say
        so and turn motion off."""
        self.errors.append(message)
        self._disable()

    def _stop_everything_now(self) -> None:
        self.jog_leases.clear()
        self.homing.abort()
        self._orient_wait = None
        for joint in self.joints:
            joint.planner.reset(joint.pos_cmd)
        self.tp.set_position(list(self.carte_pos_cmd))
        self._reset_teleop()

    @handler(emc.EMC_TRAJ_ABORT, emc.EMC_MOTION_ABORT)
    def _abort(self, _cmd: emc.NMLmsg | None) -> None:
        """ABORT: always accepted, idempotent; decelerates, then empties the queue (MOT-022)."""
        self.jog_leases.clear()
        self.homing.abort()
        for planner in (j.planner for j in self.joints):
            planner.stop()
        self._stop_teleop()
        self.tp.abort()
        self._orient_wait = None

    @handler(emc.EMC_TRAJ_SET_MODE)
    def _set_mode(self, cmd: emc.EMC_TRAJ_SET_MODE) -> None:
        mode = cmd.mode
        self.is_teleop_after_homing = False  # (a mode asked for replaces the one pending)
        self.was_all_homed = all(j.is_homed for j in self.joints)
        if mode == self.mode:
            return
        if mode not in (FREE, COORD, TELEOP):
            raise Refused(f"unknown trajectory mode {mode}")
        if self._is_moving():
            raise Refused("cannot change mode while moving")
        if (
            mode in (COORD, TELEOP)
            and self.kins.kinematics_type() != KinematicsType.IDENTITY  # as LinuxCNC's motion
            and not all(j.is_homed for j in self.joints)
        ):
            raise Refused("all joints must be homed before going into coordinated mode")
        if mode == TELEOP:
            self._reset_teleop()
        if mode == COORD:  # (hook: the planner's pose is without external offsets)
            self.tp.set_position(self.eoffsets.remove(self.carte_pos_cmd))
        else:
            for joint in self.joints:
                joint.planner.reset(joint.pos_cmd)
        self.mode = mode

    def _is_moving(self) -> bool:
        # (teleop motion only exists in teleop mode: leaving it waits for rest)
        return (
            not self.tp.is_done
            or self._orient_wait is not None
            or self.homing.is_homing
            or any(j.planner.is_active for j in self.joints)
            or (self.mode == TELEOP and self._is_teleop_moving())
        )

    # ---------------------------------------------------------------- jogs (free mode)
    @handler(emc.EMC_JOG_STOP)
    def _jog_stop(self, cmd: emc.EMC_JOG_STOP) -> None:
        """Stop a jog: accepted in any state and mode, never refused (MOT-052). A stop
        sent for a joint while motion is in teleop (or for an axis in free mode) stops
        what that index is doing now, as LinuxCNC's jog abort does."""
        index = cmd.joint_or_axis
        is_joint = cmd.jjogmode == emc.JOG_MODE.JOINT
        for key in ((is_joint, index), (not is_joint, index)):
            is_joint_key, number = key
            if is_joint_key and (self.homing.is_homing or not 0 <= number < len(self.joints)):
                continue  # (homing owns the joint planners; abort cancels it)
            if not is_joint_key and not 0 <= number < NUM_AXES:
                continue
            self.jog_leases.pop(key, None)
            planner = self.jog_planner(key)
            if planner.is_active:
                planner.stop()

    @handler(emc.EMC_JOG_CONT, emc.EMC_JOG_INCR, emc.EMC_JOG_ABS)
    def _jog(self, cmd: emc.NMLmsg) -> None:
        """Jog a joint in free mode, or a world axis in teleop mode (MOT-045..052)."""
        if not self.is_enabled:
            raise Refused("cannot jog with motion disabled")
        if self.homing.is_homing:
            raise Refused("cannot jog while homing")
        if self.is_jog_inhibited:
            raise Refused("jogging is inhibited (motion.jog-inhibit)")
        index = cmd.joint_or_axis
        if cmd.jjogmode == emc.JOG_MODE.JOINT:
            if self.mode != FREE:
                raise Refused("jogging a joint needs free (joint) mode")
            joint = self._joint(index)
            is_locking = self.homing_configs[index].locking_indexer
            problem = self.extra_joints.check_jog(index) or self.indexers.check_jog(
                index, None, is_locking
            )
            if problem:
                raise Refused(problem)  # (hook)
            planner, name = joint.planner, f"joint {index}"
            override = self.is_override_limits or not joint.is_homed
        else:
            if self.mode != TELEOP:
                raise Refused("jogging an axis needs teleop mode (teleop_enable(1) once homed)")
            if not 0 <= index < NUM_AXES or not self._has_axis(index):
                raise Refused(f"axis {index} is not used by this machine")
            problem = self.indexers.check_jog(None, index)
            if problem:
                raise Refused(problem)  # (hook)
            planner, name = self.axis_planners[index], f"axis {AXIS_LETTERS[index]}"
            override = self.is_override_limits
        try:
            if isinstance(cmd, emc.EMC_JOG_CONT):
                planner.jog_cont(cmd.vel, override)
            elif isinstance(cmd, emc.EMC_JOG_INCR):
                direction = math.copysign(1.0, cmd.vel) if cmd.vel else 1.0
                planner.jog_incr(cmd.incr * direction, abs(cmd.vel), override)
            else:
                planner.jog_abs(cmd.pos, abs(cmd.vel), override)
        except JogLimitError as exc:
            raise Refused(f"{name}: {exc}") from None
        key = (cmd.jjogmode == emc.JOG_MODE.JOINT, index)
        if isinstance(cmd, emc.EMC_JOG_CONT):  # runs while its requester keeps the lease
            self.jog_leases[key] = JogLease(name, cmd.lease_slot, cmd.lease_pid)
        else:
            self.jog_leases.pop(key, None)

    def jog_planner(self, key: tuple[bool, int]) -> FreePlanner:
        """The planner of a jog lease's key: (is joint, index)."""
        is_joint, index = key
        return self.joints[index].planner if is_joint else self.axis_planners[index]

    def stop_jog(self, key: tuple[bool, int], reason: str) -> None:
        """Brake a continuous jog to a stop (its requester went quiet) and say why."""
        self.jog_leases.pop(key, None)
        planner = self.jog_planner(key)
        if planner.is_active:
            planner.stop()
            self.errors.append(reason)

    def _has_axis(self, index: int) -> bool:
        return bool(getattr(self.kins, "axis_mask", 0b111) >> index & 1)

    def _inverse_array(self, pose: np.ndarray) -> list[float]:
        return self.kins.inverse(Pose(*pose.tolist()))

    # ---------------------------------------------------------------- coordinated moves
    def _require_coord(self) -> str | None:
        if self.mode != COORD:
            return "moves need coordinated mode"
        if not self.is_enabled:
            return "cannot move with motion disabled"
        if self.tp.is_full:
            return "motion queue is full"
        return None

    def _check_soft_limits(self, end: Pose, what: str) -> str | None:
        """Refuse a move whose end is outside an axis's or a joint's limits, in LinuxCNC's
        words (one line per limit crossed) (MOT-072)."""
        if self.is_override_limits:
            return None
        line = self.next_motion_id
        problems = []
        for index, value in enumerate(end):
            letter = AXIS_LETTERS[index]
            if value > self.axis_max_limit[index]:
                problems.append(f"{what} on line {line} would exceed {letter}'s positive limit")
            elif value < self.axis_min_limit[index]:
                problems.append(f"{what} on line {line} would exceed {letter}'s negative limit")
        for index, (joint, target) in enumerate(
            zip(self.joints, self.kins.inverse(end), strict=False)
        ):
            if target > joint.max_limit:
                problems.append(
                    f"{what} on line {line} would exceed joint {index}'s positive limit"
                )
            elif target < joint.min_limit:
                problems.append(
                    f"{what} on line {line} would exceed joint {index}'s negative limit"
                )
        return "\n".join(problems) or None

    @handler(emc.EMC_TRAJ_LINEAR_MOVE)
    def _linear_move(self, cmd: emc.EMC_TRAJ_LINEAR_MOVE) -> None:
        end = cmd.end.pose()
        problem = self._require_coord() or self._check_soft_limits(end, "Linear move")
        if problem:
            raise Refused(problem)
        is_indexing = cmd.type == emc.EMC_MOTION_TYPE.INDEXROTARY  # (task named the joint)
        is_rapid = is_indexing or cmd.type == emc.EMC_MOTION_TYPE.TRAVERSE
        self._note_move_type(is_rapid)
        # (hook) a move of a locking indexer's axis waits for its unlock (motion/indexer.py)
        indexer = {}
        if self.indexers.axis_joint or is_indexing:
            requested = cmd.indexer_jnum if is_indexing else -1
            joint = self.indexers.indexing_joint(self.tp.end_position, list(end), requested)
            if joint >= 0:
                problem = self.indexers.check_move(joint)
                if problem:
                    raise Refused(problem)
                indexer = {"indexer_joint": joint}
        self.tp.add_line(
            list(end),
            cmd.vel,
            cmd.ini_maxvel,
            cmd.acc,
            motion_id=self.next_motion_id,
            term=TermCond.STOP if indexer else self.term_cond,
            tolerance=self.tolerance,
            is_rapid=is_rapid,
            tag=cmd.tag.to_bytes(),
            **indexer,
        )
        self._flush_synchronised_outputs()

    @handler(emc.EMC_TRAJ_CIRCULAR_MOVE)
    def _circular_move(self, cmd: emc.EMC_TRAJ_CIRCULAR_MOVE) -> None:
        end = cmd.end.pose()
        problem = self._require_coord() or self._check_soft_limits(end, "Circular move")
        if problem:
            raise Refused(problem)
        self._note_move_type(is_rapid=False)
        # LinuxCNC's turn: n >= 0 counter-clockwise about the normal plus n full turns;
        # -1, -2 ... clockwise (one arc, plus -turn - 1 full turns): the other way round
        normal = (cmd.normal.x, cmd.normal.y, cmd.normal.z)
        turns = cmd.turn
        if turns < 0:
            normal = (-normal[0], -normal[1], -normal[2])
            turns = -turns - 1
        self.tp.add_circle(
            list(end),
            (cmd.center.x, cmd.center.y, cmd.center.z),
            normal,
            turns,
            cmd.vel,
            cmd.ini_maxvel,
            cmd.acc,
            motion_id=self.next_motion_id,
            term=self.term_cond,
            tolerance=self.tolerance,
            tag=cmd.tag.to_bytes(),
        )
        self._flush_synchronised_outputs()

    def _note_move_type(self, is_rapid: bool) -> None:
        """In CSS mode a feed after a rapid waits for the spindle's new speed (motion(9))."""
        is_css = any(s.css_factor for s in self.spindles)
        if is_css and self._is_last_move_rapid and not is_rapid:
            self.tp.wait_for_spindle_at_speed()
        self._is_last_move_rapid = is_rapid

    @handler(emc.EMC_TRAJ_PROBE)
    def _probe(self, cmd: emc.EMC_TRAJ_PROBE) -> None:
        end = cmd.pos.pose()
        problem = self._require_coord() or self._check_soft_limits(end, "Probe move")
        if problem:
            raise Refused(problem)
        # probe_type as in LinuxCNC: bit 1 set = away (G38.4/5), bit 0 = no error if no trip
        probe = ProbeType.AWAY if cmd.probe_type & 2 else ProbeType.TOWARD
        self.tp.add_probe(
            list(end),
            cmd.vel,
            cmd.ini_maxvel,
            cmd.acc,
            self.next_motion_id,
            probe,
            tag=cmd.tag.to_bytes(),
        )

    def _flush_synchronised_outputs(self) -> None:
        """M62/M64-style outputs queued with the next move take effect now (MOT-060/061)."""
        for index, value in self._pending_douts:
            self.digital_out[index] = value
        for index, value in self._pending_aouts:
            self.analog_out[index] = value
        self._pending_douts.clear()
        self._pending_aouts.clear()

    # ---------------------------------------------------------------- settings
    @handler(emc.EMC_TRAJ_SET_TERM_COND)
    def _set_term_cond(self, cmd: emc.EMC_TRAJ_SET_TERM_COND) -> None:
        if cmd.cond not in _TERM_CONDS:
            raise Refused(f"unknown termination condition {cmd.cond}")
        if cmd.tolerance < 0:
            raise Refused(f"negative blend tolerance {cmd.tolerance}")
        self.term_cond = _TERM_CONDS[emc.EMC_TRAJ_TERM_COND(cmd.cond)]
        self.tolerance = cmd.tolerance

    @handler(emc.EMC_TRAJ_SET_VELOCITY)
    def _set_velocity(self, cmd: emc.EMC_TRAJ_SET_VELOCITY) -> None:
        if not cmd.velocity >= 0:  # (0 at start-up, as LinuxCNC's task sends it)
            raise Refused(f"velocity must not be negative, got {cmd.velocity}")
        self.traj_vel = cmd.velocity

    @handler(emc.EMC_TRAJ_SET_ACCELERATION)
    def _set_acceleration(self, cmd: emc.EMC_TRAJ_SET_ACCELERATION) -> None:
        if not cmd.acceleration > 0:
            raise Refused(f"acceleration must be positive, got {cmd.acceleration}")
        self.traj_acc = cmd.acceleration

    @handler(emc.EMC_TRAJ_SET_MAX_VELOCITY)
    def _set_max_velocity(self, cmd: emc.EMC_TRAJ_SET_MAX_VELOCITY) -> None:
        if not cmd.velocity > 0:
            raise Refused(f"maximum velocity must be positive, got {cmd.velocity}")
        self.max_vel = cmd.velocity
        self._apply_traj_limits()

    @handler(emc.EMC_TRAJ_SET_MAX_ACCELERATION)
    def _set_max_acceleration(self, cmd: emc.EMC_TRAJ_SET_MAX_ACCELERATION) -> None:
        if not cmd.acceleration > 0:
            raise Refused(f"maximum acceleration must be positive, got {cmd.acceleration}")
        self.max_acc = cmd.acceleration
        self._apply_traj_limits()

    @handler(
        emc.EMC_AXIS_SET_MIN_POSITION_LIMIT,
        emc.EMC_AXIS_SET_MAX_POSITION_LIMIT,
        emc.EMC_AXIS_SET_MAX_VELOCITY,
        emc.EMC_AXIS_SET_MAX_ACCELERATION,
    )
    def _axis_settings(self, cmd: emc.NMLmsg) -> None:
        """[AXIS_L] limits sent by task at start-up (KIN-002)."""
        axis = cmd.axis
        if not 0 <= axis < NUM_AXES:
            raise Refused(f"axis {axis} does not exist (0..{NUM_AXES - 1} for X..W)")
        if isinstance(cmd, emc.EMC_AXIS_SET_MIN_POSITION_LIMIT):
            self.axis_min_limit[axis] = cmd.limit
        elif isinstance(cmd, emc.EMC_AXIS_SET_MAX_POSITION_LIMIT):
            self.axis_max_limit[axis] = cmd.limit
        elif isinstance(cmd, emc.EMC_AXIS_SET_MAX_VELOCITY):  # (hook: external offsets' share)
            self.axis_max_vel[axis] = self.eoffsets.planning_velocity(axis, cmd.vel)
        else:
            self.axis_max_acc[axis] = self.eoffsets.planning_acceleration(axis, cmd.acc)
        self._apply_traj_limits()
        self.teleop.set_limits(
            self.axis_max_vel, self.axis_max_acc, self.axis_min_limit, self.axis_max_limit
        )
        vel, acc = self.axis_max_vel[axis], self.axis_max_acc[axis]
        self.axis_planners[axis].set_limits(
            vel if math.isfinite(vel) else DEFAULT_JOINT_VEL,
            acc if math.isfinite(acc) else DEFAULT_JOINT_ACC,
            self.axis_min_limit[axis],
            self.axis_max_limit[axis],
        )

    def _apply_traj_limits(self) -> None:
        self.tp.set_limits(self.axis_max_vel, self.axis_max_acc, self.max_vel, self.max_acc)

    @handler(emc.EMC_TRAJ_SET_SCALE)
    def _set_scale(self, cmd: emc.EMC_TRAJ_SET_SCALE) -> None:
        self.tp.set_feed_scale(cmd.scale)
        for joint in self.joints:
            joint.planner.scale = max(cmd.scale, 0.0)

    @handler(emc.EMC_TRAJ_SET_RAPID_SCALE)
    def _set_rapid_scale(self, cmd: emc.EMC_TRAJ_SET_RAPID_SCALE) -> None:
        self.tp.set_rapid_scale(cmd.scale)

    @handler(emc.EMC_TRAJ_SET_MOTION_ID)
    def _set_motion_id(self, cmd: emc.EMC_TRAJ_SET_MOTION_ID) -> None:
        self.next_motion_id = cmd.id

    @handler(emc.EMC_TRAJ_PAUSE)
    def _pause(self, _cmd: emc.NMLmsg) -> None:
        self.tp.pause()

    @handler(emc.EMC_TRAJ_RESUME)
    def _resume(self, _cmd: emc.NMLmsg) -> None:
        self.tp.resume()

    @handler(emc.EMC_TRAJ_STEP)
    def _step(self, _cmd: emc.NMLmsg) -> None:
        self.tp.step_once()

    @handler(emc.EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG)
    def _clear_probe(self, _cmd: emc.NMLmsg) -> None:
        self.tp.clear_probe_flag()

    # ---------------------------------------------------------------- joints
    @handler(
        emc.EMC_JOINT_SET_MIN_POSITION_LIMIT,
        emc.EMC_JOINT_SET_MAX_POSITION_LIMIT,
        emc.EMC_JOINT_SET_MAX_VELOCITY,
        emc.EMC_JOINT_SET_FERROR,
        emc.EMC_JOINT_SET_MIN_FERROR,
        emc.EMC_JOINT_SET_BACKLASH,
        emc.EMC_JOINT_SET_MAX_ACCELERATION,
    )
    def _joint_limits(self, cmd: emc.NMLmsg) -> None:
        joint = self._joint(cmd.joint)
        planner = joint.planner
        max_vel, max_acc = planner.max_vel, planner.max_acc
        min_limit, max_limit = planner.min_limit, planner.max_limit
        if isinstance(cmd, emc.EMC_JOINT_SET_MIN_POSITION_LIMIT):
            min_limit = cmd.limit
        elif isinstance(cmd, emc.EMC_JOINT_SET_MAX_POSITION_LIMIT):
            max_limit = cmd.limit
        elif isinstance(cmd, emc.EMC_JOINT_SET_MAX_VELOCITY):
            max_vel = cmd.vel
        elif isinstance(cmd, emc.EMC_JOINT_SET_MAX_ACCELERATION):
            max_acc = cmd.acc
        elif isinstance(cmd, emc.EMC_JOINT_SET_FERROR):
            joint.set_ferror(cmd.ferror, joint.min_ferror_limit)
        elif isinstance(cmd, emc.EMC_JOINT_SET_MIN_FERROR):
            joint.set_ferror(joint.ferror_limit, cmd.ferror)
        elif isinstance(cmd, emc.EMC_JOINT_SET_BACKLASH):
            joint.set_backlash(cmd.backlash)
        planner.set_limits(max_vel, max_acc, min_limit, max_limit)

    @handler(emc.EMC_JOINT_SET_MOTOR_OFFSET)
    def _motor_offset(self, cmd: emc.EMC_JOINT_SET_MOTOR_OFFSET) -> None:
        """Where the joint is, from the saved position file: no motor moves (MOT-005)."""
        joint = self._joint(cmd.joint)
        if self.is_enabled or joint.is_homed:
            raise Refused("the motor offset can only be set while motion is off and unhomed")
        joint.motor_offset = check_finite("motor offset", cmd.offset)
        joint.update_feedback(joint.motor_pos_fb)
        joint.hold_position()
        joint.update_command(self.period_s)

    @handler(emc.EMC_JOINT_SET_HOMING_PARAMS)
    def _homing_params(self, cmd: emc.EMC_JOINT_SET_HOMING_PARAMS) -> None:
        """[JOINT_n] homing keys, sent by task at start-up (MOT-043)."""
        index = cmd.joint
        self._joint(index)
        if self.homing.is_homing:
            raise Refused("cannot change homing parameters while homing")
        sequence = None if cmd.home_sequence == emc.NO_HOME_SEQUENCE else cmd.home_sequence
        self.homing_configs[index] = HomingConfig(
            home=cmd.home,
            home_offset=cmd.offset,
            search_vel=cmd.search_vel,
            latch_vel=cmd.latch_vel,
            final_vel=cmd.home_final_vel,
            use_index=bool(cmd.use_index),
            ignore_limits=bool(cmd.ignore_limits),
            is_shared=bool(cmd.is_shared),
            sequence=sequence,
            absolute_encoder=cmd.absolute_encoder,
            volatile_home=bool(cmd.volatile_home),
            locking_indexer=bool(cmd.locking_indexer),
        )
        self.homing = self.homing_class(self.joints, self.homing_configs)

    @handler(emc.EMC_JOINT_HOME)
    def _home(self, cmd: emc.EMC_JOINT_HOME) -> None:
        """Home one joint, or all (-1) sequence by sequence (MOT-043, homing module)."""
        if self.mode != FREE:
            raise Refused("homing needs free (joint) mode")
        if not self.is_enabled:
            raise Refused("cannot home with motion disabled")
        try:
            if cmd.joint == -1:
                self.homing.home_all()
            else:
                self._joint(cmd.joint)
                self.homing.home_joint(cmd.joint)
        except HomingError as exc:
            raise Refused(str(exc)) from None

    @handler(emc.EMC_JOINT_UNHOME)
    def _unhome(self, cmd: emc.EMC_JOINT_UNHOME) -> None:
        if self._is_moving():
            raise Refused("cannot unhome while moving")
        problem = self.extra_joints.check_unhome(cmd.joint, self.is_enabled)  # (hook)
        if problem:
            raise Refused(problem)
        try:
            self.homing.unhome(cmd.joint)
        except HomingError as exc:
            raise Refused(str(exc)) from None

    @handler(emc.EMC_JOINT_OVERRIDE_LIMITS)
    def _override_limits(self, cmd: emc.EMC_JOINT_OVERRIDE_LIMITS) -> None:
        self.is_override_limits = cmd.joint >= 0

    # ---------------------------------------------------------------- outputs, spindle
    @handler(emc.EMC_MOTION_SET_DOUT)
    def _set_dout(self, cmd: emc.EMC_MOTION_SET_DOUT) -> None:
        if cmd.index >= len(self.digital_out):
            raise Refused(
                f"digital output {cmd.index} does not exist (num_dio {len(self.digital_out)})"
            )
        if cmd.now:
            self.digital_out[cmd.index] = bool(cmd.start)
        else:
            self._pending_douts.append((cmd.index, bool(cmd.start)))

    @handler(emc.EMC_MOTION_SET_AOUT)
    def _set_aout(self, cmd: emc.EMC_MOTION_SET_AOUT) -> None:
        if cmd.index >= len(self.analog_out):
            raise Refused(
                f"analog output {cmd.index} does not exist (num_aio {len(self.analog_out)})"
            )
        if cmd.now:
            self.analog_out[cmd.index] = cmd.start
        else:
            self._pending_aouts.append((cmd.index, cmd.start))

    # settings kept for status and later moves: tool offset, override enables
    @handler(emc.EMC_TRAJ_SET_OFFSET)
    def _tool_offset(self, cmd: emc.EMC_TRAJ_SET_OFFSET) -> None:
        self.tool_offset = cmd.offset.pose()

    @handler(emc.EMC_TRAJ_SET_FO_ENABLE)
    def _feed_override_enable(self, cmd: emc.EMC_TRAJ_SET_FO_ENABLE) -> None:
        self.is_feed_override_enabled = bool(cmd.mode)

    @handler(emc.EMC_TRAJ_SET_FH_ENABLE)
    def _feed_hold_enable(self, cmd: emc.EMC_TRAJ_SET_FH_ENABLE) -> None:
        self.is_feed_hold_enabled = bool(cmd.mode)

    @handler(emc.EMC_TRAJ_SET_SO_ENABLE)
    def _spindle_override_enable(self, cmd: emc.EMC_TRAJ_SET_SO_ENABLE) -> None:
        if not 0 <= cmd.spindle < len(self.spindles):
            raise Refused(f"spindle {cmd.spindle} does not exist")
        self.spindles[cmd.spindle].is_override_enabled = bool(cmd.mode)

    @handler(emc.EMC_MOTION_ADAPTIVE)
    def _adaptive_feed_enable(self, cmd: emc.EMC_MOTION_ADAPTIVE) -> None:
        self.is_adaptive_feed_enabled = bool(cmd.status)

    @handler(emc.EMC_TRAJ_RIGID_TAP)
    def _rigid_tap(self, cmd: emc.EMC_TRAJ_RIGID_TAP) -> None:
        """G33.1: in following the spindle, spindle reversed, out again (MOT-062)."""
        end = cmd.pos.pose()
        problem = self._require_coord() or self._check_soft_limits(end, "Rigid tap move")
        if problem:
            raise Refused(problem)
        self.tp.add_rigid_tap(
            list(end),
            cmd.ini_maxvel,
            cmd.acc,
            motion_id=self.next_motion_id,
            retract_scale=cmd.scale if cmd.scale > 0 else 1.0,
            tag=cmd.tag.to_bytes(),
        )
        self._is_last_move_rapid = False

    # ================================================================ servo period
    def update(self, inputs: Inputs) -> None:
        """One servo period: feedback, checks, homing, planning, kinematics (MOT-001..016)."""
        dt = self.period_s
        for index, joint in enumerate(self.joints):
            joint.update_feedback(inputs.motor_pos_fb[index])
            joint.is_on_pos_limit = bool(inputs.pos_limit[index])
            joint.is_on_neg_limit = bool(inputs.neg_limit[index])
            if inputs.home_switch:
                joint.is_home_switch_on = bool(inputs.home_switch[index])
            if inputs.index_enable and joint.is_index_enabled:
                joint.is_index_enabled = bool(inputs.index_enable[index])
        self.digital_in = list(inputs.digital_in) or self.digital_in
        self.analog_in = list(inputs.analog_in) or self.analog_in
        if self.is_enabled and not inputs.enable:
            self.fault("motion disabled by the motion.enable pin")
        self._check_hard_limits_and_faults(inputs)
        self._read_spindles(inputs.spindles)
        self._jog_wheels(inputs)
        # (hook) external offsets: the pins' requests (motion/eoffsets.py)
        if self.eoffsets.planners:
            can_offset = self.is_enabled and all(j.is_homed for j in self.joints)
            self.eoffsets.plan(inputs.eoffsets, can_offset)
        if self.mode == COORD:
            self.tp.probe_input = inputs.probe
            if self.indexers.axis_joint:  # (hook) indexing moves wait for the unlock
                is_held = self.indexers.hold(self.tp.current_move)
                self.tp.is_start_held = self.tp.is_start_held or is_held
            position = self.tp.step()
            error = self.tp.take_error()
            if error:
                self.errors.append(error)
            pose = Pose(*position.tolist())
            if self.eoffsets.planners:  # (hook) external offsets on top
                pose = self.eoffsets.add(pose, dt)
            self._set_joints_from_pose(pose)
        elif self.mode == TELEOP:
            self._teleop_step(dt)
        else:
            self.homing.step(dt)
            error = self.homing.take_error()
            if error:
                self.errors.append(error)
            for joint in self.joints:
                joint.pos_cmd = joint.planner.step(dt)
            # (a joint homed in place is homed by the command already: seen here)
            is_all_homed = all(j.is_homed for j in self.joints)
            if is_all_homed and not self.was_all_homed:
                self.is_teleop_after_homing = True
            self.was_all_homed = is_all_homed
            if self.is_teleop_after_homing and not self._is_moving():
                self._set_mode(emc.EMC_TRAJ_SET_MODE(mode=TELEOP))
        if self.extra_joints.count:  # (hook) homed extra joints follow posthome-cmd
            self.extra_joints.posthome_cmd[:] = inputs.posthome_cmd
            self.extra_joints.step(dt)
        for joint in self.joints:
            joint.update_command(dt)
        if self.mode == FREE:
            self.carte_pos_cmd = self._forward([j.pos_cmd for j in self.joints])
        self.carte_pos_fb = self._forward([j.pos_fb for j in self.joints])
        self._check_following_error()
        self._drive_spindles()

    # ---------------------------------------------------------------- jog wheels
    # ---------------------------------------------------------------- spindle, per period
    def _set_joints_from_pose(self, pose: Pose) -> None:
        try:
            targets = self.kins.inverse(pose)
        except KinematicsError as exc:
            self.fault(f"inverse kinematics failed: {exc}; motion stopped")
            return
        for joint, target in zip(self.joints, targets, strict=False):
            joint.pos_cmd = target
        self.carte_pos_cmd = pose

    def _forward(self, joints: list[float]) -> Pose:
        try:
            return self.kins.forward(joints)
        except KinematicsError:
            return self.carte_pos_cmd  # a singularity: keep the last pose (KIN-012)

    def _check_hard_limits_and_faults(self, inputs: Inputs) -> None:
        if not self.is_enabled:
            return
        for index, joint in enumerate(self.joints):
            if inputs.amp_fault[index] and not self.is_faulted[index]:
                self.is_faulted[index] = True
                self.fault(f"joint {index} amplifier fault")
                return
            if joint.is_on_limit_switch() and not (self.is_override_limits or joint.is_homing):
                # LinuxCNC's words exactly: UIs and scripts match them (the side is
                # in the status, joint[n]'s min/max_hard_limit)
                self.fault(f"joint {index} on limit switch error")
                return

    def _check_following_error(self) -> None:
        """MIN_FERROR at rest rising to FERROR at max velocity (MOT-074); feedback that is
        not a number is a fault too."""
        if not self.is_enabled:
            return
        for index, joint in enumerate(self.joints):
            if not math.isfinite(joint.pos_fb):  # (NaN passes any limit comparison)
                self.fault(
                    f"joint {index} position feedback is {joint.motor_pos_fb} "
                    f"(joint.{index}.motor-pos-fb)"
                )
                return
            if joint.is_following_error() and not self.extra_joints.is_following(index):
                self.fault(f"joint {index} following error")
                return

    # ================================================================ status
    @property
    def is_in_position(self) -> bool:
        return not self._is_moving()

    @property
    def current_vel(self) -> float:
        """Path speed: the planner's in coord mode, the teleop vector's length in teleop
        mode (XYZ, else the other axes), 0 in free mode (as LinuxCNC's current_vel)."""
        if self.mode == COORD:
            return self.tp.vel
        if self.mode == TELEOP:
            speeds = (self.teleop.vel + [p.vel for p in self.axis_planners]).tolist()
            xyz = math.hypot(*speeds[:3])
            return xyz or math.hypot(*speeds[3:])
        return 0.0


# What ends a program whose move motion refused: task's abort, or a fresh start (motion
# turned off or on, another mode).
_ENDS_A_REFUSED_PROGRAM = {
    emc.EMC_TRAJ_ABORT,
    emc.EMC_MOTION_ABORT,
    emc.EMC_TRAJ_DISABLE,
    emc.EMC_TRAJ_ENABLE,
    emc.EMC_TRAJ_SET_MODE,
}

# (the parts' names, for the modules that take them from here)
__all__ = [
    "COORD",
    "FREE",
    "QUEUE_FULL_MARGIN",
    "TELEOP",
    "Inputs",
    "Joint",
    "MotionController",
    "OrientState",
    "Spindle",
    "SpindleInputs",
    "WheelInputs",
]
