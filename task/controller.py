"""Task: states, modes, MDI and programs, turned into motion and iocontrol commands.

One loop (TASK-001..021), every [TASK]CYCLE_TIME or as soon as a command arrives:

0. beat task's heartbeat and act on E-stop and abort requests of the safety board
   (nml/safety.py), which reach task even when the command buffer is blocked, and on
   supervised processes found lost;
1. take the next command from ``emcCommand`` and answer it on ``emcStatus`` (EXEC, then
   DONE or ERROR with the command's serial number; refusals also on ``emcError``);
2. plan: while a program or MDI command runs, read ahead with the interpreter, whose canon
   queues NML messages, for at most PLAN_SLICE_S a cycle, so task answers E-stop, abort
   and status within a cycle whatever the program computes (an interpreter that runs
   [TASK]INTERP_TIMEOUT seconds without queueing anything is stopped, naming the line);
   a queue buster (M6, M66, G38 ... INTERP_EXECUTE_FINISH) stops the reading until
   everything queued has been carried out, then ``synch()`` reloads the interpreter's
   world model from the machine's (TASK-008..010);
3. execute: send the queued messages in order, to motion (moves go straight into its
   queue) or iocontrol (after motion has finished), or carry them out here (dwell, M0/M1,
   program end, operator messages);
4. publish EMC_STAT = {task, motion, io}, always right after a command changes something,
   and whenever motion's or iocontrol's status moved or a program runs (at rest, at least
   every PUBLISH_AT_LEAST_S: a resting machine does not rewrite unchanged status).
"""

from __future__ import annotations

import enum
import logging
import shlex
import subprocess
import time
from collections import deque
from collections.abc import Callable, Iterable

from cnc.ini import IniFile
from cnc.inischema import io_program
from nml import emc
from nml.channels import (
    EMC_COMMAND,
    EMC_ERROR,
    EMC_STATUS,
    MOTION_COMMAND,
    MOTION_STATUS,
    TOOL_COMMAND,
    TOOL_STATUS,
    Nml,
)
from nml.commands import (
    QUEUE,
    RUNNING,
    Handlers,
    Refused,
    carry_out,
    echo,
    handler,
    internal_error,
    unmet,
)
from nml.errors import NmlError
from nml.message import RCS_STATUS, MessageKind, Receiver, Requires
from nml.outbox import Outbox
from nml.safety import SafetyLink
from nml.shmem import LOCK_HELD_REPORT_S
from task.canon import state_tag_of
from task.interp import statetag
from task.interp.errors import (
    INTERP_ENDFILE,
    INTERP_EXECUTE_FINISH,
    INTERP_EXIT,
    INTERP_OK,
    InterpError,
)
from task.positions import PositionFileError, begin_run, read_positions, write_positions
from task.runfrom import STATE_MESSAGES, enclosing_block
from task.setup import MachineSetup, load_setup
from task.watchdog import InterpreterInterruptedError, InterpreterWatchdog

log = logging.getLogger("task")

MODE = emc.EMC_TASK_MODE_ENUM
STATE = emc.EMC_TASK_STATE_ENUM
EXEC = emc.EMC_TASK_EXEC_ENUM
INTERP = emc.EMC_TASK_INTERP_ENUM
READAHEAD = 50  # messages queued ahead of motion while reading a program
# Motion commands sent but not yet answered. Motion reports its queue full while fewer than
# its QUEUE_FULL_MARGIN (200) slots are free, so moves in flight always fit; and an ABORT
# waits behind them in motion's command buffer (motion takes 2-4 a period), so few keep
# abort quick: 100 delayed the stop by ~75 ms. Ten a task cycle outrun any program.
MAX_MOTION_IN_FLIGHT = 10
PUBLISH_AT_LEAST_S = 0.05  # EMC_STAT's longest age at rest (see cycle)
BUSY_POLL_S = 0.001  # how often task looks at motion while a program or MDI runs
# The interpreter's share of a cycle: it reads on in the next cycle, after task has looked
# at its commands and the safety board again.
PLAN_SLICE_S = 0.005
DEFAULT_HEARTBEAT_TIMEOUT_S = 1.0  # [TASK]HEARTBEAT_TIMEOUT
DEFAULT_INTERP_TIMEOUT_S = 10.0  # [TASK]INTERP_TIMEOUT (0: never)
# why ON_ABORT_COMMAND runs (its argument): LinuxCNC's EMC_ABORT reasons
EMC_ABORT_TASK_ABORT = 8
EMC_ABORT_INTERPRETER_ERROR = 9  # during a program
EMC_ABORT_INTERPRETER_ERROR_MDI = 10


class Run(enum.Enum):
    """What the interpreter is doing for us."""

    IDLE = 0
    MDI = 1
    PROGRAM = 2


class LineQueue(deque):
    """What the interpreter queued for motion and iocontrol, each message with the program
    line that made it (LinuxCNC's interp_list line numbers: stat.current_line)."""

    def __init__(self, messages: Iterable[emc.NMLmsg] = ()) -> None:
        super().__init__(messages)
        self.lines: deque[int] = deque(0 for _ in self)
        self.line = 0  # the line being interpreted: given to the messages appended now

    def append(self, msg: emc.NMLmsg) -> None:
        super().append(msg)
        self.lines.append(self.line)

    def popleft(self) -> emc.NMLmsg:
        if self.lines:
            self.lines.popleft()
        return super().popleft()

    def clear(self) -> None:
        super().clear()
        self.lines.clear()

    def head_line(self) -> int:
        return self.lines[0] if self.lines else self.line


class Task:
    def __init__(self, ini: IniFile, nml: Nml, canon_factory: Callable | None = None) -> None:
        from task.canon import CanonSetup, TaskCanon
        from task.interp.interp import Interpreter

        self.ini = ini
        self.setup: MachineSetup = load_setup(ini)
        self.nml = nml
        self.stat = emc.EMC_STAT()
        self.stat.status = RCS_STATUS.DONE  # idle with no command yet, as LinuxCNC's task
        # [EMCIO]EMCIO set but empty: the launcher starts no iocontrol, as LinuxCNC's
        # (orphans/axis_noio.ini; without the key LinuxCNC starts its io). E-stop is then
        # motion's and the safety board's alone; tool, coolant and lube commands are
        # refused (see _send_io)
        self.has_iocontrol = bool(io_program(ini))
        canon_setup = CanonSetup(
            linear_units=self.setup.linear_units,
            axis_mask=self.setup.axis_mask,
            axis_max_vel=[
                self.setup.axes[i].max_vel if i in self.setup.axes else float("inf")
                for i in range(9)
            ],
            axis_max_acc=[
                self.setup.axes[i].max_acc if i in self.setup.axes else float("inf")
                for i in range(9)
            ],
            max_velocity=self.setup.max_velocity,
            max_acceleration=self.setup.max_acceleration,
            random_toolchanger=self.setup.random_toolchanger,
            tool_change_position=self.setup.tool_change_position,
            user_m_commands=self.setup.user_m_commands,
            writable_dirs=_writable_dirs(ini, self.setup),
        )
        self.canon = (canon_factory or TaskCanon)(canon_setup)
        # what the canon queues, with line numbers. It holds INIT_CANON's blending already,
        # which motion starts with itself (motion/motmod.py): not sent (LinuxCNC's task
        # sends it, unless an E-stop reset comes first and drops it)
        initial = [m for m in self.canon.out if not isinstance(m, emc.EMC_TRAJ_SET_TERM_COND)]
        self.queue = self.canon.out = LineQueue(initial)
        self.interp = Interpreter(
            self.canon,
            ini=ini,
            parameter_file=self.setup.parameter_file,
            task=1,
            python_modules=self._python_modules(),
        )
        self.interp.init()
        self.interp.on_progress = self.keep_alive  # (reading a large program)
        self.current_line = 0  # the line of the message last taken from the queue
        self.mode = MODE.MANUAL
        self.state = STATE.ESTOP
        self.run = Run.IDLE
        self.is_paused = False
        self.is_reading_done = True  # the interpreter has nothing more to read for this run
        self.is_waiting_for_synch = False
        self.delay_until = 0.0
        self.input_wait: tuple[int, float] | None = None  # an M66 under way: (mode, deadline)
        self.mdi_queue: deque[tuple[int, str]] = deque()
        # a command still running (MDI, a program run), answered DONE when finished
        self.pending_serial = 0
        self.last_motion_serial = 0
        # motion may still be stopping from an abort: a move sent now would be dropped
        # with the aborted ones (it empties its queue once at rest), so moves wait
        self.is_after_abort = False
        self.last_io_serial = 0
        self.checked_motion_serial = 0
        self.file = ""
        self.system_command: subprocess.Popen[bytes] | None = None
        self.is_homing_required = False  # after an unclean shutdown, even with NO_FORCE_HOMING
        self.first_line = 0  # run from line: the lines before it are only interpreted
        self.is_skipping = False  # ... and these are being read
        self.skipped_state: dict[type, emc.NMLmsg] = {}  # the state the skipped lines set
        # the last tool change of the skipped lines: (line, tool number), or None
        self.skipped_tool_change: tuple[int, int] | None = None
        self.skipped_prepared_tool = 0
        self.furthest_line = 0  # the furthest line of the program read so far
        self.is_stepping = False  # AUTO_STEP: one line at a time
        self.step_line: int | None = None  # the line this step carries out (None: the next)
        self.interp_timeout = ini.get_float("TASK", "INTERP_TIMEOUT", DEFAULT_INTERP_TIMEOUT_S)
        self.is_running_on_abort = False  # ON_ABORT_COMMAND runs (its errors: no other)
        self.idle_reading_s = 0.0  # the interpreter's time since it last queued anything
        self.safety = SafetyLink.open(
            "task", ini.get_float("TASK", "HEARTBEAT_TIMEOUT", DEFAULT_HEARTBEAT_TIMEOUT_S)
        )
        # around every call into the interpreter: heartbeat, E-stop and abort while it runs
        self.watchdog = InterpreterWatchdog(self.safety, self.interp_timeout)
        # the newest safety board requests task has acted on (by the board or a command)
        self.estop_handled = 0
        self.status_counts: tuple[int, int] | None = None  # (motion's, iocontrol's) last read
        self.publish_due = 0.0  # EMC_STAT is published again by then, changed or not
        self.abort_handled = 0
        self.outbox = Outbox(nml[EMC_ERROR])  # operator messages: never wait for a reader
        self.stuck_command_writer = 0  # the pid last reported holding emcCommand's lock
        self.bad_buffer_quiet_until = 0.0
        self.bad_buffer_reports = 0
        self.handlers = Handlers(self)  # the @handler methods below: commands
        self.queue_steps = Handlers(self, table=QUEUE)  # and a program's queued messages

    # ================================================================ main loop
    def start(self) -> None:
        """Tell motion the machine's limits and where it was, put the machine in E-stop
        (as LinuxCNC's task starts: motion and the spindles stopped, motion off, the
        VOLATILE_HOME joints unhomed, joint mode), run the startup code and carry out what
        is queued, then publish the first status."""
        for msg in self.setup.motion_init_messages() + self._saved_positions():
            self._send_motion(msg)
        self._await(MOTION_STATUS, "motion", self.last_motion_serial, timeout=5.0)
        self.refresh()  # (motion's spindles)
        # (what the interpreter queued as it started stays queued: offsets, ...)
        self._abort_motion()
        self._stop_spindles()
        self._send_motion(emc.EMC_TRAJ_DISABLE())
        self._send_io(emc.EMC_AUX_ESTOP_ON())
        self._unhome_volatile_joints()
        self._send_motion(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.FREE))
        self._await(MOTION_STATUS, "motion", self.last_motion_serial, timeout=5.0)
        self.refresh()
        self._run_startup_code()
        # the first status shows what the interpreter restored (the .var file's offsets)
        # and the startup code set, as LinuxCNC's: a display may start with it
        self._execute()
        self._await(MOTION_STATUS, "motion", self.last_motion_serial, timeout=5.0)
        self.refresh()
        self.publish()

    def _run_startup_code(self) -> None:
        """[RS274NGC]RS274NGC_STARTUP_CODE, as LinuxCNC's task runs it after each
        interpreter initialisation: its canonical calls (a G43's tool offset) are queued
        and carried out like an MDI line's, whatever the machine's state."""
        code = self.setup.startup_code
        if not code:
            return
        self.queue.line = 0
        try:
            with self.watchdog:
                self.canon.set_status(self.stat)
                self.interp.synch()
                status = self.interp.execute(code)
                while status == INTERP_EXECUTE_FINISH:
                    status = self.interp.execute()
                self.canon.FINISH()
        except InterpError as exc:
            self.operator_error(f"[RS274NGC]RS274NGC_STARTUP_CODE: {exc}")

    def _saved_positions(self) -> list[emc.NMLmsg]:
        """[TRAJ]POSITION_FILE (task/positions.py): where the joints were at the last clean
        shutdown; after an unclean one, nothing, and homing is required."""
        path = self.setup.position_file
        if not path:
            return []
        if not begin_run(path):
            self.is_homing_required = True
            self.operator_error(
                f"{path}: the last run ended without saving the joint positions (killed or "
                "power lost): they are not restored; home the machine"
            )
            return []
        try:
            values = read_positions(path)
        except PositionFileError as exc:
            self.operator_error(f"{exc}; ignored")
            return []
        return [
            emc.EMC_JOINT_SET_MOTOR_OFFSET(joint=index, offset=-value)
            for index, value in enumerate(values[: len(self.setup.joints)])
        ]

    def cycle(self) -> None:
        """One pass of the loop: waits for a command at most CYCLE_TIME, or one servo
        period while something runs, so completions are seen (and answered) at once."""
        timeout = self.setup.cycle_time if self.run is Run.IDLE else BUSY_POLL_S
        has_news = self.take_safety_requests()
        cmd = self._next_command(timeout)
        has_news |= self.refresh()
        if cmd is not None:
            self.take_safety_requests()  # (a request older than the command goes first)
            self.handle(cmd)
        try:
            self._watch_estop()
            self._plan()
            self._execute()
            self._finish_runs()
        except Exception as exc:  # a bug: what runs stops, task goes on (nml/commands.py)
            self.operator_error(internal_error("task", "running the program", exc).reason)
            self._abort()
        self.outbox.flush()
        # at rest nothing changes: published again only when it may have (most of an idle
        # cycle's cost), and at least every PUBLISH_AT_LEAST_S all the same
        now = time.monotonic()
        if has_news or cmd is not None or self.run is not Run.IDLE or now >= self.publish_due:
            self.publish()

    def keep_alive(self) -> None:
        """Beat task's heartbeat in the middle of a long piece of work (reading a large
        program): task is alive, only busy; requests are taken at the next cycle."""
        if self.safety is not None:
            self.safety.heartbeat.beat()

    def take_safety_requests(self) -> bool:
        """Beat task's heartbeat; act on new E-stop and abort requests of the safety board
        and report the processes found lost (their E-stop is requested already). True if
        there was anything to act on."""
        if self.safety is None:
            return False
        tick = self.safety.tick()
        for lost in tick.lost:
            self.operator_error(f"E-stop: {lost.reason}")
        sent_before = self.last_motion_serial
        is_braking = False
        if tick.estop is not None and tick.estop.stamp > self.estop_handled:
            self.estop_handled = tick.estop.stamp
            is_braking = tick.estop.is_braking
            self._estop(is_braking=is_braking)
        if tick.abort is not None and tick.abort.stamp > self.abort_handled:
            self.abort_handled = tick.abort.stamp
            self._abort_command(emc.EMC_TASK_ABORT())
        if self.last_motion_serial != sent_before and not is_braking:
            # the E-stop or abort command that follows its request is answered at once
            # ("done already"): motion has what the request made task send by then (a
            # braking E-stop may be for motion lost: not waited for)
            self._await(MOTION_STATUS, "motion", self.last_motion_serial)
        return bool(tick.lost) or tick.estop is not None or tick.abort is not None

    def _next_command(self, timeout: float) -> emc.NMLmsg | None:
        channel = self.nml[EMC_COMMAND]
        try:
            return channel.blocking_read(timeout)
        except NmlError as exc:
            self._report_bad_buffer(f"bad command message: {exc}")
            return None
        finally:
            holder = channel.lock_holder()
            if holder is not None and holder[1] >= LOCK_HELD_REPORT_S:
                if holder[0] != self.stuck_command_writer:
                    self.stuck_command_writer = holder[0]
                    self.operator_error(
                        f"{channel.name}: process {holder[0]} has held the command lock for "
                        f"{holder[1]:.1f} s (stuck?): other user interfaces cannot send "
                        "commands; E-stop and abort still work"
                    )
            else:
                self.stuck_command_writer = 0

    def _report_bad_buffer(self, text: str) -> None:
        """Corrupt messages or buffers: said at most once a second, the rest counted."""
        now = time.monotonic()
        if now < self.bad_buffer_quiet_until:
            self.bad_buffer_reports += 1
            return
        if self.bad_buffer_reports:
            text += f" ({self.bad_buffer_reports} more such errors in the last second)"
        self.bad_buffer_reports = 0
        self.bad_buffer_quiet_until = now + 1.0
        self.operator_error(text)

    # ================================================================ commands
    def handle(self, cmd: emc.NMLmsg) -> None:
        """Carry out one command and answer it (EXEC, then DONE or ERROR)."""
        stat = self.stat
        echo(stat, cmd, RCS_STATUS.EXEC)
        serial = cmd.serial_number  # (a command passed on to motion gets motion's number)
        sent_before = self.last_motion_serial
        answer = carry_out("task", self._carry_out, cmd, expected=(InterpError, ValueError))
        if self.last_motion_serial != sent_before:
            # as LinuxCNC's task, which waits for motion to take each command it sends: a
            # command is answered once motion has what it sent (motion says why it refuses)
            self._await(MOTION_STATUS, "motion", self.last_motion_serial)
        # (echoed again: an abort it made may have answered an earlier running command)
        echo(stat, cmd, answer.status)
        stat.echo_serial_number = serial
        if answer.status == RCS_STATUS.EXEC:  # still running: answered when it finishes
            self.pending_serial = serial
            return
        if answer.reason is not None:
            self.operator_error(answer.reason)
        self.refresh()
        self.publish()

    def _carry_out(self, cmd: emc.NMLmsg) -> object:
        """A command's preconditions (its ``requires``), then its handler here, or else
        the process it is declared for (its ``receiver``), waiting for the answer."""
        self._check(cmd.REQUIRES)
        function = self.handlers.get(type(cmd))
        if function is not None:
            return function(cmd)
        if cmd.RECEIVER is Receiver.MOTION:  # manual motion, settings
            return self._order(self._send_motion, cmd)
        if cmd.RECEIVER is Receiver.IO:
            return self._order(self._send_io, cmd)
        raise Refused(f"task does not handle {cmd.NAME}")

    def _check(self, requires: Requires | None) -> None:
        """Refuse unless the machine state and mode are what ``requires`` says."""
        problem = unmet(requires, self.state, self.mode)
        if problem:
            raise Refused(problem)

    @staticmethod
    def _order(send: Callable[..., str | None], msg: emc.NMLmsg) -> None:
        """Send ``msg`` with ``send`` (_send_motion, _send_io) and wait for the answer;
        refused if it is."""
        problem = send(msg, is_waiting=True)
        if problem:
            raise Refused(problem)

    # ---------------------------------------------------------------- state and mode
    @handler(emc.EMC_TASK_SET_STATE)
    def _set_state(self, cmd: emc.EMC_TASK_SET_STATE) -> None:
        target = cmd.state
        if target == STATE.ESTOP:
            if cmd.request:  # the E-stop the sender also put on the safety board
                if cmd.request <= self.estop_handled:
                    return  # done already, from the board
                self.estop_handled = cmd.request
            self._estop(is_braking=False)
        elif target == STATE.ESTOP_RESET:
            lost = self.safety.board.lost_names() if self.safety is not None else []
            if lost:
                raise Refused(
                    f"cannot reset E-stop: {', '.join(lost)} was lost (its safety inputs "
                    "are not read); restart the machine"
                )
            self._order(self._send_io, emc.EMC_AUX_ESTOP_RESET())
            self._order(self._send_io, emc.EMC_AUX_ESTOP_OFF())
            if self.stat.io.aux.estop:
                raise Refused(
                    "cannot reset E-stop: the E-stop chain (iocontrol.0.emc-enable-in) is open"
                )
            self._abort_all()
            if self.stat.motion.traj.enabled:  # (off in E-stop: only as a safeguard)
                self._send_motion(emc.EMC_TRAJ_DISABLE())
            self.state = STATE.ESTOP_RESET
        elif target == STATE.ON:
            if self.state == STATE.ESTOP:
                raise Refused("cannot turn the machine on while in E-stop")
            self._order(self._send_motion, emc.EMC_TRAJ_ENABLE())
            self.state = STATE.ON
        elif target == STATE.OFF:
            if self.state == STATE.ESTOP:
                raise Refused("cannot turn the machine off while in E-stop (reset it first)")
            self._abort_all()
            self._send_motion(emc.EMC_TRAJ_DISABLE())
            self._unhome_volatile_joints()
            self.state = STATE.OFF
        else:
            raise Refused(f"unknown machine state {target}")

    def _estop(self, is_braking: bool) -> None:
        """E-stop, asked for by a command, the E-stop chain or the safety board: stop
        everything, iocontrol's outputs safe, motion off at once. A braking E-stop (a
        process was lost) leaves motion on: it brakes along its path, goes off by itself
        and then asks for the immediate E-stop, which turns iocontrol's outputs off. Never
        waits for an answer: iocontrol or motion may be the process that is gone."""
        self._abort_all()
        if not is_braking:
            self._send_motion(emc.EMC_TRAJ_DISABLE())
            self._send_io(emc.EMC_AUX_ESTOP_ON())
            self._unhome_volatile_joints()
        self.state = STATE.ESTOP

    def _unhome_volatile_joints(self) -> None:
        """[JOINT_n]VOLATILE_HOME joints lose their home with E-stop and machine off, as
        in LinuxCNC (motion off: sent after EMC_TRAJ_DISABLE)."""
        self._send_motion(emc.EMC_JOINT_UNHOME(joint=-2))

    @handler(emc.EMC_TASK_SET_MODE)
    def _set_mode(self, cmd: emc.EMC_TASK_SET_MODE) -> None:
        mode = cmd.mode
        if mode not in (MODE.MANUAL, MODE.AUTO, MODE.MDI):
            raise Refused(f"unknown mode {mode}")
        if mode == self.mode and mode != MODE.MANUAL:
            return
        if self.run is Run.PROGRAM:
            raise Refused("cannot change mode while a program runs (abort it first)")
        if mode in (MODE.AUTO, MODE.MDI):
            # as LinuxCNC's task: coordinated mode at once, then an abort (what ran in the
            # other mode stops); not while jogging, which LinuxCNC ignores the change for
            if self.stat.motion.jogging_active:
                raise Refused("cannot change mode while jogging")
            self._send_motion(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD))
            if self.run is Run.IDLE:  # (what waits in the queue, a restore, stays)
                self._abort_motion()
            else:
                self._abort()
        if mode == MODE.MANUAL:
            # manual mode jogs world axes (teleop) once every joint is homed, else joints
            # (free), as LinuxCNC's emcTaskSetMode; asked again (after homing) it switches,
            # unless a jog runs (LinuxCNC ignores a mode change then)
            if mode != self.mode:
                self._abort()
            elif self.stat.motion.jogging_active:
                return
            joints = self.stat.motion.joint
            is_all_homed = all(joints[i].homed for i in range(len(self.setup.joints)))
            traj_mode = (
                emc.EMC_TRAJ_MODE_ENUM.TELEOP if is_all_homed else emc.EMC_TRAJ_MODE_ENUM.FREE
            )
            self._send_motion(emc.EMC_TRAJ_SET_MODE(mode=traj_mode), is_waiting=True)
        self.mode = MODE(mode)

    @handler(emc.EMC_TRAJ_SET_TELEOP_ENABLE)
    def _teleop(self, cmd: emc.EMC_TRAJ_SET_TELEOP_ENABLE) -> None:
        """Manual mode jogs joints (free) or, once homed, world axes (teleop), as LinuxCNC."""
        mode = emc.EMC_TRAJ_MODE_ENUM.TELEOP if cmd.enable else emc.EMC_TRAJ_MODE_ENUM.FREE
        self._order(self._send_motion, emc.EMC_TRAJ_SET_MODE(mode=mode))

    def _ensure_coordinated(self) -> None:
        """Programs and MDI need coordinated mode, which needs homed joints (TASK-016)."""
        joints = self.stat.motion.joint
        is_forced = self.setup.is_homing_forced or self.is_homing_required
        if is_forced and not all(joints[i].homed for i in range(len(self.setup.joints))):
            if self.is_homing_required:
                raise Refused(
                    "all joints must be homed first (the last run did not save positions)"
                )
            raise Refused("all joints must be homed first ([TRAJ]NO_FORCE_HOMING is not set)")
        if self.stat.motion.traj.mode == emc.EMC_TRAJ_MODE_ENUM.COORD:
            return  # (since the switch to Auto or MDI mode, as a rule)
        self._order(self._send_motion, emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD))

    # ---------------------------------------------------------------- MDI and programs
    @handler(emc.EMC_TASK_PLAN_EXECUTE)
    def _mdi(self, cmd: emc.EMC_TASK_PLAN_EXECUTE) -> str | None:
        if self.run is not Run.IDLE:
            self.mdi_queue.append((cmd.serial_number, cmd.command))
            return RUNNING
        self._ensure_coordinated()
        outcome = self._start_mdi_or_abort(cmd.command)
        if isinstance(outcome, str):
            raise Refused(outcome)
        return RUNNING

    def _start_mdi_or_abort(self, text: str) -> str | bool:
        """``_start_mdi``; when the interpreter refuses the line, ON_ABORT_COMMAND runs
        (reason 10, EMC_ABORT_INTERPRETER_ERROR_MDI) after the error is reported."""
        outcome = self._start_mdi(text)
        if isinstance(outcome, str):
            self._run_on_abort(EMC_ABORT_INTERPRETER_ERROR_MDI)
        return outcome

    def _start_mdi(self, text: str) -> str | bool:
        self.stat.task.command = emc.fit_text(text)
        self.checked_motion_serial = self.last_motion_serial
        self.queue.line = 0  # MDI lines have no line number in a file
        self.interp.slice_deadline = time.monotonic() + PLAN_SLICE_S  # (a subroutine call)
        try:
            with self.watchdog:
                self.canon.set_status(self.stat)
                self.interp.synch()
                status = self.interp.execute(text)
                self.canon.FINISH()  # queue a move held back for naive-CAM joining (G64 Q)
        except InterpError as exc:
            self.queue.clear()
            return str(exc)
        finally:
            self.interp.slice_deadline = None
        self.idle_reading_s = 0.0
        self.run = Run.MDI
        self.is_reading_done = status != INTERP_EXECUTE_FINISH and not self.interp.call_level
        self.is_waiting_for_synch = status == INTERP_EXECUTE_FINISH
        return True

    @handler(emc.EMC_TASK_PLAN_OPEN)
    def _open(self, cmd: emc.EMC_TASK_PLAN_OPEN) -> None:
        if self.run is Run.PROGRAM:
            raise Refused("cannot open a program while one runs")
        with self.watchdog:
            self.interp.close()
            self.interp.open(cmd.file)
        self.file = cmd.file
        self.current_line = 0

    @handler(emc.EMC_TASK_PLAN_CLOSE)
    def _close(self, _cmd: emc.NMLmsg) -> None:
        if self.run is Run.PROGRAM:
            raise Refused("cannot close the program while it runs")
        self.interp.close()
        self.file = ""

    @handler(emc.EMC_TASK_PLAN_RUN)
    def _run_program(self, cmd: emc.EMC_TASK_PLAN_RUN) -> str:
        if not self.file:
            raise Refused("no program open (program_open first)")
        if self.run is not Run.IDLE:
            raise Refused("a program is already running")
        self._ensure_coordinated()
        with self.watchdog:
            self.interp.close()
            self.interp.open(self.file)
            if cmd.line > 1:
                inside = enclosing_block(self.interp.file_lines or [], cmd.line, self.keep_alive)
                if inside:
                    raise Refused(
                        f"cannot run from line {cmd.line}: it is inside {inside}, whose state "
                        "cannot be known without running it; start at the block's first line"
                    )
            self.canon.set_status(self.stat)
            self.interp.synch()
        self.checked_motion_serial = self.last_motion_serial
        self.run = Run.PROGRAM
        self.is_paused = False
        self.is_reading_done = False
        self.is_waiting_for_synch = False
        self.first_line = cmd.line
        self.is_skipping = cmd.line > 1
        self.skipped_state.clear()
        self.skipped_tool_change = None
        self.furthest_line = 0
        self.is_stepping = False
        return RUNNING  # answered when the program ends, as LinuxCNC's (wait_complete waits)

    @handler(emc.EMC_TASK_PLAN_PAUSE)
    def _pause(self, _cmd: emc.NMLmsg) -> None:
        if self.run is Run.IDLE:
            raise Refused("nothing is running to pause")
        self.is_paused = True
        self._refuse_if(self._send_motion(emc.EMC_TRAJ_PAUSE()))

    @handler(emc.EMC_TASK_PLAN_RESUME)
    def _resume(self, _cmd: emc.NMLmsg) -> None:
        self.is_stepping = False
        if not self.is_paused:
            return
        self.is_paused = False
        self._refuse_if(self._send_motion(emc.EMC_TRAJ_RESUME()))

    @staticmethod
    def _refuse_if(problem: str | None) -> None:
        if problem:
            raise Refused(problem)

    @handler(emc.EMC_TASK_PLAN_STEP)
    def _step(self, cmd: emc.NMLmsg) -> None:
        """AUTO_STEP: carry out the next line, then pause (from idle: start the program).
        Paused with moves left in motion's queue (a feed hold in the middle of a line),
        motion runs the next of them to its end and pauses again, as LinuxCNC's task
        does; then the lines still in task's queue go out one at a time (_may_step)."""
        if self.run is Run.IDLE:
            self._check(emc.EMC_TASK_PLAN_RUN.REQUIRES)
            self._run_program(emc.EMC_TASK_PLAN_RUN(line=0))
        elif self.run is not Run.PROGRAM:
            raise Refused("step needs a program (AUTO mode)")
        self.is_stepping = True
        if self.is_paused and self.stat.motion.traj.queue > 0:
            self._refuse_if(self._send_motion(emc.EMC_TRAJ_STEP()))
            return
        self.step_line = None
        if self.is_paused:
            self.is_paused = False
            self._refuse_if(self._send_motion(emc.EMC_TRAJ_RESUME()))

    def _may_step(self, line: int) -> bool:
        """While stepping: may a message of ``line`` go out now? Those of the line being
        stepped may; the first of the next line ends the step, once the line is done."""
        if self.step_line is None:
            self.step_line = line
        if line == self.step_line:
            return True
        if self._is_everything_done():
            self.is_paused = True
            self.step_line = None
        return False

    @handler(emc.EMC_TASK_PLAN_INIT)
    def _plan_init(self, _cmd: emc.NMLmsg) -> None:
        if self.run is not Run.IDLE:
            raise Refused("cannot reset the interpreter while it runs")
        self.interp.reset()
        self._run_startup_code()

    @handler(emc.EMC_TASK_PLAN_SYNCH)
    def _synch(self, _cmd: emc.NMLmsg) -> None:
        self.canon.set_status(self.stat)
        self.interp.synch()

    @handler(emc.EMC_TASK_PLAN_SET_OPTIONAL_STOP)
    def _set_optional_stop(self, cmd: emc.NMLmsg) -> None:
        self.canon.SET_OPTIONAL_PROGRAM_STOP(bool(cmd.state))

    @handler(emc.EMC_TASK_PLAN_SET_BLOCK_DELETE)
    def _set_block_delete(self, cmd: emc.NMLmsg) -> None:
        self.canon.SET_BLOCK_DELETE(bool(cmd.state))

    @handler(emc.EMC_OPERATOR_ERROR, emc.EMC_OPERATOR_TEXT, emc.EMC_OPERATOR_DISPLAY)
    def _forward_operator_message(self, cmd: emc.NMLmsg) -> None:
        """A UI's error_msg/text_msg/display_msg goes to every UI (as LinuxCNC's task)."""
        self._write_error_channel(cmd)

    @handler(emc.EMC_TASK_ABORT)
    def _abort_command(self, cmd: emc.EMC_TASK_ABORT) -> None:
        if cmd.request:  # the abort the sender also put on the safety board
            if cmd.request <= self.abort_handled:
                return  # done already, from the board
            self.abort_handled = cmd.request
        # as LinuxCNC's task: the abort, then motion aborted once more (and the spindles
        # stopped) before the interpreter's state is restored
        self._abort()
        self._abort_all()
        if self.mode == MODE.AUTO:
            self._restore_interpreter_state()
        self.operator_text("task: aborted")  # an abort is always reported (TASK-019)
        self._run_on_abort(EMC_ABORT_TASK_ABORT)

    def _restore_interpreter_state(self) -> None:
        """After a program's abort: the interpreter read ahead of motion, so its modes
        (coordinate system, units, feed ...) are those of a line never carried out; bring
        them back to those of the move motion was on (its state tag), as LinuxCNC's task
        does (emcTaskStateRestore). The G-code that does it queues the canon's messages
        (a G55's EMC_TRAJ_SET_G5X ...), carried out as an MDI line's are."""
        tag = state_tag_of(self.stat.motion.traj.tag)
        self.queue.line = 0
        try:
            with self.watchdog:
                self.canon.set_status(self.stat)
                if self.interp.restore_from_tag(tag):
                    self.canon.FINISH()
        except InterpError as exc:
            self.operator_error(str(exc))

    def _abort_all(self) -> None:
        """Abort as LinuxCNC's task does on STOP, E-stop, machine off and run-time errors:
        as ``_abort``, and every spindle stops and iocontrol turns the coolant off and
        drops any tool-change handshake (emcIoAbort, emcSpindleAbort)."""
        self._abort()
        self._stop_spindles()
        self._send_io(emc.EMC_TOOL_ABORT())

    def _stop_spindles(self) -> None:
        for spindle in range(max(self.stat.motion.traj.spindles, 1)):
            self._send_motion(emc.EMC_SPINDLE_OFF(spindle=spindle))

    def _abort(self) -> None:
        """Stop motion along the path and every jog, forget what was queued (LinuxCNC's
        emcTaskAbort)."""
        self._abort_motion()
        if self.stat.io.status == RCS_STATUS.EXEC:
            self._send_io(emc.EMC_TOOL_ABORT())
        self.queue.clear()
        self.mdi_queue.clear()
        if self.run is not Run.IDLE:
            self.interp.reset()
        self.run = Run.IDLE
        self.is_paused = False
        self.is_stepping = False
        self.step_line = None
        self.is_reading_done = True
        self.is_waiting_for_synch = False
        self.delay_until = 0.0
        self.input_wait = None
        self._answer_pending(RCS_STATUS.DONE)  # (stopped: done, as LinuxCNC's status says)
        self.idle_reading_s = 0.0

    def _abort_motion(self) -> None:
        """Stop motion along the path and every jog (LinuxCNC's emcMotionAbort); the moves
        queued after it wait until motion is at rest."""
        self._send_motion(emc.EMC_MOTION_ABORT())
        self.is_after_abort = True

    def _run_on_abort(self, reason: int) -> None:
        """[RS274NGC]ON_ABORT_COMMAND (e.g. ``O <on_abort> call``) after an abort or an
        interpreter error, with the reason (LinuxCNC's EMC_ABORT_*) as its argument
        (REMAP-037, REMAP-038): it runs as an MDI command, so its queue busters synchronise.
        Not in E-stop (nothing could move), nor for an error of the command itself."""
        if self.is_running_on_abort:  # the command itself failed or was aborted
            self.is_running_on_abort = False
            return
        if self.state != STATE.ON:
            return
        command = self.interp.abort_command(reason)
        if command is None:
            return
        self.is_running_on_abort = True
        outcome = self._start_mdi(command)
        if outcome is not True:
            self.is_running_on_abort = False
            self.operator_error(f"ON_ABORT_COMMAND: {outcome}")

    def _python_modules(self) -> dict:
        """``emctask`` for the interpreter's Python (PY-024, PY-025): task's status, its
        INI file and its operator messages."""
        from task.interp.python import emctask

        def message(kind: str, text: str) -> None:
            if not hasattr(self, "outbox"):  # (TOPLEVEL's __init__, at start-up)
                log.info("%s", text)
            elif kind == "error":
                self.operator_error(text)
            elif kind == "text":
                self.operator_text(text)
            else:
                self._write_error_channel(emc.EMC_OPERATOR_DISPLAY(display=emc.fit_text(text)))

        emctask.bind(self.stat, getattr(self.ini, "path", ""), message)
        return {"emctask": emctask}

    # ================================================================ planning
    def _plan(self) -> None:
        """Read ahead while a program or MDI command runs (TASK-006..010), for at most
        PLAN_SLICE_S: the rest is read in the next cycles."""
        if self.run is Run.IDLE or self.is_paused:
            return
        if self.is_reading_done:
            return
        if self.is_waiting_for_synch:  # a queue buster: synch once all it queued is done
            if self.queue or not self._is_everything_done():
                return
            self.canon.set_status(self.stat)
            with self.watchdog:
                self.interp.synch()
            self.is_waiting_for_synch = False
        started = time.monotonic()
        queued, furthest = len(self.queue), self.furthest_line
        self.interp.slice_deadline = started + PLAN_SLICE_S
        try:
            with self.watchdog:
                self._read_ahead()
        finally:
            self.interp.slice_deadline = None
        if self.run is not Run.IDLE:
            has_progressed = len(self.queue) != queued or self.furthest_line != furthest
            self._check_interp_time(0.0 if has_progressed else time.monotonic() - started)

    def _read_ahead(self) -> None:
        deadline = self.interp.slice_deadline
        while len(self.queue) < READAHEAD and not self.is_reading_done:
            if time.monotonic() >= deadline:
                return  # on in the next cycle
            try:
                if self.run is Run.MDI:
                    status = self.interp.execute(None) if self.interp.call_level else INTERP_EXIT
                    if status != INTERP_EXECUTE_FINISH and not self.interp.call_level:
                        self.is_reading_done = True
                else:
                    status = self.interp.read()
                    if status == INTERP_ENDFILE:
                        self.is_reading_done = True
                        break
                    line = self.interp.sequence_number
                    self.furthest_line = max(self.furthest_line, line)
                    if self.is_skipping and not self.interp.call_level and line >= self.first_line:
                        self._end_skipping()  # (the line before it was in a subroutine)
                    self.queue.line = line
                    status = self.interp.execute()
                    if self.is_skipping:  # run from line: interpreted for its state only
                        self._keep_state_of_skipped_line()
                        status = INTERP_OK if status == INTERP_EXECUTE_FINISH else status
                    if status == INTERP_EXIT:
                        self.is_reading_done = True
            except InterpreterInterruptedError as exc:
                if exc.is_requested:  # task acts on the E-stop or abort right after
                    self._abort()
                else:
                    self._program_error(str(exc))
                return
            except InterpError as exc:
                self._program_error(str(exc))
                return
            if status == INTERP_EXECUTE_FINISH:
                self.is_waiting_for_synch = True
                return

    def _check_interp_time(self, spent: float) -> None:
        """[TASK]INTERP_TIMEOUT: an interpreter that neither queues anything nor reaches a
        line it had not reached before for that long is in an endless loop: stop it."""
        if not spent:
            self.idle_reading_s = 0.0
            return
        self.idle_reading_s += spent
        if self.interp_timeout and self.idle_reading_s > self.interp_timeout:
            self._program_error(
                f"the interpreter ran {self.idle_reading_s:.1f} s without producing motion "
                f"(an endless loop?); stopped ([TASK]INTERP_TIMEOUT = {self.interp_timeout:g})"
            )

    # ---------------------------------------------------------------- run from line
    def _keep_state_of_skipped_line(self) -> None:
        """Run from line: what a skipped line queued is not carried out, but the state it
        set is kept (the last of each kind), so that motion and the interpreter agree on
        offsets and settings when the run starts. Its tool changes are noted (the
        machine keeps the tool it holds); its errors are reported, as LinuxCNC does."""
        for msg in self.queue:
            if isinstance(msg, STATE_MESSAGES):
                self.skipped_state[type(msg)] = msg
            elif isinstance(msg, emc.EMC_TOOL_PREPARE):
                self.skipped_prepared_tool = msg.tool
            elif isinstance(msg, emc.EMC_TOOL_LOAD):  # M6: the prepared tool
                self.skipped_tool_change = (self.interp.sequence_number, self.skipped_prepared_tool)
            elif isinstance(msg, emc.EMC_TOOL_SET_NUMBER):  # M61: a tooldata index
                tool = self.interp.tool_table[msg.tool].toolno
                self.skipped_tool_change = (self.interp.sequence_number, tool)
            elif isinstance(msg, emc.EMC_OPERATOR_ERROR):
                self._write_error_channel(msg)
        self.queue.clear()
        if not self.interp.call_level and self.interp.sequence_number + 1 >= self.first_line:
            self._end_skipping()  # the next line is the start line

    def _end_skipping(self) -> None:
        """The start line is next: the interpreter's world model becomes the machine's
        again (as LinuxCNC synchs there), and the state the skipped lines set goes out
        before the start line's own messages. A tool changed by the skipped lines that is
        not the one in the spindle stops the run: its offsets would not be the tool's."""
        self.is_skipping = False
        in_spindle = self.stat.io.tool.toolInSpindle
        if self.skipped_tool_change and self.skipped_tool_change[1] != in_spindle:
            line, tool = self.skipped_tool_change
            raise InterpError(
                f"cannot run from line {self.first_line}: line {line} before it changes to "
                f"tool {tool}, and the spindle holds tool {in_spindle}; load tool {tool} "
                f"first, or start at line {line} or before"
            )
        for msg in self.skipped_state.values():
            self.queue.append(msg)
        self.skipped_state.clear()
        self.canon.set_status(self.stat)
        self.interp.synch()

    def _program_error(self, text: str) -> None:
        line = getattr(self.interp, "sequence_number", 0)
        # the file the interpreter reads: the program, or a subroutine's file (MDI calls)
        source = getattr(self.interp, "filename", "") or (
            self.file if self.run is Run.PROGRAM else ""
        )
        where = (
            f" (line {line} of {source})" if source and (self.run is Run.PROGRAM or line) else ""
        )
        self.operator_error(f"{text}{where}")
        self.stat.task.interpreter_errcode = 1
        self._answer_pending(RCS_STATUS.ERROR)
        was_mdi = self.run is Run.MDI
        self._abort()
        self._run_on_abort(
            EMC_ABORT_INTERPRETER_ERROR_MDI if was_mdi else EMC_ABORT_INTERPRETER_ERROR
        )

    # ================================================================ execution
    def _execute(self) -> None:
        """Send queued messages in order, each when its preconditions hold: the step
        declared for its type (``@handler(..., table=QUEUE)`` below), else
        ``_pass_on``. A step returns whether the message is done with (then it leaves
        the queue), or must be looked at again next cycle."""
        now = time.monotonic()
        while self.queue and not self.is_paused:
            if now < self.delay_until:
                return
            msg = self.queue[0]
            line = self.queue.head_line()
            if self.is_stepping and not self._may_step(line):
                return
            self.current_line = line
            step = self.queue_steps.get(type(msg), self._pass_on)
            if not step(msg, now):
                return
            if self.queue:  # (an error in the step may have aborted the run and emptied it)
                self.queue.popleft()

    def _pass_on(self, msg: emc.NMLmsg, _now: float) -> bool:
        """A queued message without a step of its own: an operator message goes to the
        error channel, a command to its declared receiver (moves straight into motion's
        queue while it has room; a queue buster once all before it is done)."""
        if msg.KIND is MessageKind.OPERATOR:
            self._write_error_channel(msg)
            return True
        if msg.RECEIVER is Receiver.MOTION:
            motion = self.stat.motion
            if isinstance(msg, emc.MOVES_WITH_MOTION_ID):
                if not motion.traj.enabled:
                    self._refuse_move_with_motion_off()
                    return True
                if self.is_after_abort:
                    if not self._is_motion_done():
                        return False
                    self.is_after_abort = False
            in_flight = self.last_motion_serial - motion.echo_serial_number
            if motion.traj.queueFull or in_flight >= MAX_MOTION_IN_FLIGHT:
                return False
            if msg.waits_for_motion() and not self._is_everything_done():
                return False
            return not self._send_motion(msg)
        if msg.RECEIVER is Receiver.IO:
            if msg.waits_for_motion() and not self._is_everything_done():
                return False
            return not self._send_io(msg)
        return True

    @handler(emc.EMC_MOTION_SET_DOUT, emc.EMC_MOTION_SET_AOUT, table=QUEUE)
    def _output(self, msg: emc.EMC_MOTION_SET_DOUT | emc.EMC_MOTION_SET_AOUT, now: float) -> bool:
        """M62/M63/M67 go with the next move. An immediate output (M64, M65, M68: ``now``)
        is set once all before it is done, and task waits for motion's answer, as
        LinuxCNC's task waits for each command it gives motion: the status task publishes
        next, the one echoing the MDI line that set it, already shows it. (A refusal
        stops the run through _check_motion_errors.)"""
        if not msg.now:
            return self._pass_on(msg, now)
        if not self._is_everything_done() or not self._pass_on(msg, now):
            return False
        self._await(MOTION_STATUS, "motion", self.last_motion_serial)
        return True

    def _refuse_move_with_motion_off(self) -> None:
        """A queued move with motion off (the startup code's, in E-stop): motion would
        refuse it, and LinuxCNC's task then drops what is queued. Said, and dropped
        without sending anything (nothing reached motion that needs stopping)."""
        text = "cannot move with the machine off: the queued moves and what follows are dropped"
        if self.run is not Run.IDLE:
            self._program_error(text)
            return
        self.operator_error(text)
        self.queue.clear()

    @handler(emc.EMC_TRAJ_DELAY, table=QUEUE)
    def _delay(self, msg: emc.EMC_TRAJ_DELAY, now: float) -> bool:
        if not self._is_motion_done():
            return False
        self.delay_until = now + msg.delay
        return True

    @handler(emc.EMC_TASK_PLAN_PAUSE, emc.EMC_TASK_PLAN_OPTIONAL_STOP, table=QUEUE)
    def _program_pause(self, msg: emc.NMLmsg, _now: float) -> bool:
        """M0, and M1 with the optional stop on: pause once motion is at rest."""
        if not self._is_motion_done():
            return False
        if isinstance(msg, emc.EMC_TASK_PLAN_PAUSE) or self.canon.GET_OPTIONAL_PROGRAM_STOP():
            self.is_paused = True
            # motion pauses too, as LinuxCNC's: stat.paused reads true at an M0/M1
            self._send_motion(emc.EMC_TRAJ_PAUSE())
        return True

    @handler(emc.EMC_TASK_PLAN_END, table=QUEUE)
    def _program_end(self, _msg: emc.NMLmsg, _now: float) -> bool:
        if not self._is_everything_done():
            return False
        self.is_reading_done = True
        return True

    @handler(emc.EMC_TRAJ_SET_G5X, emc.EMC_TRAJ_SET_G92, emc.EMC_TRAJ_SET_ROTATION, table=QUEUE)
    def _origin(self, msg: emc.NMLmsg, _now: float) -> bool:
        """G54..G59.3, G92 and G10's changes of the active system, and their XY rotation:
        they are task's (motion works in machine coordinates), shown in EMC_STAT once the
        moves before them are done, as LinuxCNC's task applies them: the status shows the
        origin of the move being carried out, not of a line the interpreter read ahead."""
        if not self._is_motion_done():
            return False
        task = self.stat.task
        if isinstance(msg, emc.EMC_TRAJ_SET_G5X):
            task.g5x_offset, task.g5x_index = msg.origin, msg.g5x_index
        elif isinstance(msg, emc.EMC_TRAJ_SET_G92):
            task.g92_offset = msg.origin
        else:
            task.rotation_xy = msg.rotation
        return True

    @handler(emc.EMC_TRAJ_SET_OFFSET, table=QUEUE)
    def _tool_offset(self, msg: emc.EMC_TRAJ_SET_OFFSET, _now: float) -> bool:
        if not self._is_everything_done() or self._send_motion(msg):
            return False
        # the applied tool length offset (G43/G49), in step with the program
        self.stat.task.toolOffset = msg.offset
        return True

    @handler(emc.EMC_AUX_INPUT_WAIT, table=QUEUE)
    def _input_wait(self, msg: emc.EMC_AUX_INPUT_WAIT, now: float) -> bool:
        return self._is_motion_done() and self._is_input_wait_over(msg, now)

    @handler(emc.EMC_SYSTEM_CMD, table=QUEUE)
    def _system_command(self, msg: emc.EMC_SYSTEM_CMD, _now: float) -> bool:
        return self._is_everything_done() and self._start_system_command(msg)

    @handler(emc.EMC_TRAJ_SET_MOTION_ID, table=QUEUE)
    def _motion_id(self, msg: emc.EMC_TRAJ_SET_MOTION_ID, now: float) -> bool:
        # the move that follows carries the id to motion; else motion takes it itself
        return self._stamp_next_move(msg.id) or self._pass_on(msg, now)

    def _is_input_wait_over(self, msg: emc.EMC_AUX_INPUT_WAIT, now: float) -> bool:
        """M66 (and emccanon.WAIT): wait, as LinuxCNC's task, until the digital input is
        high or low (L3, L4), or goes high or low (L1, L2: seen low first, or high), or the
        timeout (Q) passes, which sets input_timeout (GET_EXTERNAL_*_INPUT then give -1). An
        immediate read (L0), and an analog input, do not wait."""
        mode = emc.WAIT_MODE
        if self.input_wait is None:
            self.stat.task.input_timeout = 0
            if msg.input_type != emc.INPUT_TYPE.DIGITAL or msg.wait_type == mode.IMMEDIATE:
                return True
            self.input_wait = (msg.wait_type, now + msg.timeout)
        wait_type, deadline = self.input_wait
        is_high = bool(self.stat.motion.synch_di[msg.index])
        if wait_type == mode.RISE and not is_high:
            wait_type = mode.HIGH  # low seen: now the rise
        elif wait_type == mode.FALL and is_high:
            wait_type = mode.LOW
        self.input_wait = (wait_type, deadline)
        if (wait_type == mode.HIGH and is_high) or (wait_type == mode.LOW and not is_high):
            self.input_wait = None
            return True
        if now >= deadline:
            self.input_wait = None
            self.stat.task.input_timeout = 1
            return True
        return False

    def _stamp_next_move(self, motion_id: int) -> bool:
        """Give ``motion_id`` to the move queued right after it (as LinuxCNC's task fills
        emcmotCommand.id); False when no move follows or the id is 0, which a move's
        ``id`` cannot carry."""
        queue = self.queue
        if not motion_id or len(queue) < 2 or not isinstance(queue[1], emc.MOVES_WITH_MOTION_ID):
            return False
        queue[1].id = motion_id
        return True

    def _start_system_command(self, msg: emc.NMLmsg) -> bool:
        """M100..M199: run the user's program and wait for it (TASK-011); True once it ran."""
        if self.system_command is not None:
            if self.system_command.poll() is None:
                return False
            status = self.system_command.returncode
            self.system_command = None
            if status != 0:
                self._program_error(f"{msg.string.split()[0]} exited with status {status}")
            return True
        try:
            self.system_command = subprocess.Popen(shlex.split(msg.string))
        except OSError as exc:
            self._program_error(f"cannot run {msg.string}: {exc}")
            return True
        return False

    def _finish_runs(self) -> None:
        """A run is over when nothing is left to read, queue or move."""
        self._check_motion_errors()
        if self.run is Run.IDLE or not self.is_reading_done or self.queue:
            return
        if not self._is_everything_done() or time.monotonic() < self.delay_until:
            return
        was_mdi = self.run is Run.MDI
        self.run = Run.IDLE
        self.is_running_on_abort = False
        if was_mdi and self.mdi_queue:
            # the queued MDI commands run in turn; the last one received (the pending
            # serial) is answered DONE when all have run, as LinuxCNC's wait_complete expects
            serial, text = self.mdi_queue.popleft()
            outcome = self._start_mdi_or_abort(text)
            if outcome is True:
                return
            self.mdi_queue.clear()
            self.pending_serial = 0
            self.stat.echo_serial_number = serial
            self.stat.status = RCS_STATUS.ERROR
            self.operator_error(outcome)
            return
        self._answer_pending(RCS_STATUS.DONE)

    def _answer_pending(self, status: RCS_STATUS) -> None:
        """Answer the command still running (an MDI command, a program run), if any."""
        if self.pending_serial:
            self.stat.echo_serial_number = self.pending_serial
            self.stat.status = status
            self.pending_serial = 0

    def _check_motion_errors(self) -> None:
        """A command motion refused during a run stops the run (motion said why)."""
        motion = self.stat.motion
        if (
            motion.status == RCS_STATUS.ERROR
            and motion.echo_serial_number > self.checked_motion_serial
        ):
            self.checked_motion_serial = motion.echo_serial_number
            if self.run is not Run.IDLE:
                self._program_error("motion refused a command")

    def _is_motion_done(self) -> bool:
        motion = self.stat.motion
        return (
            motion.echo_serial_number >= self.last_motion_serial
            and motion.status != RCS_STATUS.EXEC
            and motion.traj.inpos
            and motion.traj.queue == 0
        )

    def _is_io_done(self) -> bool:
        io = self.stat.io
        return io.echo_serial_number >= self.last_io_serial and io.status != RCS_STATUS.EXEC

    def _is_everything_done(self) -> bool:
        return self._is_motion_done() and self._is_io_done()

    # ================================================================ sending
    def _send_motion(self, msg: emc.NMLmsg, is_waiting: bool = False) -> str | None:
        try:
            self.last_motion_serial = self.nml[MOTION_COMMAND].write(msg)
        except NmlError as exc:
            return f"cannot send {msg.NAME} to motion: {exc}"
        return self._await(MOTION_STATUS, "motion", self.last_motion_serial) if is_waiting else None

    def _send_io(self, msg: emc.NMLmsg, is_waiting: bool = False) -> str | None:
        if not self.has_iocontrol:
            if isinstance(msg, _IO_OPTIONAL):
                return None  # nothing to tell an iocontrol that is not there
            return f"cannot {msg.NAME}: this machine has no iocontrol ([EMCIO]EMCIO is empty)"
        try:
            self.last_io_serial = self.nml[TOOL_COMMAND].write(msg)
        except NmlError as exc:
            return f"cannot send {msg.NAME} to iocontrol: {exc}"
        return self._await(TOOL_STATUS, "io", self.last_io_serial) if is_waiting else None

    def _await(self, buffer: str, part: str, serial: int, timeout: float = 2.0) -> str | None:
        """Wait until motion or iocontrol has answered command ``serial`` (not for moves:
        only for the short commands task needs the result of)."""
        channel = self.nml[buffer]
        deadline = time.monotonic() + timeout
        while True:
            self.keep_alive()  # alive while waiting; an E-stop ends the wait
            safety = self.safety
            if safety is not None and safety.board.estop_stamp() != safety.watcher.estop_seen:
                return "E-stop was requested"
            try:
                stat = channel.peek()
            except NmlError:
                stat = None  # (reported by refresh; the answer may still come)
            if (
                stat is not None
                and stat.echo_serial_number >= serial
                and stat.status
                in (
                    RCS_STATUS.DONE,
                    RCS_STATUS.ERROR,
                )
            ):
                self.refresh()
                if stat.echo_serial_number == serial and stat.status == RCS_STATUS.ERROR:
                    return f"{part} refused the command"
                return None
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return f"{part} did not answer within {timeout:g} s (is it running?)"
            channel.blocking_read(min(remaining, 0.05))

    # ================================================================ status
    def _watch_estop(self) -> None:
        """The E-stop chain: iocontrol reports emc-enable-in dropped (IO-004)."""
        if self.state != STATE.ESTOP and self.stat.io.aux.estop:
            self._abort_all()
            self._send_motion(emc.EMC_TRAJ_DISABLE())
            self._unhome_volatile_joints()
            self.state = STATE.ESTOP
            self.operator_error("E-stop: the E-stop chain opened (iocontrol.0.emc-enable-in)")

    def refresh(self) -> bool:
        """Take motion's and iocontrol's latest status into EMC_STAT (a corrupt one is
        reported and the last good one kept); True if either changed since last time."""
        motion_buffer, io_buffer = self.nml[MOTION_STATUS], self.nml[TOOL_STATUS]
        try:
            counts = (motion_buffer.write_count(), io_buffer.write_count())
            if counts == self.status_counts:
                return False
            motion = motion_buffer.peek()
            io = io_buffer.peek()
        except NmlError as exc:
            self._report_bad_buffer(str(exc))
            return False
        self.status_counts = counts
        if motion is not None:
            self.stat.motion = motion
            # the units are task's (LinuxCNC's emcTrajUpdate fills them in the same way)
            traj = self.stat.motion.traj
            traj.linearUnits = self.setup.units_per_mm
            traj.angularUnits = self.setup.angular_units
            # ... and so are the axes' limits (LinuxCNC's emcAxisUpdate, from the INI)
            for index, axis in self.setup.axes.items():
                record = self.stat.motion.axis[index]
                record.minPositionLimit, record.maxPositionLimit = axis.min_limit, axis.max_limit
            # ... and the joints' types and units (LinuxCNC's emcJointUpdate)
            for joint, record in zip(self.setup.joints, self.stat.motion.joint, strict=False):
                if joint.is_angular:
                    record.jointType, record.units = emc.EmcJointType.ANGULAR, traj.angularUnits
                else:
                    record.jointType, record.units = emc.EmcJointType.LINEAR, traj.linearUnits
        if io is not None:
            self.stat.io = io
        return True

    def publish(self) -> None:
        task = self.stat.task
        interp = self.interp
        task.mode = self.mode
        task.state = self.state
        if self.run is Run.IDLE:
            task.interpState = INTERP.IDLE
        elif self.is_paused:
            task.interpState = INTERP.PAUSED
        elif self.is_reading_done or self.is_waiting_for_synch:
            task.interpState = INTERP.WAITING
        else:
            task.interpState = INTERP.READING
        task.execState = EXEC.DONE if self._is_everything_done() else EXEC.WAITING_FOR_MOTION
        task.task_paused = self.is_paused
        # (the canon holds both switches; both start on, as LinuxCNC's)
        task.optional_stop_state = self.canon.GET_OPTIONAL_PROGRAM_STOP()
        task.block_delete_state = self.canon.GET_BLOCK_DELETE()
        task.file = emc.fit_text(self.file)
        task.callLevel = interp.call_level
        task.motionLine = self.stat.motion.traj.id
        task.currentLine = self.current_line
        task.readLine = getattr(interp, "sequence_number", 0)
        task.queuedMDIcommands = len(self.mdi_queue)
        task.delayLeft = max(0.0, self.delay_until - time.monotonic())
        g_codes, m_codes, settings = self._active_modes()
        task.activeGCodes[: len(g_codes)] = g_codes
        task.activeMCodes[: len(m_codes)] = m_codes
        task.activeSettings[: len(settings)] = settings
        task.programUnits = interp.length_units if hasattr(interp, "length_units") else 0
        task.ini_filename = emc.fit_text(self.ini.path)
        self.publish_due = time.monotonic() + PUBLISH_AT_LEAST_S
        try:
            self.nml[EMC_STATUS].write(self.stat)
        except NmlError as exc:
            log.error("cannot publish status: %s", exc)

    def _active_modes(self) -> tuple[list[int], list[int], list[float]]:
        """The active G codes, M codes and settings EMC_STAT shows: while a program runs,
        those of the move motion is carrying out (its state tag; the interpreter reads
        ahead), else, or before the first tagged move, the interpreter's (LinuxCNC's
        emcTaskUpdate)."""
        if self.run is Run.PROGRAM:
            tag = state_tag_of(self.stat.motion.traj.tag)
            if statetag.is_valid(tag):
                return statetag.active_modes(tag)
        interp = self.interp
        return interp.active_g_codes(), interp.active_m_codes(), interp.active_settings()

    # ================================================================ messages
    def operator_error(self, text: str) -> None:
        self._write_error_channel(emc.EMC_OPERATOR_ERROR(error=emc.fit_text(text)))

    def operator_text(self, text: str) -> None:
        self._write_error_channel(emc.EMC_OPERATOR_TEXT(text=emc.fit_text(text)))

    def _write_error_channel(self, msg: emc.NMLmsg) -> None:
        self.outbox.post(msg)

    # ================================================================ shutdown
    def shutdown(self) -> None:
        """Stop motion, then save what must survive a restart: parameters and the joint
        positions motion reports at rest (atomically). A failed save is told to the
        operator, on the error channel."""
        self._stop_for_shutdown()
        try:
            self.interp.exit()
            if getattr(self.interp, "save_error", None) is not None:
                self.operator_error(f"cannot save the parameters: {self.interp.save_error}")
        except InterpError as exc:
            self.operator_error(f"cannot save the parameters: {exc}")
        if self.setup.position_file:
            joints = self.stat.motion.joint  # all 16, as LinuxCNC writes them
            try:
                write_positions(self.setup.position_file, [j.output for j in joints])
            except OSError as exc:
                self.operator_error(
                    f"cannot save the joint positions to {self.setup.position_file}: {exc}"
                )
        self.outbox.flush()
        if self.safety is not None:
            self.safety.close()

    def _stop_for_shutdown(self, timeout: float = 5.0) -> None:
        """Abort and wait (at most ``timeout``) until motion is at rest, so the positions
        saved are where the machine stands, not where it was passing."""
        self._abort()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.keep_alive()
            self.refresh()
            motion = self.stat.motion
            if motion.traj.inpos and motion.traj.queue == 0 and not motion.traj.current_vel:
                return
            time.sleep(0.005)
        log.error("motion did not come to rest within %g s of the shutdown", timeout)


def _writable_dirs(ini: IniFile, setup: MachineSetup) -> list[str]:
    """Where G-code may write files ((PROBEOPEN), (LOGOPEN)): the machine's folder, its
    [DISPLAY]PROGRAM_PREFIX and the folders of [RS274NGC]WRITABLE_DIRS (colon separated,
    relative to the INI's folder). Task may run as root."""
    folders = [str(setup.folder)]
    prefix = ini.find("DISPLAY", "PROGRAM_PREFIX")
    if prefix:
        folders.append(setup.resolve(prefix))
    extra = ini.find("RS274NGC", "WRITABLE_DIRS") or ""
    folders += [setup.resolve(name) for name in extra.split(":") if name.strip()]
    return folders


# What task tells iocontrol about E-stop and aborts: nothing to do without one.
_IO_OPTIONAL = (
    emc.EMC_AUX_ESTOP_ON,
    emc.EMC_AUX_ESTOP_OFF,
    emc.EMC_AUX_ESTOP_RESET,
    emc.EMC_TOOL_ABORT,
)
