"""``loadrt motmod``: the motion controller as a realtime HAL module (MOT-008..018, ARCH-007).

    loadrt trivkins coordinates=XYZ
    loadrt motmod servo_period_nsec=1000000 num_joints=3 [base_period_nsec=N num_spindles=1
                  num_dio=4 num_aio=4]     # creates servo-thread (and base-thread), as LinuxCNC
    addf motion-command-handler servo-thread
    addf motion-controller servo-thread

It exports LinuxCNC's pins (``motion.*``, ``joint.N.*``, ``axis.L.*``, ``spindle.N.*``) and
two functions. ``motion-command-handler`` takes the commands task queued on ``motCommand``
and answers each on ``motStatus`` (echoed serial number, DONE or ERROR; refusals also go to
``emcError`` as operator errors). ``motion-controller`` runs one servo period of
``MotionController`` and publishes EMC_MOTION_STAT.

Nothing here may block the servo thread: the NML connections use the ``motion`` P lines
of the NML file ([EMC]NML_FILE via ``$CNC_NML_FILE``, default configs/common/cnc.nml),
whose timeout 0 makes a busy buffer fail at once; a command then waits for the next period
and an error message stays pending until it can be written.
"""

from __future__ import annotations

import contextlib
import os
import time
from typing import Any

from hal.api import RtComponent, pin
from hal.core import HalError
from motion.controller import (
    COORD,
    TELEOP,
    EoffsetInputs,
    Inputs,
    MotionController,
    SpindleInputs,
    WheelInputs,
)
from motion.homing import load_homing
from motion.kinematics import Kinematics, KinematicsError, fit_joints
from motion.modules import ModuleInterfaceError
from motion.safety import DEFAULT_HEARTBEAT_TIMEOUT_S, MotionSafety
from motion.tp import load_planner
from nml import emc
from nml.axes import AXIS_LETTERS
from nml.channels import EMC_ERROR, MOTION_COMMAND, MOTION_STATUS, Nml, load_config
from nml.commands import InternalError, Refused, carry_out, echo, internal_error
from nml.errors import NmlError, NmlTimeoutError
from nml.pose import AXIS_NAMES

NML_PROCESS = "motion"
# The command handler takes commands while the next one, costing as much as the longest
# this period so far, would end within a quarter of the period (always one at least, at
# most MAX_COMMANDS_PER_PERIOD), and leaves the rest queued for the next periods: a move
# costs ~50-150 µs to queue, and while task fills the planner's queue at the start of a
# program, 20 moves in one period overran a 1 ms servo period.
COMMAND_PERIOD_FRACTION = 4
MAX_COMMANDS_PER_PERIOD = 20


class MotionPins(RtComponent):
    enable = pin("bit in", default=1)
    probe_input = pin("bit in")
    motion_enabled = pin("bit out")
    in_position = pin("bit out")
    is_all_homed = pin("bit out")  # every joint is homed (LinuxCNC 2.9's motion.is-all-homed)
    coord_mode = pin("bit out")
    teleop_mode = pin("bit out")
    on_soft_limit = pin("bit out")
    program_line = pin("s32 out")
    jog_inhibit = pin("bit in")
    jog_stop = pin("bit in")
    jog_stop_immediate = pin("bit in")
    jog_is_active = pin("bit out")
    current_vel = pin("float out")
    distance_to_go = pin("float out")
    digital_out = pin("bit out", "digital-out-{:02d}", count="num_dio")
    digital_in = pin("bit in", "digital-in-{:02d}", count="num_dio")
    analog_out = pin("float out", "analog-out-{:02d}", count="num_aio")
    analog_in = pin("float in", "analog-in-{:02d}", count="num_aio")
    eoffset_active = pin("bit out")  # an external offset is applied (motion/eoffsets.py)
    eoffset_limited = pin("bit out")  # ... and held at a soft limit

    def setup(self, num_dio: int = 4, num_aio: int = 4) -> None:
        pass


class IniSettings:
    """What motion reads of the machine's INI file itself: task sends it no message
    for these (LinuxCNC's task does, in fields our messages do not have)."""

    def __init__(self) -> None:
        self.heartbeat_timeout = DEFAULT_HEARTBEAT_TIMEOUT_S
        self.eoffset_ratios: dict[int, float] = {}  # [AXIS_L]OFFSET_AV_RATIO
        # the blending the canon starts with (LinuxCNC's INIT_CANON: G64 within 0.001
        # inch), in machine units ([TRAJ]LINEAR_UNITS); task starts in agreement with it
        # rather than sending it (LinuxCNC's first abort drops it when it comes early)
        self.blend_tolerance: float | None = None
        self.locking_joints: dict[int, int] = {}  # [AXIS_L]LOCKING_INDEXER_JOINT


class SwitchPins(RtComponent):
    """Made when the kinematics are switchable, as in LinuxCNC (M428-M430 set it)."""

    switchkins_type = pin("float in")


class JointPins(RtComponent):
    motor_pos_cmd = pin("float out")
    motor_pos_fb = pin("float in")
    motor_offset = pin("float out")
    pos_cmd = pin("float out")
    pos_fb = pin("float out")
    vel_cmd = pin("float out")
    f_error = pin("float out")
    f_errored = pin("bit out")
    amp_enable_out = pin("bit out")
    amp_fault_in = pin("bit in")
    home_sw_in = pin("bit in")
    homing = pin("bit out")
    homed = pin("bit out")
    in_position = pin("bit out")
    pos_lim_sw_in = pin("bit in")
    neg_lim_sw_in = pin("bit in")
    index_enable = pin("bit io")
    # MPG wheel (free mode)
    jog_counts = pin("s32 in")
    jog_enable = pin("bit in")
    jog_scale = pin("float in")
    jog_vel_mode = pin("bit in")
    jog_accel_fraction = pin("float in", default=1.0)


class UnlockPins(RtComponent):
    """A locking indexer's pins (bit N of ``unlock_joints_mask``, motion/indexer.py)."""

    unlock = pin("bit out")
    is_unlocked = pin("bit in")


class PosthomePins(RtComponent):
    """An extra joint's command once homed (``num_extrajoints``, motion/extrajoints.py)."""

    posthome_cmd = pin("float in")


class AxisPins(RtComponent):
    pos_cmd = pin("float out")
    teleop_pos_cmd = pin("float out")
    # external offsets (motion/eoffsets.py)
    eoffset_enable = pin("bit in")
    eoffset_clear = pin("bit in")
    eoffset_counts = pin("s32 in")
    eoffset_scale = pin("float in")
    eoffset = pin("float out")
    eoffset_request = pin("float out")
    # MPG wheel (teleop mode)
    jog_counts = pin("s32 in")
    jog_enable = pin("bit in")
    jog_scale = pin("float in")
    jog_vel_mode = pin("bit in")
    jog_accel_fraction = pin("float in", default=1.0)


class SpindlePins(RtComponent):
    """``spindle.N.*`` as motion(9) lists them."""

    speed_out = pin("float out")  # rpm, negative in reverse
    speed_out_rps = pin("float out")
    speed_out_abs = pin("float out")
    speed_out_rps_abs = pin("float out")
    speed_cmd_rps = pin("float out")  # the programmed speed, before override and CSS
    on = pin("bit out")
    forward = pin("bit out")
    reverse = pin("bit out")
    brake = pin("bit out")
    at_speed = pin("bit in", default=1)
    speed_in = pin("float in")  # revolutions per second (G95, G96)
    revs = pin("float in")  # encoder position in revolutions (G33, G33.1)
    index_enable = pin("bit io")  # set by motion, cleared by the encoder at the index
    inhibit = pin("bit in")
    amp_fault_in = pin("bit in")
    orient = pin("bit out")  # M19
    orient_angle = pin("float out")
    orient_mode = pin("bit out")
    orient_fault = pin("s32 in")
    is_oriented = pin("bit in")
    locked = pin("bit out")


class Motmod:
    """The pins, the controller and the NML connections of one loaded motmod."""

    def __init__(self, host: Any, comp: str, args: dict[str, str]) -> None:
        options = _options(args)
        kins = _kinematics(host, options["num_joints"] - options["num_extrajoints"])
        period_s = options["servo_period_nsec"] / 1e9
        planner, homing = _modules(args)
        try:
            self.controller = MotionController(
                kins,
                options["num_joints"],
                period_s,
                num_spindles=options["num_spindles"],
                num_dio=options["num_dio"],
                num_aio=options["num_aio"],
                planner_factory=planner,
                homing_class=homing,
                num_extrajoints=options["num_extrajoints"],
                unlock_joints_mask=options["unlock_joints_mask"],
            )
        except ValueError as exc:
            raise HalError(f"motmod: {exc}") from None
        settings = _ini_settings()
        if settings.blend_tolerance is not None:
            self.controller.tolerance = settings.blend_tolerance
        try:
            for axis, ratio in settings.eoffset_ratios.items():
                self.controller.eoffsets.set_ratio(axis, ratio)
        except ValueError as exc:
            raise HalError(f"motmod: {exc}") from None
        for axis, joint in settings.locking_joints.items():
            problem = self.controller.indexers.set_axis_joint(axis, joint)
            if problem:
                raise HalError(f"motmod: [AXIS_{AXIS_LETTERS[axis]}]: {problem}")
        hal = host.hal
        io = {"num_dio": options["num_dio"], "num_aio": options["num_aio"]}
        self.motion = MotionPins.create(hal, comp, "motion", io)
        self.joints = [
            JointPins.create(hal, comp, f"joint.{i}") for i in range(options["num_joints"])
        ]
        mask = options["unlock_joints_mask"]
        self.unlock_pins = {
            i: UnlockPins.create(hal, comp, f"joint.{i}")
            for i in range(options["num_joints"])
            if mask >> i & 1
        }
        extra = self.controller.extra_joints
        self.posthome_pins = [
            PosthomePins.create(hal, comp, f"joint.{i}")
            for i in range(extra.first, extra.first + extra.count)
        ]
        letters = [AXIS_NAMES[i] for i in range(9) if getattr(kins, "axis_mask", 0b111) >> i & 1]
        self.axes = {AXIS_NAMES.index(c): AxisPins.create(hal, comp, f"axis.{c}") for c in letters}
        # LinuxCNC 2.9 makes the pins of all nine axes (HAL files connect axis.c.* on an
        # XYZ machine); those of axes the kinematics lack are made but never serviced
        self.unused_axes = [
            AxisPins.create(hal, comp, f"axis.{c}") for c in AXIS_NAMES if c not in letters
        ]
        self.spindles = [
            SpindlePins.create(hal, comp, f"spindle.{i}") for i in range(options["num_spindles"])
        ]
        is_switchable = getattr(kins, "is_switchable", False)
        self.switch_pins = SwitchPins.create(hal, comp, "motion") if is_switchable else None
        self.kinstype = 0
        try:
            config = load_config(os.environ.get("CNC_NML_FILE") or None)
            self.nml = Nml(config, NML_PROCESS, [MOTION_COMMAND, MOTION_STATUS, EMC_ERROR])
        except NmlError as exc:
            raise HalError(f"motmod: cannot connect to the NML buffers: {exc}") from None
        self.status = emc.EMC_MOTION_STAT()
        self._status_bytes = self.status.byte_view()
        self._published = b""  # the status record as last written (see _publish)
        self.status.numExtraJoints = options["num_extrajoints"]
        self._eoffsets_written: tuple = ()
        self.pending_errors: list[str] = []
        # the safety board: E-stop/abort requests, heartbeats, jog leases (motion/safety.py)
        self.safety = MotionSafety.open(self.controller, period_s, settings.heartbeat_timeout)
        self._is_period_error_said = False  # (an internal error, since motion was last on)
        self._is_failure_said = False  # (a fault outside the controller, see _fail)
        self.hal = hal
        # what _write_pins last wrote of the values that seldom change
        self._written_generation = -1
        self._joint_written: list[tuple] = [()] * len(self.joints)
        self._motion_written: tuple = ()
        self._digital_out_written: list[bool] = []
        self._analog_out_written: list[float] = []
        self._spindle_written: list[tuple] = [()] * len(self.spindles)
        count = len(self.joints)
        self.inputs = Inputs(
            motor_pos_fb=[0.0] * count,
            pos_limit=[False] * count,
            neg_limit=[False] * count,
            amp_fault=[False] * count,
            home_switch=[False] * count,
            index_enable=[False] * count,
            spindles=[SpindleInputs() for _ in self.spindles],
            joint_wheels=[WheelInputs() for _ in self.joints],
            axis_wheels={index: WheelInputs() for index in self.axes},
            eoffsets={
                axis: EoffsetInputs() for axis in self.controller.eoffsets.axes if axis in self.axes
            },
            posthome_cmd=[0.0] * len(self.posthome_pins),
        )
        host.add_function(comp, "motion-command-handler", self.command_handler)
        host.add_function(comp, "motion-controller", self.controller_period)
        # As LinuxCNC's motmod: the threads the HAL files addf to (base first, fastest).
        if options["base_period_nsec"]:
            host.new_thread("base-thread", options["base_period_nsec"], creator=comp)
        host.new_thread("servo-thread", options["servo_period_nsec"], creator=comp)

    # ------------------------------------------------------------------ functions
    def command_handler(self, period: int) -> None:
        """Carry out the commands queued since the last period (MOT-009), for about a
        quarter of the period at most (``period`` in ns). Never raises: a fault here
        stops the machine (_fail) rather than leaving the host to disable the function."""
        try:
            self._handle_commands(period)
        except Exception as exc:
            self._fail("in the command handler", exc)

    def _handle_commands(self, period: int) -> None:
        commands = self.nml[MOTION_COMMAND]
        if not commands.has_new_data():  # most periods: a look at the queue's count
            return
        clock = time.monotonic_ns
        started = clock()
        give_up_at = started + period // COMMAND_PERIOD_FRACTION
        longest = 0
        for _ in range(MAX_COMMANDS_PER_PERIOD):
            if started + longest > give_up_at:
                break
            try:
                cmd = commands.read()
            except NmlTimeoutError:
                break  # busy this instant: next period
            except NmlError as exc:  # a command may have been lost: stop the machine
                self._fail("reading its commands", exc)
                continue
            if cmd is None:
                break
            answer = carry_out("motion", self._carry_out, cmd)
            echo(self.status, cmd, answer.status)
            if isinstance(answer.refusal, InternalError):  # a bug: motion off, said once
                self.controller.fault(f"{answer.refusal}; motion is off")
            elif answer.reason:
                self.pending_errors.extend(answer.reason.splitlines())
            ended = clock()
            longest = max(longest, ended - started)
            started = ended

    def _carry_out(self, cmd: emc.NMLmsg) -> None:
        """The controller's answer as a refusal ("": quietly, see MotionController.handle)."""
        problem = self.controller.handle(cmd)
        if problem is not None:
            raise Refused(problem, is_quiet=not problem)

    def controller_period(self, period: int) -> None:
        """One servo period: safety board, pins in, controller, pins out, status out
        (MOT-010..016). Never raises (see command_handler)."""
        try:
            self._run_period()
        except Exception as exc:
            self._fail("in a servo period", exc)

    def _run_period(self) -> None:
        safety = self.safety
        if safety is not None:
            safety.period()
        if self.switch_pins is not None:
            self._switch_kinematics()
        inputs = self.inputs
        for index, pins in enumerate(self.joints):
            inputs.motor_pos_fb[index] = pins.motor_pos_fb
            inputs.pos_limit[index] = pins.pos_lim_sw_in
            inputs.neg_limit[index] = pins.neg_lim_sw_in
            inputs.amp_fault[index] = pins.amp_fault_in
            inputs.home_switch[index] = pins.home_sw_in
            inputs.index_enable[index] = pins.index_enable
            _read_wheel(pins, inputs.joint_wheels[index])
        for index, pins in self.axes.items():
            _read_wheel(pins, inputs.axis_wheels[index])
        for index, eoffset in inputs.eoffsets.items():
            pins = self.axes[index]
            eoffset.is_enabled, eoffset.is_clear = pins.eoffset_enable, pins.eoffset_clear
            eoffset.counts, eoffset.scale = pins.eoffset_counts, pins.eoffset_scale
        for k, pins in enumerate(self.posthome_pins):
            inputs.posthome_cmd[k] = pins.posthome_cmd
        joints = self.controller.joints
        for index, pins in self.unlock_pins.items():
            joints[index].is_unlocked = pins.is_unlocked
        motion_pins = self.motion
        inputs.probe = motion_pins.probe_input
        inputs.enable = motion_pins.enable
        inputs.is_jog_inhibited = motion_pins.jog_inhibit
        inputs.is_jog_stop = motion_pins.jog_stop
        inputs.is_jog_stop_immediate = motion_pins.jog_stop_immediate
        inputs.digital_in = list(motion_pins.digital_in)
        inputs.analog_in = list(motion_pins.analog_in)
        for pins, spindle, state in zip(
            self.spindles, inputs.spindles, self.controller.spindles, strict=True
        ):
            spindle.revs, spindle.speed_in = pins.revs, pins.speed_in
            spindle.is_at_speed, spindle.index_enable = pins.at_speed, pins.index_enable
            spindle.is_inhibited, spindle.is_amp_fault = pins.inhibit, pins.amp_fault_in
            if state.is_orienting:  # (only an orient cycle reads these)
                spindle.is_oriented, spindle.orient_fault = pins.is_oriented, pins.orient_fault
        controller = self.controller
        try:
            controller.update(inputs)
        except Exception as exc:  # said once while it recurs with motion off
            if controller.is_enabled or not self._is_period_error_said:
                self._internal_error("in a servo period", exc)
            self._is_period_error_said = True
        else:
            if controller.is_enabled:
                self._is_period_error_said = False
                self._is_failure_said = False
        self._write_pins()
        self.pending_errors.extend(controller.errors)
        controller.errors.clear()
        if safety is not None and safety.messages:
            self.pending_errors.extend(safety.messages)
            safety.messages.clear()
        controller.fill_status(self.status)
        self._publish()

    def _switch_kinematics(self) -> None:
        """As LinuxCNC: when ``motion.switchkins-type`` changes, switch the kinematics and
        take the world position from the joints' commands through the new ones."""
        wanted = int(self.switch_pins.switchkins_type)
        if wanted == self.kinstype:
            return
        self.kinstype = wanted
        controller = self.controller
        joints = [joint.pos_cmd for joint in controller.joints]
        try:
            controller.kins.switch(wanted)
            pose = controller.kins.forward(joints)
        except KinematicsError as exc:
            controller.fault(f"motion: kinematicsSwitch({wanted}) failed: {exc}")
            return
        controller.carte_pos_cmd = pose
        controller.tp.set_position(list(pose))

    def _fail(self, where: str, exc: Exception) -> None:
        """A fault in one of motion's functions (a bug, a corrupt buffer): motion off, the
        machine to E-stop, the operator told; said once until motion is turned on again.
        The function keeps running: a disabled one would leave the machine unsupervised."""
        if self._is_failure_said:
            return
        self._is_failure_said = True
        text = f"motion: fault {where}: {type(exc).__name__}: {exc}; E-stop"
        with contextlib.suppress(Exception):
            self.controller.fault(text)
        if self.safety is not None:
            with contextlib.suppress(Exception):
                self.safety.board.request_estop(text)
        with contextlib.suppress(Exception):
            self._write_pins()
            self._publish()

    def _internal_error(self, where: str, exc: Exception) -> None:
        """What an exception inside the controller does: motion off (everything stops where
        it is, the queue is emptied) and an error saying so. The host would otherwise
        disable the function that raised it: motion would stop listening, or stop running,
        and nobody would be told."""
        self.controller.fault(f"{internal_error('motion', where, exc)}; motion is off")

    def _write_pins(self) -> None:
        """Pins out. Values that change while moving are written every period; the rest
        (enable, homing, spindle, I/O) only when they change, or when the HAL was edited
        (a signal linked since may not hold the pin's value yet)."""
        controller = self.controller
        generation = self.hal.generation
        is_all = generation != self._written_generation
        self._written_generation = generation
        is_enabled = controller.is_enabled
        for index, (joint, pins) in enumerate(zip(controller.joints, self.joints, strict=True)):
            pins.pos_cmd = joint.pos_cmd
            pins.motor_pos_cmd = joint.motor_pos_cmd
            pins.pos_fb = joint.pos_fb
            pins.vel_cmd = joint.vel_cmd
            pins.f_error = joint.ferror
            pins.index_enable = joint.is_index_enabled  # (an io pin: the encoder clears it)
            state = (
                is_enabled,
                joint.is_homed,
                joint.is_homing,
                joint.planner.is_active,
                joint.motor_offset,
            )
            if is_all or state != self._joint_written[index]:
                self._joint_written[index] = state
                pins.amp_enable_out = is_enabled
                pins.homed = joint.is_homed
                pins.homing = joint.is_homing
                pins.in_position = not joint.planner.is_active
                pins.motor_offset = joint.motor_offset
        pose = controller.carte_pos_cmd.as_tuple()
        for index, pins in self.axes.items():
            pins.pos_cmd = pose[index]
        for index, pins in self.unlock_pins.items():
            pins.unlock = controller.joints[index].is_unlock_requested
        if self.inputs.eoffsets:
            self._write_eoffsets(is_all)
        tp = controller.tp
        motion = self.motion
        motion.program_line = tp.motion_id
        motion.current_vel = controller.current_vel
        motion.distance_to_go = tp.distance_to_go if controller.mode == COORD else 0.0
        is_in_position = controller.is_in_position
        mode, is_jogging = controller.mode, controller.is_jogging
        is_all_homed = all(joint.is_homed for joint in controller.joints)
        state = (is_enabled, is_in_position, mode, is_jogging, is_all_homed)
        if is_all or state != self._motion_written:
            self._motion_written = state
            motion.motion_enabled = is_enabled
            motion.in_position = is_in_position
            motion.is_all_homed = is_all_homed
            motion.coord_mode = mode == COORD
            motion.teleop_mode = mode == TELEOP
            motion.jog_is_active = is_jogging
        if is_all or controller.digital_out != self._digital_out_written:
            self._digital_out_written = list(controller.digital_out)
            for index, value in enumerate(controller.digital_out):
                motion.digital_out[index] = value
        if is_all or controller.analog_out != self._analog_out_written:
            self._analog_out_written = list(controller.analog_out)
            for index, value in enumerate(controller.analog_out):
                motion.analog_out[index] = value
        spindles = zip(controller.spindles, self.spindles, strict=True)
        for index, (spindle, pins) in enumerate(spindles):
            pins.index_enable = spindle.is_index_enabled  # (an io pin: the encoder clears it)
            speed = spindle.speed_out
            state = (
                speed,
                spindle.speed,
                spindle.is_brake_on,
                spindle.is_orienting,
                spindle.orient_angle,
                spindle.orient_mode,
                spindle.is_locked,
            )
            if not is_all and state == self._spindle_written[index]:
                continue
            self._spindle_written[index] = state
            pins.speed_out = speed
            pins.speed_out_rps = speed / 60.0
            pins.speed_out_abs = abs(speed)
            pins.speed_out_rps_abs = abs(speed) / 60.0
            pins.speed_cmd_rps = spindle.speed / 60.0
            pins.on = speed != 0
            pins.forward = speed > 0
            pins.reverse = speed < 0
            pins.brake = spindle.is_brake_on
            pins.orient = spindle.is_orienting
            pins.orient_angle = spindle.orient_angle
            pins.orient_mode = bool(spindle.orient_mode)
            pins.locked = spindle.is_locked

    def _write_eoffsets(self, is_all: bool) -> None:
        """The external offsets' pins and status (axis.L.pos-cmd without the offset, as
        LinuxCNC), written when they change."""
        eoffsets = self.controller.eoffsets
        offsets = eoffsets.offsets()
        pose = self.controller.carte_pos_cmd.as_tuple()
        for index in self.inputs.eoffsets:
            self.axes[index].pos_cmd = pose[index] - offsets[index]
        state = (*offsets, *eoffsets.request, eoffsets.is_active, eoffsets.is_limited)
        if not is_all and state == self._eoffsets_written:
            return
        self._eoffsets_written = state
        for index in self.inputs.eoffsets:
            pins = self.axes[index]
            pins.eoffset, pins.eoffset_request = offsets[index], eoffsets.request[index]
        self.motion.eoffset_active = eoffsets.is_active
        self.motion.eoffset_limited = eoffsets.is_limited
        status = self.status
        status.external_offsets_applied = eoffsets.is_active
        status.eoffset_pose.set(offsets)
        self.pending_errors.extend(eoffsets.notes)
        eoffsets.notes.clear()

    def _publish(self) -> None:
        # written only when it changed: a machine at rest writes nothing, so task (which
        # reads it when its change counter moves) and the UIs stay idle too
        record = self._status_bytes.tobytes()
        if record != self._published:
            with contextlib.suppress(NmlTimeoutError):  # busy this instant: next period
                self.nml[MOTION_STATUS].write(self.status)
                self._published = record
        errors = self.nml[EMC_ERROR]
        while self.pending_errors:
            try:
                message = emc.EMC_OPERATOR_ERROR(error=emc.fit_text(self.pending_errors[0]))
                errors.write(message, is_oldest_dropped=True)
            except NmlTimeoutError:
                return
            self.pending_errors.pop(0)


def _ini_settings() -> IniSettings:
    """What motion reads of the machine's INI ($CNC_INI_FILE, from the launcher, which
    checked it against cnc/inischema.py): [EMCMOT]HEARTBEAT_TIMEOUT, and per axis
    OFFSET_AV_RATIO and LOCKING_INDEXER_JOINT, the blend tolerance from [TRAJ]LINEAR_UNITS.
    Defaults without an INI file."""
    settings = IniSettings()
    path = os.environ.get("CNC_INI_FILE")
    if not path:
        return settings
    from cnc.ini import IniError, IniFile
    from cnc.inischema import DEFAULT_BLEND_TOLERANCE_MM, LINEAR_UNITS, MM_PER_INCH

    try:
        ini = IniFile.load(path)
        value = ini.get_float("EMCMOT", "HEARTBEAT_TIMEOUT")
        if value is not None:
            settings.heartbeat_timeout = value
        for axis, letter in enumerate(AXIS_NAMES):
            section = f"AXIS_{letter.upper()}"
            ratio = ini.get_float(section, "OFFSET_AV_RATIO")
            if ratio:
                settings.eoffset_ratios[axis] = ratio
            joint = ini.get_int(section, "LOCKING_INDEXER_JOINT")
            if joint is not None and joint >= 0:
                settings.locking_joints[axis] = joint
        units = LINEAR_UNITS.parse(ini.find("TRAJ", "LINEAR_UNITS") or "")
        mm_per_unit = MM_PER_INCH if units == "inch" else 1.0
        settings.blend_tolerance = DEFAULT_BLEND_TOLERANCE_MM / mm_per_unit
    except (IniError, OSError, ValueError):
        return settings
    return settings


def _read_wheel(pins: JointPins | AxisPins, wheel: WheelInputs) -> None:
    """The wheel's pins; the rest only when the counts changed (all the controller uses
    then), to keep the servo period short."""
    counts = pins.jog_counts
    if counts != wheel.counts:
        wheel.is_enabled, wheel.scale = pins.jog_enable, pins.jog_scale
        wheel.is_vel_mode, wheel.accel_fraction = pins.jog_vel_mode, pins.jog_accel_fraction
    wheel.counts = counts


def rtapi_app_main(host: Any, comp: str, args: dict[str, str]) -> None:
    host.motmod = Motmod(host, comp, args)


_INT_OPTIONS = {
    "base_period_nsec": 0,
    "servo_period_nsec": 1_000_000,
    "traj_period_nsec": 0,
    "num_joints": 3,
    "num_spindles": 1,
    "num_dio": 4,
    "num_aio": 4,
    "num_extrajoints": 0,
    "unlock_joints_mask": 0,
}
_LIMITS = {
    "num_joints": (1, emc.EMCMOT_MAX_JOINTS),
    "num_spindles": (1, emc.EMCMOT_MAX_SPINDLES),
    "num_dio": (0, emc.EMCMOT_MAX_DIO),
    "num_aio": (0, emc.EMCMOT_MAX_AIO),
}


# Replaceable modules (ARCH-007/008): motmod's tp=/hm= arguments, else what the launcher
# took from [TRAJ]TPMOD / [EMCMOT]HOMEMOD; LinuxCNC's default names mean ours.
_MODULE_OPTIONS = {
    "tp": ("CNC_TPMOD", "tpmod", "planner"),
    "hm": ("CNC_HOMEMOD", "homemod", "homing"),
}


def _modules(args: dict[str, str]) -> tuple[type, type]:
    """The trajectory planner and homing classes; an incomplete module is refused with
    the list of what it lacks."""
    names = {}
    for key, (env, linuxcnc_default, ours) in _MODULE_OPTIONS.items():
        name = args.get(key) or os.environ.get(env) or ours
        names[key] = ours if name == linuxcnc_default else name
    try:
        return load_planner(names["tp"]), load_homing(names["hm"])
    except ModuleInterfaceError as exc:
        raise HalError(f"motmod: {exc}") from None


def _options(args: dict[str, str]) -> dict[str, int]:
    unknown = set(args) - set(_INT_OPTIONS) - set(_MODULE_OPTIONS)
    if unknown:
        raise HalError(f"motmod: unknown argument '{sorted(unknown)[0]}'")
    options = dict(_INT_OPTIONS)
    for key, text in args.items():
        if key in _INT_OPTIONS:  # (tp= and hm= are module names, see _modules)
            try:
                options[key] = int(text, 0)
            except ValueError:
                raise HalError(f"motmod: {key}={text} is not an integer") from None
    for key, (low, high) in _LIMITS.items():
        if not low <= options[key] <= high:
            raise HalError(f"motmod: {key}={options[key]} out of range {low}..{high}")
    if options["servo_period_nsec"] < 10_000:
        raise HalError(f"motmod: servo_period_nsec={options['servo_period_nsec']} is too short")
    return options


def _kinematics(host: Any, num_joints: int) -> Kinematics:
    """The kinematics loaded before motmod (``loadrt trivkins ...``, which sets
    ``host.kinematics``), as LinuxCNC requires, seen through motmod's joint count."""
    kins = getattr(host, "kinematics", None)
    if kins is None:
        raise HalError("motmod: no kinematics loaded; loadrt [KINS]KINEMATICS before motmod")
    return fit_joints(kins, num_joints)
