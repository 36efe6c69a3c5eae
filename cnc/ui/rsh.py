"""``cnc rsh``: LinuxCNC's remote shell (``linuxcncrsh``), a TCP server for pendants and scripts.

    cnc rsh [--port 5007] [--name EMCNETSVR] [--connectpw EMC] [--enablepw EMCTOO]
            [--sessions -1] [--path DIR] [-- -ini FILE.ini]

It speaks linuxcncrsh's line protocol, command for command and reply for reply, on top of
the Python API (``import cnc as linuxcnc``). A client says ``hello <connectpw> <name>
<version>`` (answer ``HELLO ACK <server name> 1.1`` or ``HELLO NAK``), takes control with
``set enable <enablepw>`` (one connection at a time), then:

- ``get <item> [args]`` answers one line, ``<ITEM> <value...>``, or ``GET <ITEM> NAK``;
  it works before ``hello`` too;
- ``set <item> <args>`` answers nothing when it worked (``SET <ITEM> ACK`` with ``set
  verbose on``) and ``SET <ITEM> NAK`` when it did not: unknown item, bad argument, the
  connection not enabled (every item from ``inifile`` on needs it), the machine not on
  (every item after ``machine`` needs it), or the controller refusing the command;
- ``set set_wait done`` makes each command wait until the controller has finished it
  (``received``, the default: until it has taken it); ``set timeout S`` bounds the wait
  (0: none); ``set wait done|received`` waits for the last command;
- ``quit`` closes the connection, ``shutdown`` (enabled connection only) stops the server,
  which, as the machine's display, stops the machine; ``help [command]`` explains.

Items: echo verbose enable config comm_mode comm_prot inifile plat ini debug set_wait wait
timeout update error operator_display operator_text time estop machine mode mist flood
lube lube_level spindle brake tool tool_offset load_tool_table home jog_stop jog jog_incr
feed_override abs_cmd_pos abs_act_pos rel_cmd_pos rel_act_pos joint_pos pos_offset
joint_limit joint_fault joint_homed mdi task_plan_init open run pause resume step abort
program program_line program_status program_codes joint_type joint_units program_units
program_linear_units program_angular_units user_linear_units user_angular_units
display_linear_units display_angular_units linear_unit_conversion angular_unit_conversion
probe_clear probe_tripped probe_value probe teleop_enable kinematics_type override_limits
spindle_override optional_stop. Words are not case sensitive; passwords, file names and
MDI text are. Input is echoed back once ``hello`` succeeded (``set echo off`` stops it).
LinuxCNC's replies keep their quirks: ``SET`` replies end in ``\\n\\r``, a ``GET ... NAK``
in two ``\\r\\n``; ``get ini``, ``get wait``, ``get update``, ``get probe`` and ``get
probe_clear`` repeat the connection's previous reply; ``set debug`` and ``set comm_prot``
take their value from the second word after the item.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import socketserver
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cnc
from cnc.api import constants as c
from nml.axes import AXIS_LETTERS

DEFAULT_PORT = 5007
SERVER_VERSION = "1.1"
# LinuxCNC's order matters: from INIFILE on a set needs the enabled connection, after
# MACHINE the machine must be on
ITEMS = [
    "ECHO",
    "VERBOSE",
    "ENABLE",
    "CONFIG",
    "COMM_MODE",
    "COMM_PROT",
    "INIFILE",
    "PLAT",
    "INI",
    "DEBUG",
    "SET_WAIT",
    "WAIT",
    "TIMEOUT",
    "UPDATE",
    "ERROR",
    "OPERATOR_DISPLAY",
    "OPERATOR_TEXT",
    "TIME",
    "ESTOP",
    "MACHINE",
    "MODE",
    "MIST",
    "FLOOD",
    "LUBE",
    "LUBE_LEVEL",
    "SPINDLE",
    "BRAKE",
    "TOOL",
    "TOOL_OFFSET",
    "LOAD_TOOL_TABLE",
    "HOME",
    "JOG_STOP",
    "JOG",
    "JOG_INCR",
    "FEED_OVERRIDE",
    "ABS_CMD_POS",
    "ABS_ACT_POS",
    "REL_CMD_POS",
    "REL_ACT_POS",
    "JOINT_POS",
    "POS_OFFSET",
    "JOINT_LIMIT",
    "JOINT_FAULT",
    "JOINT_HOMED",
    "MDI",
    "TASK_PLAN_INIT",
    "OPEN",
    "RUN",
    "PAUSE",
    "RESUME",
    "STEP",
    "ABORT",
    "PROGRAM",
    "PROGRAM_LINE",
    "PROGRAM_STATUS",
    "PROGRAM_CODES",
    "JOINT_TYPE",
    "JOINT_UNITS",
    "PROGRAM_UNITS",
    "PROGRAM_LINEAR_UNITS",
    "PROGRAM_ANGULAR_UNITS",
    "USER_LINEAR_UNITS",
    "USER_ANGULAR_UNITS",
    "DISPLAY_LINEAR_UNITS",
    "DISPLAY_ANGULAR_UNITS",
    "LINEAR_UNIT_CONVERSION",
    "ANGULAR_UNIT_CONVERSION",
    "PROBE_CLEAR",
    "PROBE_TRIPPED",
    "PROBE_VALUE",
    "PROBE",
    "TELEOP_ENABLE",
    "KINEMATICS_TYPE",
    "OVERRIDE_LIMITS",
    "SPINDLE_OVERRIDE",
    "OPTIONAL_STOP",
]
NEEDS_ENABLE_FROM = ITEMS.index("INIFILE")
NEEDS_MACHINE_ON_AFTER = ITEMS.index("MACHINE")
LINEAR_UNITS = {"INCH": 1 / 25.4, "MM": 1.0, "CM": 0.1}  # user units per mm
ANGULAR_UNITS = {"DEG": 1.0, "RAD": math.pi / 180, "GRAD": 100 / 90}  # per degree
CANON_UNITS = {1: "INCH", 2: "MM", 3: "CM"}  # task.program_units
NO_REPLY = None  # a handler's result when nothing is to be written


class FailedError(Exception):
    """A set or get that answers ``NAK``."""


class Session:
    """What one connection knows about itself (linuxcncrsh's connection record)."""

    def __init__(self) -> None:
        self.is_linked = False  # hello succeeded
        self.is_echo = True
        self.is_verbose = False
        self.comm_mode = "ASCII"
        self.version = "1.0"
        self.client = "Default"
        self.reply = ""  # the last reply, which some gets repeat


class RemoteShell:
    """The state all connections share, and the commands."""

    def __init__(self, ini: str | None, options: argparse.Namespace) -> None:
        self.ini = ini
        self.connect_password = options.connectpw
        self.enable_password = options.enablepw
        self.server_name = options.name
        self.program_path = options.path
        self.enabled: Session | None = None
        self.wait_for = "RECEIVED"
        self.timeout = 0.0
        self.is_auto_update = True
        self.linear_conversion = "AUTO"
        self.angular_conversion = "AUTO"
        self.program_start_line = 0
        self.last_program = ""
        self.messages = {"ERROR": "", "OPERATOR_TEXT": "", "OPERATOR_DISPLAY": ""}
        self.lock = threading.Lock()  # one command at a time, as task takes them
        self.stat = cnc.stat(ini)
        self.command = cnc.command(ini)
        self.errors = cnc.error_channel(ini)
        self.on_shutdown: Callable[[], None] = lambda: None

    # ------------------------------------------------------------ one line
    def handle(self, session: Session, line: str) -> str | None:
        """The reply to one line (with its line ending), or None for no reply; raises
        EOFError for quit and SystemExit for shutdown."""
        words = _words(line)
        if not words:
            return NO_REPLY
        verb = words[0].upper()
        if verb == "HELLO":
            return self._hello(session, words[1:])
        if verb == "GET":
            return self._get(session, line, words[1:])
        if verb == "SET":
            if not session.is_linked:
                return "SET NAK\r\n"
            with self.lock:
                return self._set(session, line, words[1:])
        if verb == "QUIT":
            raise EOFError
        if verb == "SHUTDOWN":
            if self.enabled is session:
                raise SystemExit(0)
            return "SHUTDOWN NAK\r\n"
        if verb == "HELP":
            return self._help(words[1:])
        return NO_REPLY

    def _hello(self, session: Session, args: list[str]) -> str:
        if len(args) < 3 or args[0] != self.connect_password or len(args[2]) >= 8:
            return "HELLO NAK\r\n"
        session.client, session.version, session.is_linked = args[1], args[2], True
        print(f"Connected to {session.client}", flush=True)
        return f"HELLO ACK {self.server_name} {SERVER_VERSION}\r\n"

    # ------------------------------------------------------------ set
    def _set(self, session: Session, line: str, args: list[str]) -> str | None:
        if not args:
            return "SET NAK\n\r"
        item = args[0].upper()
        index = ITEMS.index(item) if item in ITEMS else len(ITEMS)
        nak = f"SET {item} NAK\n\r"
        if index >= NEEDS_ENABLE_FROM and self.enabled is not session:
            return nak
        if index > NEEDS_MACHINE_ON_AFTER:
            self.stat.poll()
            if self.stat.task_state != c.STATE_ON:
                return nak
        handler = getattr(self, f"set_{item.lower()}", None)
        try:
            if handler is None:
                raise FailedError
            handler(session, args[1:], _rest_of_line(line, 2))
        except (FailedError, cnc.error, ValueError, IndexError):
            return nak
        return f"SET {item} ACK\n\r" if session.is_verbose else NO_REPLY

    def _send(self, send: Callable[[], Any]) -> None:
        """Send one command, then wait as set_wait says; FailedError if it was refused."""
        send()
        if self.wait_for == "DONE":
            timeout = self.timeout if self.timeout > 0 else 1e9
            if self.command.wait_complete(timeout) != c.RCS_DONE:
                raise FailedError

    def _send_message(self, message: Any) -> None:
        """A message the Python API has no method for (lube, probe, load tool table)."""
        self._send(lambda: self.command._send(message))

    def set_echo(self, session: Session, args: list[str], rest: str) -> None:
        session.is_echo = _on_off(args)

    def set_verbose(self, session: Session, args: list[str], rest: str) -> None:
        session.is_verbose = _on_off(args)

    def set_enable(self, session: Session, args: list[str], rest: str) -> None:
        if args and args[0] == self.enable_password:
            self.enabled = session
        elif not _on_off(args):
            if self.enabled is session:
                self.enabled = None
        else:
            raise FailedError

    def set_config(self, session: Session, args: list[str], rest: str) -> None:
        pass

    def set_comm_mode(self, session: Session, args: list[str], rest: str) -> None:
        mode = args[0].upper() if args else ""
        if mode not in ("ASCII", "BINARY"):
            raise FailedError
        session.comm_mode = mode

    def set_comm_prot(self, session: Session, args: list[str], rest: str) -> None:
        session.version = args[1]  # (sic) the word after the value, as linuxcncrsh reads it

    def set_inifile(self, session: Session, args: list[str], rest: str) -> None:
        pass

    set_plat = set_ini = set_inifile

    def set_debug(self, session: Session, args: list[str], rest: str) -> None:
        level = int(args[1], 0)  # (sic) the second word, as linuxcncrsh reads it
        self._send(lambda: self.command.debug(level))

    def set_set_wait(self, session: Session, args: list[str], rest: str) -> None:
        wait = args[0].upper() if args else ""
        if wait == "NONE":
            print(
                "linuxcncrsh: 'set set_wait' asked for 'none', but that setting has been "
                "removed as it may cause commands to be lost",
                file=sys.stderr,
            )
        if wait not in ("RECEIVED", "DONE"):
            raise FailedError
        self.wait_for = wait

    def set_wait(self, session: Session, args: list[str], rest: str) -> None:
        wait = args[0].upper() if args else ""
        if wait == "DONE":
            timeout = self.timeout if self.timeout > 0 else 1e9
            if self.command.wait_complete(timeout) != c.RCS_DONE:
                raise FailedError
        elif wait != "RECEIVED":
            raise FailedError

    def set_timeout(self, session: Session, args: list[str], rest: str) -> None:
        self.timeout = float(args[0])

    def set_update(self, session: Session, args: list[str], rest: str) -> None:
        word = args[0].upper() if args else ""
        if word not in ("NONE", "AUTO"):
            raise FailedError
        self.is_auto_update = word == "AUTO"

    def set_estop(self, session: Session, args: list[str], rest: str) -> None:
        state = c.STATE_ESTOP if _on_off(args) else c.STATE_ESTOP_RESET
        self._send(lambda: self.command.state(state))

    def set_machine(self, session: Session, args: list[str], rest: str) -> None:
        state = c.STATE_ON if _on_off(args) else c.STATE_OFF
        self._send(lambda: self.command.state(state))

    def set_mode(self, session: Session, args: list[str], rest: str) -> None:
        modes = {"MANUAL": c.MODE_MANUAL, "AUTO": c.MODE_AUTO, "MDI": c.MODE_MDI}
        mode = modes.get(args[0].upper() if args else "")
        if mode is None:
            raise FailedError
        self._send(lambda: self.command.mode(mode))

    def set_mist(self, session: Session, args: list[str], rest: str) -> None:
        action = c.MIST_ON if _on_off(args) else c.MIST_OFF
        self._send(lambda: self.command.mist(action))

    def set_flood(self, session: Session, args: list[str], rest: str) -> None:
        action = c.FLOOD_ON if _on_off(args) else c.FLOOD_OFF
        self._send(lambda: self.command.flood(action))

    def set_lube(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        self._send_message(emc.EMC_LUBE_ON() if _on_off(args) else emc.EMC_LUBE_OFF())

    def set_spindle(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        spindles, args = self._spindle_numbers(args)
        word = args[0].upper() if args else ""
        self.stat.poll()
        speed = abs(self.stat.settings[2]) or 500.0  # the program's S word, else 500 rpm
        for spindle in spindles:
            messages = {
                "FORWARD": lambda n=spindle: emc.EMC_SPINDLE_ON(spindle=n, speed=speed),
                "REVERSE": lambda n=spindle: emc.EMC_SPINDLE_ON(spindle=n, speed=-speed),
                "INCREASE": lambda n=spindle: emc.EMC_SPINDLE_INCREASE(spindle=n),
                "DECREASE": lambda n=spindle: emc.EMC_SPINDLE_DECREASE(spindle=n),
                "CONSTANT": lambda n=spindle: emc.EMC_SPINDLE_CONSTANT(spindle=n),
                "OFF": lambda n=spindle: emc.EMC_SPINDLE_OFF(spindle=n),
            }
            if word not in messages:
                raise FailedError
            self._send_message(messages[word]())

    def set_brake(self, session: Session, args: list[str], rest: str) -> None:
        spindles, args = self._spindle_numbers(args)
        action = c.BRAKE_ENGAGE if _on_off(args) else c.BRAKE_RELEASE
        for spindle in spindles:
            self._send(lambda n=spindle: self.command.brake(action, n))

    def _spindle_numbers(self, args: list[str]) -> tuple[list[int], list[str]]:
        """An optional spindle number first; without one, every spindle."""
        if args and _is_int(args[0]):
            return [int(args[0])], args[1:]
        self.stat.poll()
        return list(range(max(1, self.stat.spindles))), args

    def set_tool_offset(self, session: Session, args: list[str], rest: str) -> None:
        tool, length, diameter = int(args[0]), float(args[1]), float(args[2])
        self._send(lambda: self.command.tool_offset(tool, length, 0.0, diameter, 0.0, 0.0, 0))

    def set_load_tool_table(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        self._send_message(emc.EMC_TOOL_LOAD_TOOL_TABLE(file=args[0]))

    def set_home(self, session: Session, args: list[str], rest: str) -> None:
        joint = int(args[0])
        if joint < -1:
            raise FailedError
        self._send(lambda: self.command.home(joint))

    def set_jog_stop(self, session: Session, args: list[str], rest: str) -> None:
        is_joint, index = _joint_or_axis(args[0])
        self._send(lambda: self.command.jog(c.JOG_STOP, is_joint, index))

    def set_jog(self, session: Session, args: list[str], rest: str) -> None:
        is_joint, index = _joint_or_axis(args[0])
        speed = float(args[1])
        self._send(lambda: self.command.jog(c.JOG_CONTINUOUS, is_joint, index, speed))

    def set_jog_incr(self, session: Session, args: list[str], rest: str) -> None:
        is_joint, index = _joint_or_axis(args[0])
        speed, increment = float(args[1]), float(args[2])
        self._send(lambda: self.command.jog(c.JOG_INCREMENT, is_joint, index, speed, increment))

    def set_feed_override(self, session: Session, args: list[str], rest: str) -> None:
        percent = int(float(args[0]))
        self._send(lambda: self.command.feedrate(percent / 100.0))

    def set_spindle_override(self, session: Session, args: list[str], rest: str) -> None:
        if len(args) >= 2:
            spindles, percent = [int(args[0])], int(args[1])
        else:
            self.stat.poll()
            spindles, percent = list(range(max(1, self.stat.spindles))), int(args[0])
        for spindle in spindles:
            self._send(lambda n=spindle: self.command.spindleoverride(percent / 100.0, n))

    def set_mdi(self, session: Session, args: list[str], rest: str) -> None:
        self._send(lambda: self.command.mdi(rest))

    def set_task_plan_init(self, session: Session, args: list[str], rest: str) -> None:
        self._send(self.command.reset_interpreter)

    def set_open(self, session: Session, args: list[str], rest: str) -> None:
        if not rest:
            raise FailedError
        self.last_program = rest
        self._send(lambda: self.command.program_open(rest))

    def set_run(self, session: Session, args: list[str], rest: str) -> None:
        line = int(args[0]) if args else 0
        self.stat.poll()
        if not self.stat.file and self.last_program:  # reopen the last program
            self._send(lambda: self.command.program_open(self.last_program))
        self.program_start_line = line
        self._send(lambda: self.command.auto(c.AUTO_RUN, line))

    def set_pause(self, session: Session, args: list[str], rest: str) -> None:
        self._send(lambda: self.command.auto(c.AUTO_PAUSE))

    def set_resume(self, session: Session, args: list[str], rest: str) -> None:
        self._send(lambda: self.command.auto(c.AUTO_RESUME))

    def set_step(self, session: Session, args: list[str], rest: str) -> None:
        self._send(lambda: self.command.auto(c.AUTO_STEP))

    def set_abort(self, session: Session, args: list[str], rest: str) -> None:
        self._send(self.command.abort)

    def set_linear_unit_conversion(self, session: Session, args: list[str], rest: str) -> None:
        word = args[0].upper() if args else ""
        if word not in (*LINEAR_UNITS, "AUTO", "CUSTOM"):
            raise FailedError
        self.linear_conversion = word

    def set_angular_unit_conversion(self, session: Session, args: list[str], rest: str) -> None:
        word = args[0].upper() if args else ""
        if word not in (*ANGULAR_UNITS, "AUTO", "CUSTOM"):
            raise FailedError
        self.angular_conversion = word

    def set_probe_clear(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        self._send_message(emc.EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG())

    def set_probe(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        x, y, z = (float(word) for word in args[:3])
        message = emc.EMC_TRAJ_PROBE()
        message.pos.tran.x, message.pos.tran.y, message.pos.tran.z = x, y, z
        self._send_message(message)

    def set_teleop_enable(self, session: Session, args: list[str], rest: str) -> None:
        enable = 1 if _on_off(args) else 0
        self._send(lambda: self.command.teleop_enable(enable))

    def set_override_limits(self, session: Session, args: list[str], rest: str) -> None:
        from nml import emc

        joint = 0 if _on_off(args) else -1
        self._send_message(emc.EMC_JOINT_OVERRIDE_LIMITS(joint=joint))

    def set_optional_stop(self, session: Session, args: list[str], rest: str) -> None:
        state = int(args[0])
        self._send(lambda: self.command.set_optional_stop(state))

    # ------------------------------------------------------------ get
    def _get(self, session: Session, line: str, args: list[str]) -> str:
        if not args:
            return "GET NAK\r\n"
        item = args[0].upper()
        if self.is_auto_update:
            self.stat.poll()
        if item in ("INI", "WAIT", "UPDATE", "PROBE_CLEAR", "PROBE"):
            return f"{session.reply}\r\n"  # linuxcncrsh leaves its buffer as it was
        handler = getattr(self, f"get_{item.lower()}", None)
        try:
            if handler is None:
                raise FailedError
            session.reply = handler(session, args[1:])
        except (FailedError, cnc.error, ValueError, IndexError):
            session.reply = f"GET {item} NAK\r\n"
        return f"{session.reply}\r\n"

    def get_echo(self, session: Session, args: list[str]) -> str:
        return f"ECHO {_word(session.is_echo)}"

    def get_verbose(self, session: Session, args: list[str]) -> str:
        return f"VERBOSE {_word(session.is_verbose)}"

    def get_enable(self, session: Session, args: list[str]) -> str:
        return f"ENABLE {_word(self.enabled is session)}"

    def get_config(self, session: Session, args: list[str]) -> str:
        return "CONFIG"

    def get_comm_mode(self, session: Session, args: list[str]) -> str:
        return f"COMM_MODE {session.comm_mode}"

    def get_comm_prot(self, session: Session, args: list[str]) -> str:
        return f"COMM_PROT {session.version}"

    def get_inifile(self, session: Session, args: list[str]) -> str:
        return f"INIFILE {self.ini or ''}"

    def get_plat(self, session: Session, args: list[str]) -> str:
        return "PLAT Linux"

    def get_debug(self, session: Session, args: list[str]) -> str:
        return f"DEBUG {self.stat.debug}"

    def get_set_wait(self, session: Session, args: list[str]) -> str:
        return f"SET_WAIT {self.wait_for}"

    def get_timeout(self, session: Session, args: list[str]) -> str:
        return f"SET_TIMEOUT {self.timeout:f}"

    def get_error(self, session: Session, args: list[str]) -> str:
        return self._message("ERROR")

    def get_operator_display(self, session: Session, args: list[str]) -> str:
        return self._message("OPERATOR_DISPLAY")

    def get_operator_text(self, session: Session, args: list[str]) -> str:
        return self._message("OPERATOR_TEXT")

    def _message(self, kind: str) -> str:
        """The latest message of a kind ("OK" before any); one new message is read per
        call, as linuxcncrsh does."""
        kinds = {c.OPERATOR_ERROR: "ERROR", c.NML_ERROR: "ERROR", c.OPERATOR_TEXT:
                 "OPERATOR_TEXT", c.NML_TEXT: "OPERATOR_TEXT", c.OPERATOR_DISPLAY:
                 "OPERATOR_DISPLAY", c.NML_DISPLAY: "OPERATOR_DISPLAY"}  # fmt: skip
        with self.lock:
            received = self.errors.poll()
            if received is not None and received[0] in kinds:
                self.messages[kinds[received[0]]] = received[1]
            return f"{kind} {self.messages[kind] or 'OK'}"

    def get_time(self, session: Session, args: list[str]) -> str:
        return f"TIME {time.time():f}"

    def get_estop(self, session: Session, args: list[str]) -> str:
        return f"ESTOP {_word(self.stat.task_state == c.STATE_ESTOP)}"

    def get_machine(self, session: Session, args: list[str]) -> str:
        return f"MACHINE {_word(self.stat.task_state == c.STATE_ON)}"

    def get_mode(self, session: Session, args: list[str]) -> str:
        modes = {c.MODE_MANUAL: "MANUAL", c.MODE_AUTO: "AUTO", c.MODE_MDI: "MDI"}
        return f"MODE {modes.get(self.stat.task_mode, '?')}"

    def get_mist(self, session: Session, args: list[str]) -> str:
        return f"MIST {_word(self.stat.mist == 1)}"

    def get_flood(self, session: Session, args: list[str]) -> str:
        return f"FLOOD {_word(self.stat.flood == 1)}"

    def get_lube(self, session: Session, args: list[str]) -> str:
        return f"LUBE {_word(self.stat.lube != 0)}"

    def get_lube_level(self, session: Session, args: list[str]) -> str:
        return f"LUBE_LEVEL {'OK' if self.stat.lube_level else 'LOW'}"

    def get_spindle(self, session: Session, args: list[str]) -> str:
        spindle = self._spindle_index(args)
        direction = self.stat.spindle[spindle]["direction"]
        state = "FORWARD" if direction > 0 else "REVERSE" if direction < 0 else "OFF"
        return f"SPINDLE {spindle} {state}"

    def get_brake(self, session: Session, args: list[str]) -> str:
        return f"BRAKE {_word(self.stat.spindle[self._spindle_index(args)]['brake'] == 1)}"

    def get_spindle_override(self, session: Session, args: list[str]) -> str:
        spindle = self._spindle_index(args)
        percent = math.floor(self.stat.spindle[spindle]["override"] * 100.0 + 0.5)
        return f"SPINDLE_OVERRIDE {spindle} {percent}"

    def _spindle_index(self, args: list[str]) -> int:
        """The spindle asked for; without one the last (linuxcncrsh answers for each and
        keeps the last answer)."""
        if args and _is_int(args[0]):
            return int(args[0])
        return max(1, self.stat.spindles) - 1

    def get_tool(self, session: Session, args: list[str]) -> str:
        return f"TOOL {self.stat.tool_in_spindle}"

    def get_tool_offset(self, session: Session, args: list[str]) -> str:
        return f"TOOL_OFFSET {self.stat.tool_offset[2]:f}"

    def get_feed_override(self, session: Session, args: list[str]) -> str:
        return f"FEED_OVERRIDE {math.floor(self.stat.feedrate * 100.0 + 0.5)}"

    def _positions(self, name: str, values: tuple[float, ...], args: list[str]) -> str:
        """``NAME x y z a b c``, or ``NAME i value`` for one of them."""
        if not args:
            return name + "".join(f" {v:f}" for v in values[:6])
        index = _atoi(args[0])
        return f"{name} {index} {values[index]:f}" if 0 <= index < 6 else f"{name} {index}"

    def _relative(self, position: tuple[float, ...]) -> tuple[float, ...]:
        offsets = zip(self.stat.g5x_offset, self.stat.g92_offset, strict=False)
        return tuple(p - g5x - g92 for p, (g5x, g92) in zip(position, offsets, strict=False))

    def get_abs_cmd_pos(self, session: Session, args: list[str]) -> str:
        return self._positions("ABS_CMD_POS", self.stat.position, args)

    def get_abs_act_pos(self, session: Session, args: list[str]) -> str:
        return self._positions("ABS_ACT_POS", self.stat.actual_position, args)

    def get_rel_cmd_pos(self, session: Session, args: list[str]) -> str:
        return self._positions("REL_CMD_POS", self._relative(self.stat.position), args)

    def get_rel_act_pos(self, session: Session, args: list[str]) -> str:
        return self._positions("REL_ACT_POS", self._relative(self.stat.actual_position), args)

    def get_joint_pos(self, session: Session, args: list[str]) -> str:
        inputs = [joint["input"] for joint in self.stat.joint]
        if not args:
            return "JOINT_POS" + "".join(f" {v:f}" for v in inputs[:6])
        joint = _atoi(args[0])
        return f"JOINT_POS {joint} {inputs[joint]:f}"

    def get_pos_offset(self, session: Session, args: list[str]) -> str:
        offsets = [
            self._to_display_units(g5x + g92)
            for g5x, g92 in zip(self.stat.g5x_offset, self.stat.g92_offset, strict=False)
        ]
        if not args:
            return "POS_OFFSET" + "".join(f" {v:f}" for v in offsets[:6])
        letter = args[0][0].upper()
        index = {"X": 0, "Y": 1, "Z": 2, "A": 3, "R": 3, "B": 4, "P": 4, "C": 5, "W": 5}
        value = f" {offsets[index[letter]]:f}" if letter in index else ""
        return f"POS_OFFSET {letter} {value}"

    def _to_display_units(self, value: float) -> float:
        """Linear user units to the units of ``linear_unit_conversion``."""
        if self.linear_conversion == "CUSTOM":
            return value
        in_mm = value / self.stat.linear_units
        units = self.linear_conversion
        if units == "AUTO":
            units = CANON_UNITS.get(self.stat.program_units, "")
        return in_mm * LINEAR_UNITS[units] if units in LINEAR_UNITS else value

    def _each_joint(self, name: str, describe: Callable[[dict], str], args: list[str]) -> str:
        """``NAME v0 .. v5``, or ``NAME j v`` for one joint."""
        if not args:
            return name + "".join(f" {describe(j)}" for j in self.stat.joint[:6])
        joint = _atoi(args[0])
        return f"{name} {joint} {describe(self.stat.joint[joint])}"

    def get_joint_limit(self, session: Session, args: list[str]) -> str:
        def limit(joint: dict) -> str:
            for key, word in (
                ("min_hard_limit", "MINHARD"),
                ("min_soft_limit", "MINSOFT"),
                ("max_soft_limit", "MAXSOFT"),
                ("max_hard_limit", "MAXHARD"),
            ):
                if joint[key]:
                    return word
            return "OK"

        return self._each_joint("JOINT_LIMIT", limit, args)

    def get_joint_fault(self, session: Session, args: list[str]) -> str:
        return self._each_joint("JOINT_FAULT", lambda j: "FAULT" if j["fault"] else "OK", args)

    def get_joint_homed(self, session: Session, args: list[str]) -> str:
        return self._each_joint("JOINT_HOMED", lambda j: "YES" if j["homed"] else "NO", args)

    def get_joint_type(self, session: Session, args: list[str]) -> str:
        types = {c.LINEAR: "LINEAR", c.ANGULAR: "ANGULAR"}
        if not args:
            words = [f" {types[j['jointType']]}" if j["jointType"] in types else "CUSTOM"
                     for j in self.stat.joint[:6]]  # fmt: skip
            return "JOINT_TYPE" + "".join(words)
        joint = _atoi(args[0])
        kind = self.stat.joint[joint]["jointType"]
        return f"JOINT_TYPE {joint} {' ' + types[kind] if kind in types else 'CUSTOM'}"

    def get_joint_units(self, session: Session, args: list[str]) -> str:
        def units(joint: dict) -> str:
            table = {c.LINEAR: LINEAR_UNITS, c.ANGULAR: ANGULAR_UNITS}.get(joint["jointType"])
            return _closest(joint["units"], table or {})

        return self._each_joint("JOINT_UNITS", units, args)

    def get_program(self, session: Session, args: list[str]) -> str:
        return f"PROGRAM {self.stat.file or 'NONE'}"

    def get_program_line(self, session: Session, args: list[str]) -> str:
        task = self.stat
        if self.program_start_line < 0 or task.read_line < self.program_start_line:
            line = task.read_line
        elif task.current_line > 0:
            is_motion_behind = 0 < task.motion_line < task.current_line
            line = task.motion_line if is_motion_behind else task.current_line
        else:
            line = 0
        return f"PROGRAM_LINE {line}"

    def get_program_status(self, session: Session, args: list[str]) -> str:
        states = {c.INTERP_READING: "RUNNING", c.INTERP_WAITING: "RUNNING"}
        states[c.INTERP_PAUSED] = "PAUSED"
        return f"PROGRAM_STATUS {states.get(self.stat.interp_state, 'IDLE')}"

    def get_program_codes(self, session: Session, args: list[str]) -> str:
        words = []
        for code in self.stat.gcodes[1:]:
            if code == -1:
                continue
            words.append(f"G{code / 10:.1f} " if code % 10 else f"G{code // 10} ")
        settings = self.stat.settings
        return f"PROGRAM_CODES {''.join(words)}F{settings[1]:.0f} S{abs(settings[2]):.0f}"

    def get_program_units(self, session: Session, args: list[str]) -> str:
        return f"PROGRAM_UNITS {CANON_UNITS.get(self.stat.program_units, 'CUSTOM')}"

    get_program_linear_units = get_program_units

    def get_program_angular_units(self, session: Session, args: list[str]) -> str:
        return "PROGRAM_ANGULAR_UNITS DEG"

    def get_user_linear_units(self, session: Session, args: list[str]) -> str:
        return f"USER_LINEAR_UNITS {_closest(self.stat.linear_units, LINEAR_UNITS)}"

    def get_user_angular_units(self, session: Session, args: list[str]) -> str:
        return f"USER_ANGULAR_UNITS {_closest(self.stat.angular_units, ANGULAR_UNITS)}"

    def get_display_linear_units(self, session: Session, args: list[str]) -> str:
        units = self.linear_conversion
        if units == "AUTO":
            units = {1: "INCH", 2: "MM", 3: ""}.get(self.stat.program_units, "CUSTOM")
        return f"DISPLAY_LINEAR_UNITS {units}"

    def get_display_angular_units(self, session: Session, args: list[str]) -> str:
        units = "DEG" if self.angular_conversion == "AUTO" else self.angular_conversion
        return f"DISPLAY_ANGULAR_UNITS {units}"

    def get_linear_unit_conversion(self, session: Session, args: list[str]) -> str:
        return f"LINEAR_UNIT_CONVERSION {self.linear_conversion}"

    def get_angular_unit_conversion(self, session: Session, args: list[str]) -> str:
        return f"ANGULAR_UNIT_CONVERSION {self.angular_conversion}"

    def get_probe_tripped(self, session: Session, args: list[str]) -> str:
        return f"PROBE_TRIPPED {int(self.stat.probe_tripped)}"

    def get_probe_value(self, session: Session, args: list[str]) -> str:
        return f"PROBE_VALUE {int(self.stat.probe_val)}"

    def get_teleop_enable(self, session: Session, args: list[str]) -> str:
        return f"TELEOP_ENABLE {'YES' if self.stat.motion_mode == c.TRAJ_MODE_TELEOP else 'NO'}"

    def get_kinematics_type(self, session: Session, args: list[str]) -> str:
        return f"KINEMATICS_TYPE {self.stat.kinematics_type}"

    def get_override_limits(self, session: Session, args: list[str]) -> str:
        return f"OVERRIDE_LIMITS {int(self.stat.joint[0]['override_limits'])}"

    def get_optional_stop(self, session: Session, args: list[str]) -> str:
        return f"OPTIONAL_STOP {int(self.stat.optional_stop)}"

    # ------------------------------------------------------------ help
    def _help(self, args: list[str]) -> str:
        topic = args[0].upper() if args else ""
        text = HELP.get(topic)
        if text is None:
            return f"{topic} is not a valid command.\r\n"
        return text.replace("\n", "\n\r") + "\r\n"


HELP = {
    "": "Available commands:\n  Hello <password> <client name> <protocol version>\n"
    "  Get <LinuxCNC command>\n  Set <LinuxCNC command>\n  Shutdown\n  Help <command>\n",
    "HELLO": "Usage:\n  Hello <Password> <Client Name> <Protocol Version>\n"
    "  The connection password lets a client talk to the server; the reply is\n"
    "  HELLO ACK <Server Name> <Protocol Version>, or HELLO NAK.\n",
    "GET": "Usage:\n  Get <LinuxCNC command> [arguments]\n  Answers the item's value,"
    " e.g. get estop -> ESTOP ON; an unknown item or argument -> GET <ITEM> NAK.\n"
    "  Items: " + " ".join(i.lower() for i in ITEMS) + "\n",
    "SET": "Usage:\n  Set <LinuxCNC command> <arguments>\n  Needs hello and, from inifile on,"
    " set enable <password>; after machine, the machine must be on.\n"
    "  Silent when it worked (SET <ITEM> ACK with set verbose on), else SET <ITEM> NAK.\n",
    "QUIT": "Usage:\n  Quit\n  Closes this connection.\n",
    "SHUTDOWN": "Usage:\n  Shutdown\n  Stops the server (and a machine it is the display of);"
    " needs set enable.\n",
    "HELP": "Usage:\n  Help [command]\n  Lists the commands, or explains one.\n",
}


# ---------------------------------------------------------------- parsing helpers
def _words(line: str) -> list[str]:
    """Words as linuxcncrsh splits them: at blanks, CR and LF (not tabs)."""
    return [w for w in line.replace("\r", " ").replace("\n", " ").split(" ") if w]


def _rest_of_line(line: str, words_before: int) -> str:
    """What follows the first ``words_before`` words and the one blank after them, as
    linuxcncrsh reads MDI text and file names ("" when nothing does)."""
    pattern = r"(?:[ \r\n]*[^ \r\n]+){" + str(words_before) + r"}[ \r\n]?(.*)"
    found = re.match(pattern, line, re.S)
    return found.group(1).rstrip("\r\n") if found else ""


def _on_off(args: list[str]) -> bool:
    word = args[0].upper() if args else ""
    if word not in ("ON", "OFF"):
        raise FailedError
    return word == "ON"


def _word(is_on: bool) -> str:
    return "ON" if is_on else "OFF"


def _is_int(text: str) -> bool:
    with contextlib.suppress(ValueError):
        int(text)
        return True
    return False


def _atoi(text: str) -> int:
    """C's atoi: the leading integer, 0 if none."""
    digits = ""
    for index, char in enumerate(text.strip()):
        if char.isdigit() or (index == 0 and char in "+-"):
            digits += char
        else:
            break
    return int(digits) if digits not in ("", "+", "-") else 0


def _joint_or_axis(word: str) -> tuple[int, int]:
    """(1, joint) for a number, (0, axis index) for a letter X..W."""
    if _is_int(word):
        joint = int(word)
        if joint < 0:
            raise FailedError
        return 1, joint
    letter = word[0].upper()
    if letter not in AXIS_LETTERS:
        raise FailedError
    return 0, AXIS_LETTERS.index(letter)


def _closest(value: float, table: dict[str, float]) -> str:
    for name, units in table.items():
        if abs(value - units) < 1e-4 * max(1.0, units):
            return name
    return "CUSTOM"


# ---------------------------------------------------------------- the server
class _Handler(socketserver.BaseRequestHandler):
    server: _Server

    def handle(self) -> None:
        shell, session, pending = self.server.shell, Session(), b""
        sock = self.request
        while True:
            try:
                data = sock.recv(4096)
            except OSError:
                break
            if not data:
                break
            if session.is_echo and session.is_linked:
                with contextlib.suppress(OSError):
                    sock.sendall(data)
            pending += data
            *lines, pending = pending.replace(b"\r", b"\n").split(b"\n")
            for raw in lines:
                if not raw:
                    continue
                try:
                    reply = shell.handle(session, raw.decode("utf-8", errors="replace"))
                except EOFError:
                    print(f"Closing connection with {session.client}", flush=True)
                    return
                except SystemExit:
                    print("Shutting down", flush=True)
                    shell.on_shutdown()
                    return
                if reply is not None:
                    with contextlib.suppress(OSError):
                        sock.sendall(reply.encode())
        if shell.enabled is session:
            shell.enabled = None
        print(f"linuxcncrsh: disconnecting client {session.client} ({session.version})")


class _Server(socketserver.ThreadingTCPServer):
    allow_reuse_address = True
    daemon_threads = True

    def __init__(self, address: tuple[str, int], shell: RemoteShell | None, sessions: int) -> None:
        super().__init__(address, _Handler)
        self.shell = shell
        self.max_sessions = sessions
        self.sessions = 0
        self.count_lock = threading.Lock()

    def process_request(self, request: Any, client_address: Any) -> None:
        with self.count_lock:
            if 0 <= self.max_sessions <= self.sessions:
                self.shutdown_request(request)
                return
            self.sessions += 1
        super().process_request(request, client_address)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self.count_lock:
                self.sessions -= 1


def parse_arguments(argv: list[str]) -> tuple[argparse.Namespace, str | None]:
    """linuxcncrsh's options, then after ``--`` LinuxCNC's (``-ini FILE``); an INI file may
    also be given alone, as for the other ``cnc`` UIs."""
    own, _, linuxcnc_args = (
        (argv[: argv.index("--")], "--", argv[argv.index("--") + 1 :])
        if ("--" in argv)
        else (argv, "", [])
    )
    parser = argparse.ArgumentParser(prog="cnc rsh", description=__doc__.split("\n\n")[0])
    parser.add_argument("--port", type=int, default=DEFAULT_PORT)
    parser.add_argument("--name", default="EMCNETSVR", help="server name in HELLO ACK")
    parser.add_argument("--connectpw", default="EMC", help="password of hello")
    parser.add_argument("--enablepw", default="EMCTOO", help="password of set enable")
    parser.add_argument("--sessions", type=int, default=-1, help="most connections (-1: any)")
    parser.add_argument("--path", default="../../nc_files/", help="program folder")
    parser.add_argument("ini", nargs="?", help="the machine's INI file (default: the running one)")
    options = parser.parse_args(own)
    ini = options.ini
    for index, word in enumerate(linuxcnc_args):
        if word == "-ini" and index + 1 < len(linuxcnc_args):
            ini = linuxcnc_args[index + 1]
    return options, os.path.abspath(ini) if ini else None


def main(argv: list[str] | None = None) -> int:
    options, ini = parse_arguments(sys.argv[1:] if argv is None else argv)
    if ini is not None and not Path(ini).is_file():
        print(f"cnc rsh: no INI file {ini}", file=sys.stderr)
        return 1
    # Listen first, then attach to the machine: a client that connects meanwhile (a
    # script starting right after the machine) waits in the queue instead of being refused.
    try:
        server = _Server(("0.0.0.0", options.port), None, options.sessions)
    except OSError as exc:
        print(f"cnc rsh: error initializing sockets: {exc.strerror}", file=sys.stderr)
        return 1
    shell = server.shell = RemoteShell(ini, options)
    shell.on_shutdown = lambda: threading.Thread(target=server.shutdown, daemon=True).start()
    print(f"cnc rsh: listening on port {server.server_address[1]}", file=sys.stderr, flush=True)
    import signal

    signal.signal(signal.SIGTERM, lambda *_: shell.on_shutdown())
    try:
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
