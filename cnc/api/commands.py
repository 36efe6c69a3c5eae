"""``cnc.command``: LinuxCNC's command object, sending EMC messages to task.

Each method builds the message LinuxCNC's ``linuxcnc.command`` sends (same type, same field
values) and queues it on ``emcCommand``; the buffer gives it its serial number. Like
LinuxCNC, a method then waits (up to 5 s, silently) until task has taken the command, that
is until ``EMC_STAT.echo_serial_number`` reaches its serial, so that a ``stat.poll()`` right
after it sees task handling it. ``wait_complete()`` waits for the end of the last command
sent. Both wait on the status buffer's wake-ups, never by polling.

Arguments are checked as LinuxCNC checks them: TypeError for a wrong type or number of
arguments, ValueError for an unknown constant or a text too long, OverflowError for a byte
value out of 0..255.
"""

from __future__ import annotations

import operator
import os
import time
from collections.abc import Callable
from typing import Any

from cnc.api import constants as c
from cnc.api.connection import Link
from cnc.api.errors import error
from cnc.api.safety import jog_lease, keep_alive, request_abort, request_estop
from nml import emc
from nml.channels import EMC_COMMAND, EMC_STATUS
from nml.errors import NmlError
from nml.message import RCS_CMD_MSG, RCS_STATUS

DEFAULT_TIMEOUT_S = 5.0  # wait_complete() default and the wait for task to take a command
SAFETY_SEND_S = 0.5  # how long E-stop/abort wait for the command buffer after the board
WAIT_SLICE_S = 0.1  # waits for task are cut into slices this long
TEXT_LIMIT = emc.LINELEN - 1  # bytes of an MDI command, file name or operator message
_SERIAL_MODULUS = 1 << 31  # serial numbers wrap from 0x7FFFFFFF to 1


# ------------------------------------------------------------------ argument checks
def _int(value: Any) -> int:
    """An integer argument ('i'): ints and bools, not floats."""
    return operator.index(value)


def _float(value: Any) -> float:
    """A number argument ('d')."""
    if isinstance(value, str | bytes):
        raise TypeError(f"must be a real number, not {type(value).__name__}")
    return float(value)


def _byte(value: Any) -> int:
    """An unsigned byte argument ('b'): an integer 0..255."""
    number = operator.index(value)
    if not 0 <= number <= 255:
        raise OverflowError(f"unsigned byte integer {number} is out of range 0..255")
    return number


def _text(value: Any, what: str) -> str:
    """A text argument that must fit the message, or ValueError naming ``what``."""
    if not isinstance(value, str):
        raise TypeError(f"{what} must be str, not {type(value).__name__}")
    if len(value.encode("utf-8")) > TEXT_LIMIT:
        raise ValueError(f"{what} limited to {TEXT_LIMIT} characters")
    return value


def _clipped(value: Any) -> str:
    """An operator message, cut to what fits (LinuxCNC truncates these silently)."""
    if not isinstance(value, str):
        raise TypeError(f"message must be str, not {type(value).__name__}")
    return emc.fit_text(value)


def serial_difference(echoed: int, serial: int) -> int:
    """``echoed - serial`` across the wrap of serial numbers (> 0: a later command)."""
    half = _SERIAL_MODULUS // 2
    return (echoed - serial + half) % _SERIAL_MODULUS - half


# ------------------------------------------------------------------ constant -> message
_SPINDLE_ADJUST = {
    c.SPINDLE_OFF: emc.EMC_SPINDLE_OFF,
    c.SPINDLE_INCREASE: emc.EMC_SPINDLE_INCREASE,
    c.SPINDLE_DECREASE: emc.EMC_SPINDLE_DECREASE,
    c.SPINDLE_CONSTANT: emc.EMC_SPINDLE_CONSTANT,
}
_PROGRAM_ACTIONS = {
    c.AUTO_PAUSE: emc.EMC_TASK_PLAN_PAUSE,
    c.AUTO_RESUME: emc.EMC_TASK_PLAN_RESUME,
    c.AUTO_STEP: emc.EMC_TASK_PLAN_STEP,
    c.AUTO_REVERSE: emc.EMC_TASK_PLAN_REVERSE,
    c.AUTO_FORWARD: emc.EMC_TASK_PLAN_FORWARD,
}
# jog action -> (its name, how many numbers follow the joint or axis index)
_JOG_FORMS = {
    c.JOG_STOP: ("JOG_STOP", 0),
    c.JOG_CONTINUOUS: ("JOG_CONTINUOUS", 1),
    c.JOG_INCREMENT: ("JOG_INCREMENT", 2),
}


class command:  # LinuxCNC's name: linuxcnc.command
    """Sends commands to task (``linuxcnc.command``); ``serial`` is the last one's number.

    ``command(path)`` names an NML or INI file; without it the running machine is found.
    Methods raise ``cnc.error`` if the controller is not running.
    """

    __slots__ = ("__weakref__", "_link", "_serial")

    def __init__(self, source: str | os.PathLike[str] | None = None) -> None:
        self._link = Link(source)
        self._link.close_with(self)
        self._serial = 0
        self._link.try_attach(EMC_COMMAND)
        self._link.try_attach(EMC_STATUS)

    @property
    def serial(self) -> int:
        """The serial number of the last command sent (0 before any)."""
        return self._serial

    def close(self) -> None:
        """Detach from the controller now (otherwise when the object is collected)."""
        self._link.close()

    # ------------------------------------------------------------------ sending, waiting
    def _send(self, msg: RCS_CMD_MSG) -> None:
        try:
            self._serial = self._link.buffer(EMC_COMMAND).write(msg)
            self._watch(DEFAULT_TIMEOUT_S, self._taken)
        except NmlError as exc:
            raise error(str(exc)) from None

    def _send_safety(self, msg: emc.EMC_TASK_ABORT | emc.EMC_TASK_SET_STATE) -> None:
        """E-stop and abort, already requested on the safety board (``msg.request``): the
        command follows for task's answer. If another process holds the command buffer
        (a stuck UI), the request has done its work: the command is given up after a
        short wait rather than blocking this UI; with no board, it is an error as usual."""
        if not msg.request:
            self._send(msg)
            return
        try:
            buffer = self._link.buffer(EMC_COMMAND, lock_timeout=SAFETY_SEND_S)
            self._serial = buffer.write(msg, timeout=SAFETY_SEND_S)
            self._watch(SAFETY_SEND_S, self._taken)
        except (NmlError, error):
            pass  # the board carried it; task acts on it from there

    def _taken(self, status: emc.EMC_STAT) -> int | None:
        """0 once task has taken the last command (it echoes its serial or a later one)."""
        return 0 if serial_difference(status.echo_serial_number, self._serial) >= 0 else None

    def _finished(self, status: emc.EMC_STAT) -> int | None:
        """RCS_DONE / RCS_ERROR once the last command has finished, else None."""
        difference = serial_difference(status.echo_serial_number, self._serial)
        if difference > 0:  # task has moved on to a later command
            return c.RCS_DONE
        if difference == 0 and status.status in (RCS_STATUS.DONE, RCS_STATUS.ERROR):
            return int(status.status)
        return None

    def _watch(self, timeout: float, outcome: Callable[[emc.EMC_STAT], int | None]) -> int | None:
        """Wait for a status for which ``outcome`` is not None, sleeping between status
        updates on the buffer's semaphore; None after ``timeout`` seconds."""
        status_buffer = self._link.buffer(EMC_STATUS)
        deadline = time.monotonic() + timeout
        latest = status_buffer.read() or status_buffer.peek()
        while True:
            if type(latest) is emc.EMC_STAT:
                result = outcome(latest)
                if result is not None:
                    return result
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            keep_alive()  # (halui: its heartbeat, while it waits)
            latest = status_buffer.blocking_read(min(remaining, WAIT_SLICE_S))

    def wait_complete(self, timeout: float = DEFAULT_TIMEOUT_S) -> int:
        """Wait for the last command to finish: RCS_DONE, RCS_ERROR, or -1 after ``timeout``."""
        timeout = _float(timeout)
        try:
            result = self._watch(timeout, self._finished)
        except NmlError as exc:
            raise error(str(exc)) from None
        return -1 if result is None else result

    # ------------------------------------------------------------------ machine and task
    def state(self, state: int, request: int = 0) -> None:
        """STATE_ESTOP, STATE_ESTOP_RESET, STATE_ON or STATE_OFF. ``request``: the stamp of
        the E-stop this process put on the safety board already (``cnc.api.safety``), so
        that task acts on it once."""
        state = _int(state)
        if state not in (c.STATE_ESTOP, c.STATE_ESTOP_RESET, c.STATE_ON, c.STATE_OFF):
            raise ValueError(
                "Machine state should be STATE_ESTOP, STATE_ESTOP_RESET, STATE_ON, or STATE_OFF"
            )
        if state == c.STATE_ESTOP:  # first through the path no lock can block
            stamp = _int(request) or request_estop()
            self._send_safety(emc.EMC_TASK_SET_STATE(state=state, request=stamp))
            return
        self._send(emc.EMC_TASK_SET_STATE(state=state))

    def mode(self, mode: int) -> None:
        """MODE_MDI, MODE_MANUAL or MODE_AUTO."""
        mode = _int(mode)
        if mode not in (c.MODE_MDI, c.MODE_MANUAL, c.MODE_AUTO):
            raise ValueError("Mode should be MODE_MDI, MODE_MANUAL, or MODE_AUTO")
        self._send(emc.EMC_TASK_SET_MODE(mode=mode))

    def mdi(self, command: str) -> None:
        """Execute one line of G-code (MDI mode)."""
        self._send(emc.EMC_TASK_PLAN_EXECUTE(command=_text(command, "MDI commands")))

    def program_open(self, filename: str) -> None:
        """Close the open program, then open ``filename``."""
        filename = _text(filename, "File name")
        self._send(emc.EMC_TASK_PLAN_CLOSE())
        self._send(emc.EMC_TASK_PLAN_OPEN(file=filename))

    def auto(self, action: int, line: int | None = None) -> None:
        """auto(AUTO_RUN, start_line), or auto(AUTO_PAUSE / RESUME / STEP / REVERSE / FORWARD)."""
        action = _int(action)
        if line is not None:
            if action != c.AUTO_RUN:
                raise TypeError("auto() takes a line number only with AUTO_RUN")
            self._send(emc.EMC_TASK_PLAN_RUN(line=_int(line)))
            return
        message = _PROGRAM_ACTIONS.get(action)
        if message is None:
            raise error(f"Unexpected argument '{action}' to command.auto")
        self._send(message())

    def abort(self, request: int = 0) -> None:
        """Abort. ``request``: the stamp of the abort this process put on the safety board
        already (``cnc.api.safety``), so that task acts on it once."""
        self._send_safety(emc.EMC_TASK_ABORT(request=_int(request) or request_abort()))

    def reset_interpreter(self) -> None:
        self._send(emc.EMC_TASK_PLAN_INIT())

    def task_plan_synch(self) -> None:
        """Have the interpreter write its parameters to the .var file."""
        self._send(emc.EMC_TASK_PLAN_SYNCH())

    def set_optional_stop(self, state: int) -> None:
        self._send(emc.EMC_TASK_PLAN_SET_OPTIONAL_STOP(state=bool(_int(state))))

    def set_block_delete(self, state: int) -> None:
        self._send(emc.EMC_TASK_PLAN_SET_BLOCK_DELETE(state=bool(_int(state))))

    def debug(self, level: int) -> None:
        """Set the DEBUG_* bits."""
        self._send(emc.EMC_SET_DEBUG(debug=_int(level)))

    # ------------------------------------------------------------------ joints, jogging
    def home(self, joint: int) -> None:
        """Home a joint; -1 homes every joint in sequence."""
        self._send(emc.EMC_JOINT_HOME(joint=_int(joint)))

    def unhome(self, joint: int) -> None:
        self._send(emc.EMC_JOINT_UNHOME(joint=_int(joint)))

    def override_limits(self) -> None:
        self._send(emc.EMC_JOINT_OVERRIDE_LIMITS(joint=0))

    def set_min_limit(self, joint: int, limit: float) -> None:
        self._send(emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=_int(joint), limit=_float(limit)))

    def set_max_limit(self, joint: int, limit: float) -> None:
        self._send(emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=_int(joint), limit=_float(limit)))

    def jog(self, action: int, jjogmode: int, index: int, *speed_and_increment: float) -> None:
        """jog(JOG_STOP, joint_flag, index), jog(JOG_CONTINUOUS, joint_flag, index, speed),
        jog(JOG_INCREMENT, joint_flag, index, speed, increment).

        ``joint_flag`` true jogs joint ``index``, false jogs axis ``index`` (0..8 = XYZABCUVW).
        """
        action, jjogmode, index = _int(action), _int(jjogmode), _int(index)
        values = [_float(value) for value in speed_and_increment]
        form = _JOG_FORMS.get(action)
        if form is None:
            raise TypeError("jog() first argument must be JOG_xxx")
        name, expected = form
        if len(values) != expected:
            raise TypeError(
                f"jog({name}, ...) takes {3 + expected} arguments ({3 + len(values)} given)"
            )
        if action == c.JOG_STOP:
            self._send(emc.EMC_JOG_STOP(joint_or_axis=index, jjogmode=jjogmode))
        elif action == c.JOG_CONTINUOUS:  # leased: it stops if this process goes quiet
            slot, pid = jog_lease()
            self._send(
                emc.EMC_JOG_CONT(
                    joint_or_axis=index,
                    vel=values[0],
                    jjogmode=jjogmode,
                    lease_slot=slot,
                    lease_pid=pid,
                )
            )
        else:
            self._send(
                emc.EMC_JOG_INCR(
                    joint_or_axis=index, vel=values[0], incr=values[1], jjogmode=jjogmode
                )
            )

    # ------------------------------------------------------------------ trajectory
    def teleop_enable(self, enable: int) -> None:
        self._send(emc.EMC_TRAJ_SET_TELEOP_ENABLE(enable=_int(enable)))

    def teleop_vector(
        self, x: float, y: float, z: float, a: float = 0.0, b: float = 0.0, c: float = 0.0
    ) -> None:
        """Teleop mode: move at this cartesian velocity, per axis in machine units per
        second (LinuxCNC 2.7's; all zero stops). Joint and axis limits slow it as a whole."""
        message = emc.EMC_TRAJ_SET_TELEOP_VECTOR()
        vector = message.vector
        vector.tran.x, vector.tran.y, vector.tran.z = _float(x), _float(y), _float(z)
        vector.a, vector.b, vector.c = _float(a), _float(b), _float(c)
        self._send(message)

    def traj_mode(self, mode: int) -> None:
        """TRAJ_MODE_FREE, TRAJ_MODE_COORD or TRAJ_MODE_TELEOP."""
        self._send(emc.EMC_TRAJ_SET_MODE(mode=_int(mode)))

    def feedrate(self, scale: float) -> None:
        """Feed override, 1.0 = 100 %."""
        self._send(emc.EMC_TRAJ_SET_SCALE(scale=_float(scale)))

    def rapidrate(self, scale: float) -> None:
        """Rapid override, 1.0 = 100 %."""
        self._send(emc.EMC_TRAJ_SET_RAPID_SCALE(scale=_float(scale)))

    def maxvel(self, velocity: float) -> None:
        self._send(emc.EMC_TRAJ_SET_MAX_VELOCITY(velocity=_float(velocity)))

    def spindleoverride(self, scale: float, spindle: int = 0) -> None:
        self._send(emc.EMC_TRAJ_SET_SPINDLE_SCALE(scale=_float(scale), spindle=_int(spindle)))

    def set_feed_override(self, enable: int) -> None:
        self._send(emc.EMC_TRAJ_SET_FO_ENABLE(mode=_byte(enable)))

    def set_spindle_override(self, enable: int, spindle: int = 0) -> None:
        self._send(emc.EMC_TRAJ_SET_SO_ENABLE(mode=_byte(enable), spindle=_int(spindle)))

    def set_feed_hold(self, enable: int) -> None:
        self._send(emc.EMC_TRAJ_SET_FH_ENABLE(mode=_byte(enable)))

    def set_adaptive_feed(self, enable: int) -> None:
        self._send(emc.EMC_MOTION_ADAPTIVE(status=_byte(enable)))

    def set_digital_output(self, index: int, value: int) -> None:
        """Set motion's digital output ``index`` now (as M62..M65 do)."""
        self._send(emc.EMC_MOTION_SET_DOUT(index=_byte(index), start=_byte(value), now=1))

    def set_analog_output(self, index: int, value: float) -> None:
        """Set motion's analog output ``index`` now (as M67/M68 do)."""
        self._send(emc.EMC_MOTION_SET_AOUT(index=_byte(index), start=_float(value), now=1))

    # ------------------------------------------------------------------ spindle, coolant
    def spindle(
        self,
        direction: int,
        speed_or_spindle: float = 0.0,
        spindle: float = 0.0,
        wait_for_speed: int = 0,
        /,
    ) -> None:
        """spindle(SPINDLE_FORWARD / SPINDLE_REVERSE, speed=0, spindle=0, wait_for_speed=0),
        spindle(SPINDLE_OFF / INCREASE / DECREASE / CONSTANT, spindle=0)."""
        direction = _int(direction)
        first, second, wait = _float(speed_or_spindle), _float(spindle), _int(wait_for_speed)
        if direction in (c.SPINDLE_FORWARD, c.SPINDLE_REVERSE):
            self._send(
                emc.EMC_SPINDLE_ON(
                    speed=direction * first, spindle=int(second), wait_for_spindle_at_speed=wait
                )
            )
            return
        message = _SPINDLE_ADJUST.get(direction)
        if message is None:
            raise ValueError(
                "Spindle direction should be SPINDLE_FORWARD, SPINDLE_REVERSE, SPINDLE_OFF, "
                "SPINDLE_INCREASE, SPINDLE_DECREASE, or SPINDLE_CONSTANT"
            )
        self._send(message(spindle=int(first)))

    def brake(self, action: int, spindle: int = 0) -> None:
        """BRAKE_ENGAGE or BRAKE_RELEASE."""
        action, spindle = _int(action), _int(spindle)
        if action == c.BRAKE_ENGAGE:
            self._send(emc.EMC_SPINDLE_BRAKE_ENGAGE(spindle=spindle))
        elif action == c.BRAKE_RELEASE:
            self._send(emc.EMC_SPINDLE_BRAKE_RELEASE(spindle=spindle))
        else:
            raise ValueError("BRAKE should be BRAKE_ENGAGE or BRAKE_RELEASE")

    def flood(self, action: int) -> None:
        """FLOOD_ON or FLOOD_OFF."""
        action = _int(action)
        if action not in (c.FLOOD_ON, c.FLOOD_OFF):
            raise ValueError("FLOOD should be FLOOD_ON or FLOOD_OFF")
        on = action == c.FLOOD_ON
        self._send(emc.EMC_COOLANT_FLOOD_ON() if on else emc.EMC_COOLANT_FLOOD_OFF())

    def mist(self, action: int) -> None:
        """MIST_ON or MIST_OFF."""
        action = _int(action)
        if action not in (c.MIST_ON, c.MIST_OFF):
            raise ValueError("Mist should be MIST_ON or MIST_OFF")
        on = action == c.MIST_ON
        self._send(emc.EMC_COOLANT_MIST_ON() if on else emc.EMC_COOLANT_MIST_OFF())

    # ------------------------------------------------------------------ tools
    def tool_offset(
        self,
        toolno: int,
        z_offset: float,
        x_offset: float,
        diameter: float,
        frontangle: float,
        backangle: float,
        orientation: int,
    ) -> None:
        """Set a tool's Z and X offsets, diameter, angles and orientation (lathe tools)."""
        message = emc.EMC_TOOL_SET_OFFSET(
            toolno=_int(toolno),
            diameter=_float(diameter),
            frontangle=_float(frontangle),
            backangle=_float(backangle),
            orientation=_int(orientation),
        )
        message.offset.tran.z = _float(z_offset)
        message.offset.tran.x = _float(x_offset)
        self._send(message)

    def load_tool_table(self) -> None:
        """Reload the tool table file named in the INI file."""
        self._send(emc.EMC_TOOL_LOAD_TOOL_TABLE(file=""))

    # ------------------------------------------------------------------ operator messages
    def error_msg(self, text: str) -> None:
        """Show an error to the operator (on every error channel)."""
        self._send(emc.EMC_OPERATOR_ERROR(id=0, error=_clipped(text)))

    def text_msg(self, text: str) -> None:
        self._send(emc.EMC_OPERATOR_TEXT(id=0, text=_clipped(text)))

    def display_msg(self, text: str) -> None:
        self._send(emc.EMC_OPERATOR_DISPLAY(id=0, display=_clipped(text)))
