"""The iocontrol process: e-stop chain, coolant, lube and tool changer over HAL (IO-001..020).

One object, ``IoControl``, owns the HAL component ``iocontrol.0``, iocontrol's NML buffers
(toolCmd, toolSts, emcError as process ``tool``) and the tool changer state. Its main loop
(IO-003), every iteration:

1. reads the HAL inputs (``emc-enable-in`` -> ``aux.estop``, ``lube_level``), completes a
   handshake the changer acknowledged (``read_tool_inputs`` of IO-003), and copies the state
   to the HAL outputs;
2. publishes EMC_IO_STAT when anything in it changed;
3. sleeps on the command buffer's semaphore until a command arrives, at most one
   [EMCIO]CYCLE_TIME (HANDSHAKE_POLL_S while a handshake is pending), and executes it.

So a command is executed as soon as it arrives, and with the handshake pins looped back in
HAL its prepare or change completes in the same iteration (IO-010).

Status (NML-041/042): ``echo_serial_number`` and ``command_type`` of the last command; status
EXEC while a prepare/change handshake is pending, ERROR if the last command failed (the reason
goes to emcError as an operator error), else DONE.
"""

from __future__ import annotations

import signal
import sys
import time
from pathlib import Path
from typing import Any

import posix_ipc

from cnc.atomicfile import atomic_write_text
from hal.api import HAL_BIT, HAL_IN, HAL_OUT, HAL_S32, HalError, component, shared_hal
from iocontrol.config import IoConfig
from iocontrol.toolchanger import ToolChangeError, ToolChanger
from iocontrol.tooldata import ToolDataWriter
from iocontrol.tooltable import ToolEntry, ToolTable, ToolTableError
from nml import emc
from nml.channels import EMC_ERROR, TOOL_COMMAND, TOOL_STATUS, Nml, load_config
from nml.commands import Handlers, Refused, carry_out, handler
from nml.errors import NmlError, NmlFormatError
from nml.ipcnames import ipc_name
from nml.message import RCS_STATUS, NMLmsg
from nml.outbox import Outbox
from nml.safety import BRAKE_TIMEOUT_S, SafetyLink
from nml.shmem import is_process_alive

COMPONENT = "iocontrol"
PREFIX = "iocontrol.0"
NML_PROCESS = "tool"
HANDSHAKE_POLL_S = 0.002  # how often tool-prepared / tool-changed are checked while pending
# Unchanged status is written again this often: a reader that reset a corrupt status buffer
# (nml/shmem.py) sees it again soon.
REPUBLISH_S = 0.5
# A braking E-stop opens the E-stop chain at the latest this long after it was asked for
# (motion brakes for at most BRAKE_TIMEOUT_S, then asks for the immediate one).
BRAKE_FALLBACK_S = BRAKE_TIMEOUT_S + 1.0
ESTOP_CHAIN_SETTLE_S = 0.1  # how long an E-stop reset waits for the chain to close

# LinuxCNC's pins (io(1)): name, type, direction.
PINS = (
    ("user-enable-out", HAL_BIT, HAL_OUT),
    ("user-request-enable", HAL_BIT, HAL_OUT),
    ("emc-enable-in", HAL_BIT, HAL_IN),
    ("coolant-flood", HAL_BIT, HAL_OUT),
    ("coolant-mist", HAL_BIT, HAL_OUT),
    ("lube", HAL_BIT, HAL_OUT),
    ("lube_level", HAL_BIT, HAL_IN),
    ("tool-prepare", HAL_BIT, HAL_OUT),
    ("tool-prepared", HAL_BIT, HAL_IN),
    ("tool-change", HAL_BIT, HAL_OUT),
    ("tool-changed", HAL_BIT, HAL_IN),
    ("tool-number", HAL_S32, HAL_OUT),
    ("tool-prep-number", HAL_S32, HAL_OUT),
    ("tool-prep-pocket", HAL_S32, HAL_OUT),
    ("tool-prep-index", HAL_S32, HAL_OUT),
    ("tool-from-pocket", HAL_S32, HAL_OUT),
)


# What HAL should hold when iocontrol is gone (its pins keep their last values, and nobody
# writes them any more): the E-stop chain open, coolant, lube and tool change off. The
# launcher writes these when it finds iocontrol dead.
SAFE_OUTPUTS = {
    f"{PREFIX}.{name}": False
    for name in (
        "user-enable-out",
        "user-request-enable",
        "coolant-flood",
        "coolant-mist",
        "lube",
        "tool-prepare",
        "tool-change",
    )
}


def entry_to_canon(entry: ToolEntry, out: emc.CANON_TOOL_TABLE) -> None:
    """Copy a tool record into an NML CANON_TOOL_TABLE (TOOL-006)."""
    out.toolno = entry.toolno
    out.pocketno = entry.pocketno
    out.diameter = entry.diameter
    out.frontangle = entry.frontangle
    out.backangle = entry.backangle
    out.orientation = entry.orientation
    out.offset.set(entry.offset)


def load_tool_table(path: Path, is_random: bool) -> ToolTable:
    """Read a tool table file; raises ToolTableError (file:line) or OSError."""
    table = ToolTable(random_toolchanger=is_random)
    table.load(path)
    return table


class IoControl:
    """iocontrol's state, its HAL component and its NML connections."""

    def __init__(self, config: IoConfig) -> None:
        self.config = config
        self.cycle_time = config.cycle_time
        self.table_path = config.tool_table
        self.is_stopping = False
        self.debug = 0
        self.abort_reason = 0
        # state mirrored to the HAL outputs and the status
        self.is_user_enabled = False
        self.is_request_enable = False
        self.request_enable_until = 0.0
        self.is_flood = False
        self.is_mist = False
        self.is_lube = False
        self.is_estop = True
        self.lube_level = 1
        # RCS acknowledgement of the last command
        self.command_type = 0
        self.echo_serial = 0
        self.has_command_failed = False
        self.heartbeat = 0
        self._published: bytes | None = None
        # tool table: a file that failed to load is never overwritten (is_save_blocked)
        self.is_save_blocked = False
        self._startup_errors: list[str] = []  # reported on emcError once NML is open
        self.changer = ToolChanger(self._startup_table())
        self._saved_text = self.changer.table.format()
        self.comp: component | None = None
        self.tool_data: ToolDataWriter | None = None
        self.nml: Nml | None = None
        self.outbox: Outbox | None = None
        self.safety: SafetyLink | None = None
        self.braking_estop_at = 0.0  # a braking E-stop: the chain opens when motion stopped
        self._published_at = 0.0
        self._handlers = Handlers(self)  # the @handler methods below

    # ------------------------------------------------------------------ set-up
    def open(self) -> None:
        """Create the HAL component and attach to the NML buffers; ready when done.

        The HAL must exist already (started by the realtime host, halrun or the launcher):
        a component that created it would leave it behind.
        """
        try:
            posix_ipc.SharedMemory(ipc_name("hal", "data")).close_fd()
        except posix_ipc.ExistentialError:
            raise HalError("no HAL is running (start the realtime host or halrun first)") from None
        self._remove_stale_component()
        comp = component(COMPONENT, prefix=PREFIX)
        self.comp = comp
        for name, hal_type, direction in PINS:
            comp.newpin(name, hal_type, direction)
        self._write_outputs()
        self.tool_data = ToolDataWriter()
        self.tool_data.publish(self.changer.table)
        self.nml = Nml(
            load_config(self.config.nml_file), NML_PROCESS, [TOOL_COMMAND, TOOL_STATUS, EMC_ERROR]
        )
        self.outbox = Outbox(self.nml[EMC_ERROR])
        self.safety = SafetyLink.open("iocontrol", self.config.heartbeat_timeout)
        for text in self._startup_errors:
            self.report_error(text)
        self.update()
        self.publish()
        comp.ready()

    def _remove_stale_component(self) -> None:
        """Take over from an iocontrol that was killed without leaving HAL (kill -9)."""
        hal = shared_hal()
        stale = hal.meta["comps"].get(COMPONENT)
        if stale is not None and not is_process_alive(stale["pid"]):
            self._warn(f"removing the component of a dead iocontrol (pid {stale['pid']})")
            hal.remove_component(COMPONENT)

    def close(self) -> None:
        """Save the tool table if it changed, remove the tool data store, leave HAL, close
        NML (IO-003)."""
        if self.safety is not None:
            self.safety.close()
            self.safety = None
        self.save_table_if_changed()
        if self.tool_data is not None:
            self.tool_data.close()
            self.tool_data = None
        if self.comp is not None:
            self.comp.exit()
            self.comp = None
        if self.nml is not None:
            self.nml.close()
            self.nml = None

    def _startup_table(self) -> ToolTable:
        try:
            table = load_tool_table(self.table_path, self.config.is_random_toolchanger)
            self.is_save_blocked = table.has_unreadable_lines  # (the launcher warned)
            return table
        except ToolTableError as exc:
            self.is_save_blocked = True
            self._startup_errors.append(
                f"{exc}; starting with an empty tool table (the file is left as is)"
            )
        except OSError as exc:
            self._startup_errors.append(f"cannot read tool table {self.table_path}: {exc.strerror}")
        return ToolTable(random_toolchanger=self.config.is_random_toolchanger)

    # ------------------------------------------------------------------ main loop
    def run(self) -> None:
        """The main loop (IO-003) until SIGTERM / SIGINT."""
        while not self.is_stopping:
            self.take_safety_requests()
            self.update()
            self.publish()
            timeout = self.cycle_time
            if self.changer.is_pending:
                timeout = min(timeout, HANDSHAKE_POLL_S)
            msg = self._next_command(timeout)
            if msg is not None:
                self.execute(msg)

    def take_safety_requests(self) -> None:
        """Beat iocontrol's heartbeat; E-stop and abort from the safety board act here
        even when task is stuck. A braking E-stop (a process was lost) opens the E-stop
        chain only when motion, at rest, asks for the immediate one, or after
        BRAKE_FALLBACK_S (motion may be the process that is gone)."""
        if self.safety is None:
            return
        tick = self.safety.tick()
        for lost in tick.lost:
            self.report_error(f"E-stop: {lost.reason}")
        if tick.estop is not None:
            if tick.estop.is_braking:
                self.braking_estop_at = self.braking_estop_at or time.monotonic()
            else:
                self.braking_estop_at = 0.0
                self._estop_on(None)
        if self.braking_estop_at and time.monotonic() - self.braking_estop_at > BRAKE_FALLBACK_S:
            self.braking_estop_at = 0.0
            self._estop_on(None)
        if tick.abort is not None:
            self._abort(None)
        if tick.estop is not None or tick.abort is not None:
            self._write_outputs()

    def stop(self, *_: Any) -> None:
        """Signal handler: leave the main loop at the next wake-up."""
        self.is_stopping = True

    def _next_command(self, timeout: float) -> NMLmsg | None:
        assert self.nml is not None
        try:
            return self.nml[TOOL_COMMAND].blocking_read(timeout)
        except posix_ipc.SignalError:
            return None  # a signal woke us: the loop checks is_stopping
        except NmlFormatError as exc:
            self.report_error(f"bad command ignored: {exc}")
            return None

    def update(self) -> None:
        """Read the HAL inputs, finish acknowledged handshakes, write the HAL outputs."""
        comp = self.comp
        assert comp is not None
        self.is_estop = not comp["emc-enable-in"]
        self.lube_level = 1 if comp["lube_level"] else 0
        if self.changer.poll(comp["tool-prepared"], comp["tool-changed"]):
            self._commit_table()
        if self.is_request_enable and time.monotonic() >= self.request_enable_until:
            self.is_request_enable = False  # end of the one-cycle pulse
        self._write_outputs()

    def _write_outputs(self) -> None:
        comp = self.comp
        assert comp is not None
        changer = self.changer
        for name, value in (
            ("user-enable-out", self.is_user_enabled),
            ("user-request-enable", self.is_request_enable),
            ("coolant-flood", self.is_flood),
            ("coolant-mist", self.is_mist),
            ("lube", self.is_lube),
            ("tool-prepare", changer.is_preparing),
            ("tool-change", changer.is_changing),
            ("tool-number", changer.tool_in_spindle),
            ("tool-prep-number", changer.prep_number),
            ("tool-prep-pocket", changer.prep_pocket),
            ("tool-prep-index", changer.prep_index),
            ("tool-from-pocket", changer.tool_from_pocket),
        ):
            comp[name] = value

    # ------------------------------------------------------------------ status
    def rcs_status(self) -> int:
        """ERROR after a failed command, EXEC while a handshake is pending, else DONE."""
        if self.has_command_failed:
            return RCS_STATUS.ERROR
        return RCS_STATUS.EXEC if self.changer.is_pending else RCS_STATUS.DONE

    def build_status(self) -> emc.EMC_IO_STAT:
        st = emc.EMC_IO_STAT()
        st.command_type = self.command_type
        st.echo_serial_number = self.echo_serial
        st.status = self.rcs_status()
        st.cycleTime = self.cycle_time
        st.debug = self.debug
        st.reason = self.abort_reason
        changer = self.changer
        st.tool.pocketPrepped = changer.pocket_prepped
        st.tool.toolInSpindle = changer.tool_in_spindle
        st.tool.toolFromPocket = changer.tool_from_pocket
        entry_to_canon(changer.spindle(), st.tool.toolTableCurrent)
        st.coolant.mist = int(self.is_mist)
        st.coolant.flood = int(self.is_flood)
        st.aux.estop = int(self.is_estop)
        st.lube.on = int(self.is_lube)
        st.lube.level = self.lube_level
        return st

    def publish(self) -> None:
        """Write EMC_IO_STAT if it differs from the last one written."""
        assert self.nml is not None
        st = self.build_status()
        key = st.to_bytes()
        now = time.monotonic()
        if key == self._published and now - self._published_at < REPUBLISH_S:
            return
        self._published = key
        self._published_at = now
        self.heartbeat += 1
        st.heartbeat = self.heartbeat
        self.nml[TOOL_STATUS].write(st)

    # ------------------------------------------------------------------ errors
    def _warn(self, text: str) -> None:
        print(f"iocontrol: {text}", file=sys.stderr, flush=True)

    def report_error(self, text: str) -> None:
        """An operator error: on stderr and on emcError, where every GUI shows it."""
        self._warn(text)
        if self.outbox is not None:
            self.outbox.error(text)  # (never waits for a reader)

    # ------------------------------------------------------------------ commands
    def execute(self, msg: NMLmsg) -> None:
        """Run one command and acknowledge it (NML-041)."""
        self.command_type = msg.TYPE
        self.echo_serial = getattr(msg, "serial_number", 0)
        self.has_command_failed = False
        answer = carry_out("iocontrol", self._carry_out, msg, expected=(ToolChangeError,))
        if answer.status == RCS_STATUS.ERROR:  # (a bug too: logged, iocontrol goes on)
            self.has_command_failed = True
            if answer.reason:
                self.report_error(answer.reason)
        if isinstance(msg, emc.EMC_TOOL_CMD_MSG):
            self._commit_table()
        self._write_outputs()  # now, so a HAL loopback answers before the next update

    def _commit_table(self) -> None:
        """After a tool command or handshake: save the file if the table changed and publish
        it to the tool data store, both before the status reports the command done."""
        if not self.save_table_if_changed():
            self.has_command_failed = True
        if self.tool_data is not None:
            self.tool_data.publish(self.changer.table)

    def _carry_out(self, msg: NMLmsg) -> None:
        function = self._handlers.get(type(msg))
        if function is None:
            raise Refused(f"iocontrol cannot execute {msg.NAME} (type {msg.TYPE})")
        function(msg)

    @handler(emc.EMC_TOOL_PREPARE)
    def _prepare(self, msg: emc.EMC_TOOL_PREPARE) -> None:
        self.changer.prepare(msg.tool)

    @handler(emc.EMC_TOOL_LOAD)
    def _load(self, msg: emc.EMC_TOOL_LOAD) -> None:
        self.changer.start_change()

    @handler(emc.EMC_TOOL_UNLOAD)
    def _unload(self, msg: emc.EMC_TOOL_UNLOAD) -> None:
        self.changer.unload()

    @handler(emc.EMC_TOOL_SET_NUMBER)
    def _set_number(self, msg: emc.EMC_TOOL_SET_NUMBER) -> None:
        self.changer.set_number(msg.tool)

    @handler(emc.EMC_TOOL_START_CHANGE)
    def _start_change(self, msg: emc.EMC_TOOL_START_CHANGE) -> None:
        """Nothing to do before M6's move."""

    @handler(emc.EMC_COOLANT_MIST_ON, emc.EMC_COOLANT_MIST_OFF)
    def _mist(self, msg: NMLmsg) -> None:
        self.is_mist = isinstance(msg, emc.EMC_COOLANT_MIST_ON)

    @handler(emc.EMC_COOLANT_FLOOD_ON, emc.EMC_COOLANT_FLOOD_OFF)
    def _flood(self, msg: NMLmsg) -> None:
        self.is_flood = isinstance(msg, emc.EMC_COOLANT_FLOOD_ON)

    @handler(emc.EMC_LUBE_ON, emc.EMC_LUBE_OFF)
    def _lube(self, msg: NMLmsg) -> None:
        self.is_lube = isinstance(msg, emc.EMC_LUBE_ON)

    def _reset_outputs(self) -> None:
        """Every HAL output to its safe value (LinuxCNC's hal_init_pins)."""
        self.is_user_enabled = False
        self.is_request_enable = False
        self.is_flood = self.is_mist = self.is_lube = False
        self.changer.reset_outputs()

    @handler(emc.EMC_IO_INIT)
    def _io_init(self, msg: emc.EMC_IO_INIT) -> None:
        self._reset_outputs()

    @handler(emc.EMC_IO_HALT, emc.EMC_TOOL_HALT)
    def _halt(self, msg: NMLmsg) -> None:
        self.changer.cancel()

    @handler(emc.EMC_IO_ABORT, emc.EMC_TOOL_ABORT)
    def _abort(self, msg: NMLmsg) -> None:
        """Task aborts: coolant off, any handshake dropped (IO-013)."""
        self.abort_reason = getattr(msg, "reason", 0)
        self.is_flood = self.is_mist = False
        self.changer.cancel()

    @handler(emc.EMC_IO_SET_CYCLE_TIME)
    def _set_cycle_time(self, msg: emc.EMC_IO_SET_CYCLE_TIME) -> None:
        if not msg.cycleTime > 0:
            raise Refused(f"cycle time {msg.cycleTime} must be positive")
        self.cycle_time = msg.cycleTime

    @handler(emc.EMC_SET_DEBUG)
    def _set_debug(self, msg: emc.EMC_SET_DEBUG) -> None:
        self.debug = msg.debug

    @handler(emc.EMC_AUX_ESTOP_ON)
    def _estop_on(self, msg: emc.EMC_AUX_ESTOP_ON) -> None:
        """Assert e-stop to the outside world: user-enable-out false, outputs safe (IO-016)."""
        self._reset_outputs()

    @handler(emc.EMC_AUX_ESTOP_OFF)
    def _estop_off(self, msg: emc.EMC_AUX_ESTOP_OFF) -> None:
        """Allow enabling: user-enable-out true and a one-cycle user-request-enable pulse,
        the rising edge that resets an external e-stop latch (IO-016). An E-stop chain
        through realtime components (estop_latch, a card's watchdog) closes a servo period
        or two later: wait for emc-enable-in that long before reporting."""
        self.is_user_enabled = True
        self._pulse_request_enable()
        self._write_outputs()
        deadline = time.monotonic() + ESTOP_CHAIN_SETTLE_S
        while self.comp is not None and not self.comp["emc-enable-in"]:
            if time.monotonic() >= deadline:
                break
            time.sleep(0.001)

    @handler(emc.EMC_AUX_ESTOP_RESET)
    def _estop_reset(self, msg: emc.EMC_AUX_ESTOP_RESET) -> None:
        """A further reset request for the external latch; LinuxCNC 2.9 ignores it."""
        if self.is_user_enabled:
            self._pulse_request_enable()

    def _pulse_request_enable(self) -> None:
        self.is_request_enable = True
        self.request_enable_until = time.monotonic() + self.cycle_time

    @handler(emc.EMC_TOOL_INIT)
    def _tool_init(self, msg: emc.EMC_TOOL_INIT) -> None:
        self._reload_table(self.table_path)

    @handler(emc.EMC_TOOL_LOAD_TOOL_TABLE)
    def _load_tool_table(self, msg: emc.EMC_TOOL_LOAD_TOOL_TABLE) -> None:
        if "\0" in msg.file:  # (no file can have that name: the OS refuses it)
            raise Refused(f"tool table file name {msg.file!r} holds a NUL character")
        path = Path(msg.file) if msg.file else self.table_path
        self._reload_table(path)

    def _reload_table(self, path: Path) -> None:
        """Replace the tool table by the file's; on any error keep the current one, and
        never save it over the table file the user is editing."""
        try:
            table = load_tool_table(path, self.changer.is_random)
        except ToolTableError as exc:
            self.is_save_blocked = self.is_save_blocked or path == self.table_path
            raise Refused(f"{exc}; tool table not reloaded") from None
        except OSError as exc:
            raise Refused(f"cannot read tool table {path}: {exc.strerror}") from None
        if table.has_unreadable_lines:  # the table in use stays rather than lose tools
            self.is_save_blocked = self.is_save_blocked or path == self.table_path
            skipped = "; ".join(str(w) for w in table.warnings if "skipped" in str(w))
            raise Refused(f"{skipped}; tool table not reloaded")
        self.changer.replace_table(table)
        # like LinuxCNC, a reload is not written back; the next change saves the table
        self._saved_text = table.format()
        if path == self.table_path:
            self.is_save_blocked = False
        for warning in table.warnings:
            self.report_error(f"warning: {warning}")

    @handler(emc.EMC_TOOL_SET_OFFSET)
    def _set_offset(self, msg: emc.EMC_TOOL_SET_OFFSET) -> None:
        self.changer.set_offset(
            msg.pocket,
            msg.toolno,
            list(msg.offset.values()),
            msg.diameter,
            msg.frontangle,
            msg.backangle,
            msg.orientation,
        )

    @handler(emc.EMC_IO_PLUGIN_CALL)
    def _plugin_call(self, msg: emc.EMC_IO_PLUGIN_CALL) -> None:
        raise Refused("iocontrol has no Python plugin (EMC_IO_PLUGIN_CALL, IO-020)")

    # ------------------------------------------------------------------ tool table file
    def save_table_if_changed(self) -> bool:
        """Write the tool table atomically if it changed since loaded or saved (IO-015).

        A table whose file failed to load is never written over that file. False if the
        table could not be saved (reported on emcError).
        """
        text = self.changer.table.format()
        if text == self._saved_text:
            return True
        # a failure is reported once per change, not again for every later command
        self._saved_text = text
        if self.is_save_blocked:
            self.report_error(
                f"tool table not saved: {self.table_path} has lines that could not be read "
                "(saving would lose them); fix the file and reload it"
            )
            return False
        try:
            atomic_write_text(self.table_path, text)
        except OSError as exc:
            self.report_error(f"cannot save tool table {self.table_path}: {exc}")
            return False
        return True


def run(config: IoConfig) -> int:
    """Start iocontrol, serve until SIGTERM / SIGINT, shut down cleanly; the exit status."""
    io = IoControl(config)
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, io.stop)
    try:
        io.open()
        io.run()
    except posix_ipc.SignalError:
        pass  # stopped while still starting
    except (NmlError, HalError, OSError, posix_ipc.Error) as exc:
        print(f"iocontrol: {exc}", file=sys.stderr, flush=True)
        return 1
    finally:
        io.close()
    return 0
