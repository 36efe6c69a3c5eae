"""``cnc run CONFIG.ini``: start a machine from its INI file, like LinuxCNC's ``linuxcnc``.

Start-up, in LinuxCNC's order (ARCH-009/010): the NML buffers (this process is their master),
the realtime host, iocontrol ([EMCIO]EMCIO, as the userspace HAL component ``iocontrol``),
[HAL]HALUI (``halui`` is ``cnc.halui``), the HAL files ([HAL]HALFILE, with ``[SECTION]KEY``
taken from the INI), task ([TASK]TASK) in the background, [HAL]HALCMD lines, the threads
started, the display ([DISPLAY]DISPLAY), task's first status, then [HAL]POSTGUI_HALFILE,
then the bridges ([MQTT], [OPCUA]: cnc.bridges, restarted when they die, never taking the
machine down).

Shut-down, when the display exits or on SIGINT/SIGTERM (ARCH-011): display, task (saves
parameters and positions), HAL (``unload all``: motion, iocontrol, which saves the tool
table), the realtime host, the buffers; nothing is left in /dev/shm. A step that fails
reports why (with file:line for INI and HAL files) and everything started so far is stopped
again.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import os
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from cnc.atomicfile import atomic_write_text
from cnc.ini import IniError, IniFile
from cnc.inischema import check_machine, io_program
from cnc.runtime import (
    claim_instance,
    read_runtime_info,
    release_instance,
    remove_runtime_info,
    write_runtime_info,
)
from cnc.stdio import protect_output
from nml.channels import DEFAULT_NML_FILE, EMC_ERROR, EMC_STATUS, MOTION_STATUS, Nml, load_config
from nml.config import NmlConfig
from nml.errors import NmlError
from nml.ipcnames import INSTANCE_ENV, current_instance, remove_instance_objects
from nml.outbox import Outbox
from nml.safety import BRAKE_TIMEOUT_S, SafetyBoard
from task.positions import write_positions

READY_TIMEOUT_S = 20.0  # after this long without task's first status, the launcher says so
PR_SET_PDEATHSIG = 1
# [DISPLAY]DISPLAY values that are our own user interfaces (anything else is run as given)
OUR_DISPLAYS = {"top": ["top"], "sh": ["sh"], "web": ["ui", "web"]}
LINUXCNC_VERSION = "2.9"  # exported as LINUXCNCVERSION: the LinuxCNC this one follows


class LaunchError(Exception):
    """A start-up step failed; the message says which and why."""


@dataclass
class LaunchOptions:
    """``linuxcnc``'s options that change how a machine starts (``cnc run -h``)."""

    is_keep_going: bool = False  # -k: go on past errors in HAL files
    is_verbose: bool = False  # -v: say what each HAL command did
    is_debug: bool = False  # -d: also echo each HAL command
    hal_dirs: list[str] = field(default_factory=list)  # -H: searched first for HAL files
    tpmod: str = ""  # -t: instead of [TRAJ]TPMOD
    homemod: str = ""  # -m: instead of [EMCMOT]HOMEMOD
    display_args: list[str] = field(default_factory=list)  # after the INI: to the display


class Launcher:
    def __init__(
        self, ini_path: str, is_headless: bool = False, options: LaunchOptions | None = None
    ) -> None:
        # absolute, but not through symlinks: relative paths in the INI are relative to
        # the folder it was named in, as LinuxCNC's launcher sees it (`pwd`/name)
        self.ini_path = os.path.abspath(os.path.expanduser(ini_path))
        self.folder = Path(self.ini_path).parent
        self.is_headless = is_headless
        self.options = options or LaunchOptions()
        # the INI file against the schema, its tool table and .var file, before anything starts
        self.config = check_machine(self.ini_path)
        self.ini = self.config.ini
        for warning in self.config.warnings:
            say(f"warning: {warning}")
        self.nml: Nml | None = None
        self.host: subprocess.Popen[bytes] | None = None
        self.task: subprocess.Popen[bytes] | None = None
        self.display: subprocess.Popen[bytes] | None = None
        self.bridges = None  # cnc.bridges.supervisor.BridgeSupervisor, once started
        self.is_hal_loaded = False
        self.hal_session = None
        self.is_owner = False
        self.is_stopping = False
        self.instance_lock: int | None = None
        self.board: SafetyBoard | None = None
        self.outbox: Outbox | None = None
        self.reported_exits: set[int] = set()  # pids of children whose end was handled
        self.made_safe: set[int] = set()  # lost iocontrols whose outputs were made safe

    # ------------------------------------------------------------------ start-up
    def start(self) -> None:
        self.instance_lock = claim_instance()
        if self.instance_lock is None:  # not ours: stop() must leave it alone
            running = read_runtime_info()
            which = f" (pid {running.pid}, {running.ini})" if running else " (starting up)"
            raise LaunchError(
                f"a machine is already running for instance '{current_instance()}'{which}: "
                f"stop it first, or set {INSTANCE_ENV} to run another one"
            )
        self.is_owner = True  # from here on this instance is ours to clean up
        self._remove_leftovers()
        # first: E-stop and abort requests and heartbeats, before any process that uses them
        self.board = SafetyBoard.create()
        nml_file = self._nml_file()
        config = load_config(nml_file)
        say(f"NML buffers from {nml_file}")
        self.nml = Nml(config, _master_process(config))
        self.outbox = Outbox(self.nml[EMC_ERROR])
        os.environ["CNC_NML_FILE"] = nml_file
        os.environ["CNC_INI_FILE"] = self.ini_path
        os.environ.update(self._linuxcnc_environment(nml_file))
        # replaceable trajectory planner and homing modules, read by motmod (ARCH-008)
        for section, key, env, override in (
            ("TRAJ", "TPMOD", "CNC_TPMOD", self.options.tpmod),
            ("EMCMOT", "HOMEMOD", "CNC_HOMEMOD", self.options.homemod),
        ):
            value = override or (self.ini.find(section, key) or "").strip()
            if value:
                os.environ[env] = value
        self._start_host()
        if io_program(self.ini):  # (our iocontrol whatever program the INI names)
            say("starting iocontrol")
            self._halcmd(
                "loadusr",
                "-Wn",
                "iocontrol",
                sys.executable,
                "-m",
                "iocontrol",
                "-ini",
                self.ini_path,
            )
        halui = (self.ini.find("HAL", "HALUI") or "").strip()
        if halui:  # before the HAL files, which may net its pins (as LinuxCNC starts it)
            say(f"starting {halui}")
            self._halcmd("loadusr", "-Wn", "halui", halui, "-ini", self.ini_path)
        self._run_hal_files()
        # as LinuxCNC's launcher: task starts in the background, the threads tick, the
        # display starts at once (a script that waits for motion's pins finds the display
        # soon after), and the machine is ready when task has published its first status
        self._start_task()
        for line in self.ini.findall("HAL", "HALCMD"):
            self._halcmd(*shlex.split(line))
        self._halcmd("start")  # the threads run from now on, as LinuxCNC starts them here
        self._start_display()
        self._await_task()
        if self._display_name() == "web" and self.display is not None:
            # LinuxCNC's GUIs run the POSTGUI files once their pins exist; ours does not
            # run HAL files itself, so the launcher does it for it
            self._run_postgui_files()
        write_runtime_info(self.ini_path, nml_file)  # scripts find it from now on
        self._start_bridges()
        _remember_last_config(self.ini_path)
        say(f"machine ready ({self.ini_path})")

    def _remove_leftovers(self) -> None:
        """A previous run killed with SIGKILL (its processes stopped with it, through
        PR_SET_PDEATHSIG) leaves its shared memory and semaphores: say whose, remove them."""
        stale = read_runtime_info(is_stale_included=True)
        leftovers = remove_instance_objects()
        if leftovers:
            whose = f" (launcher pid {stale.pid}, gone, {stale.ini})" if stale else ""
            say(
                f"removed {len(leftovers)} shared-memory objects left by a previous run of "
                f"instance '{current_instance()}'{whose}"
            )

    def _nml_file(self) -> str:
        name = self.ini.find("EMC", "NML_FILE")
        if not name:
            return str(DEFAULT_NML_FILE)
        path = Path(name).expanduser()
        if not path.is_absolute():
            path = self.folder / path
        if not path.exists():
            entry = self.ini.entry("EMC", "NML_FILE")
            raise LaunchError(f"{entry.file}:{entry.line}: NML file not found: {path}")
        return str(path)

    def _start_host(self) -> None:
        from hal.rtapi_app import host_environment  # the host's module, only when needed

        say("starting the realtime host")
        self.host = subprocess.Popen(
            [sys.executable, "-m", "hal.rtapi_app"],
            env=host_environment(),
            stdout=subprocess.PIPE,
            cwd=self.folder,
            process_group=0,  # Ctrl-C reaches the launcher, which stops things in order
            preexec_fn=die_with_parent,
        )
        line = self.host.stdout.readline().decode(errors="replace").strip()
        if line != "rtapi_app: ready":
            raise LaunchError(f"the realtime host did not start ({line or 'no answer'})")

    def _linuxcnc_environment(self, nml_file: str) -> dict[str, str]:
        """What LinuxCNC's launcher exports for HAL files, Tcl scripts and GUIs."""
        from hal.hallib import exported_environment

        env = exported_environment(self.folder, self.options.hal_dirs)
        env.update(
            INI_FILE_NAME=self.ini_path,
            CONFIG_DIR=str(self.folder),
            NMLFILE=nml_file,
            LINUXCNCVERSION=LINUXCNC_VERSION,
            PATH=f"{self.folder / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
        )
        for section, key, name in (
            ("TRAJ", "COORDINATES", "TRAJ_COORDINATES"),
            ("KINS", "KINEMATICS", "KINS_KINEMATICS"),
        ):
            value = self.ini.find(section, key)
            if value is not None:
                env[name] = value
        return env

    def _run_hal_files(self) -> None:
        """[HAL]HALFILE entries: found as LinuxCNC finds them, .hal by halcmd, .tcl by Tcl,
        in two passes with [HAL]TWOPASS (cnc.halfiles)."""
        from cnc.halfiles import find_halfiles, run_halfiles
        from hal.core import HalError

        try:
            halfiles = find_halfiles(self.ini, self.folder, self.options.hal_dirs)
        except HalError as exc:
            raise LaunchError(str(exc)) from None
        if not halfiles:
            return
        self.is_hal_loaded = True
        try:
            twopass = (self.ini.find("HAL", "TWOPASS") or "").strip()
            is_ok = run_halfiles(self._hal(), self.ini, halfiles, say=say, twopass=twopass)
        except HalError as exc:  # no Tcl for a .tcl file
            raise LaunchError(str(exc)) from None
        if not is_ok and not self.options.is_keep_going:
            raise LaunchError("a HAL file failed (see the message above)")

    def _run_postgui_files(self) -> None:
        """[HAL]POSTGUI_HALFILE entries, then [HAL]POSTGUI_HALCMD lines (GUI-016)."""
        from cnc.halfiles import run_halfiles
        from hal.core import HalError
        from hal.hallib import find_halfile

        entries = self.ini.entries("HAL", "POSTGUI_HALFILE")
        commands = self.ini.findall("HAL", "POSTGUI_HALCMD")
        if not entries and not commands:
            return
        self._wait_for_display_pins()
        try:
            halfiles = [find_halfile(e.value, self.folder, self.options.hal_dirs) for e in entries]
        except HalError as exc:
            raise LaunchError(f"[HAL]POSTGUI_HALFILE: {exc}") from None
        is_ok = run_halfiles(self._hal(), self.ini, halfiles, say=say)
        if not is_ok and not self.options.is_keep_going:
            raise LaunchError("a POSTGUI_HALFILE failed (see the message above)")
        for line in commands:
            self._halcmd(*shlex.split(line))

    def _halcmd(self, *words: str) -> None:
        """One halcmd command in this process's halcmd session (it prints file:line errors)."""
        self.is_hal_loaded = True
        if not self._hal().run_words(list(words)):
            raise LaunchError(f"halcmd {' '.join(words)} failed (see the message above)")

    def _hal(self):
        """The launcher's halcmd session, with ``[SECTION]KEY`` taken from the INI; made
        once the realtime host runs (a halcmd process per step costs ~0.3 s each)."""
        if self.hal_session is None:
            from cnc.halfiles import LauncherHalCmd
            from hal.halcmd import VERBOSITY_ERRORS, VERBOSITY_INFO

            os.chdir(self.folder)  # HAL files name their files relative to the config
            is_verbose = self.options.is_verbose or self.options.is_debug
            self.hal_session = LauncherHalCmd(
                ini=self.ini,
                is_headless=self.is_headless or not self._display_name(),
                is_keep_going=self.options.is_keep_going,
                verbosity=VERBOSITY_INFO if is_verbose else VERBOSITY_ERRORS,
            )
            self.hal_session.is_echo = self.options.is_debug
            self.hal_session.child_setup = die_with_parent  # loadusr'd programs (iocontrol)
        return self.hal_session

    def _start_task(self) -> None:
        say("starting task")
        self.task = subprocess.Popen(
            [sys.executable, "-m", "task", "-ini", self.ini_path],
            cwd=self.folder,
            process_group=0,
            preexec_fn=die_with_parent,
        )

    def _await_task(self) -> None:
        """Until task has published its first status."""
        # no time limit while task lives (a loaded computer starts slowly; LinuxCNC's
        # launcher waits as long): said once after a while, Ctrl-C ends the wait
        status = self.nml[EMC_STATUS]
        said_at = time.monotonic() + READY_TIMEOUT_S
        while status.peek() is None:
            if self.task.poll() is not None:
                raise LaunchError(f"task exited at start-up (status {self.task.returncode})")
            if time.monotonic() > said_at:
                say(f"still waiting for task's first status ({READY_TIMEOUT_S:g} s and more)")
                said_at = float("inf")
            time.sleep(0.01)

    def _display_name(self) -> str:
        """[DISPLAY]DISPLAY's program, "" for none."""
        words = (self.ini.find("DISPLAY", "DISPLAY") or "").split()
        return words[0] if words else ""

    def _start_display(self) -> None:
        display = (self.ini.find("DISPLAY", "DISPLAY") or "").strip()
        if self.is_headless or not display:
            say("no display (headless): stop with Ctrl-C or SIGTERM")
            return
        words = [*shlex.split(display), *self.options.display_args]
        if words[0] in OUR_DISPLAYS:
            command = [sys.executable, "-m", "cnc", *OUR_DISPLAYS[words[0]], *words[1:]]
            command.append(self.ini_path)
        elif words[0] == "linuxcncrsh":  # LinuxCNC's remote shell: ours, same arguments
            command = [sys.executable, "-m", "cnc", "rsh", *words[1:], "--", "-ini"]
            command.append(self.ini_path)
        elif words[0] == "dummy":  # LinuxCNC's placeholder display: runs until Enter
            print("DUMMY DISPLAY MODULE, press <ENTER> to continue.", flush=True)
            command = [sys.executable, "-c", "import sys; sys.stdin.readline()"]
        else:  # as LinuxCNC starts its GUIs: the INI first, then the display's arguments
            command = [words[0], "-ini", self.ini_path, *words[1:]]
        say(f"starting the display: {' '.join(words)}")
        try:
            self.display = subprocess.Popen(command, cwd=self.folder)
        except OSError as exc:
            raise LaunchError(f"cannot start [DISPLAY]DISPLAY = {display}: {exc}") from None

    def _start_bridges(self) -> None:
        """The MQTT and OPC UA bridges the INI enables: UIs, not supervised children."""
        from cnc.bridges.supervisor import BridgeSupervisor

        self.bridges = BridgeSupervisor(
            self.config, self.ini_path, self.folder, say, child_setup=die_with_parent
        )
        self.bridges.start()

    def _wait_for_display_pins(self) -> None:
        """Before POSTGUI_HALFILE: the display's own HAL component must exist, as LinuxCNC's
        GUIs run that file only once their pins are made (ours: ``web`` makes one for its
        [DISPLAY] MESSAGE_PINNAME / MULTIMESSAGE_ID dialogs)."""
        display = shlex.split(self.ini.find("DISPLAY", "DISPLAY") or "") or [""]
        has_messages = self.ini.find("DISPLAY", "MESSAGE_PINNAME") or self.ini.find(
            "DISPLAY", "MULTIMESSAGE_ID"
        )
        if self.display is None or display[0] != "web" or not has_messages:
            return
        from hal.core import HalError

        try:
            self._hal().wait_ready("web", self.display)
        except HalError as exc:
            raise LaunchError(f"the display's HAL pins: {exc}") from None

    # ------------------------------------------------------------------ running
    def display_status(self) -> int | None:
        """The display's exit status once it has exited (``cnc run`` exits with it, as
        ``linuxcnc`` does), else None."""
        if self.display is None:
            return None
        return self.display.poll()

    def wait(self) -> int:
        """Until the display exits, a signal arrives, or task or the host dies. Every
        process the launcher started is watched: one that ends while the machine runs is
        a lost process (nml/safety.py): motion brakes, the machine goes to E-stop and
        every UI is told which; heartbeats that stop are found here too."""
        while not self.is_stopping:
            if self.display is not None and self.display.poll() is not None:
                return 0
            for name, proc in self._children():
                if proc.poll() is not None and proc.pid not in self.reported_exits:
                    self.reported_exits.add(proc.pid)
                    status = self._child_exited(name, proc)
                    if status is not None:
                        return status
            for buffer in self.nml.channels.values():  # (garbage over a header)
                buffer.claim_as_master()
            for lost in self.board.find_lost():
                self.board.request_estop(lost.reason, is_braking=True)
            for lost in self.board.take_unreported():
                self.outbox.error(f"E-stop: {lost.reason}")
            self._make_lost_outputs_safe()
            self.outbox.flush()
            if self.bridges is not None:
                self.bridges.check()
            time.sleep(0.05)
        return 0

    def _children(self) -> list[tuple[str, subprocess.Popen[bytes]]]:
        children = [("task", self.task), ("the realtime host", self.host)]
        if self.hal_session is not None:
            children += list(self.hal_session.user_procs.items())
        return [(name, proc) for name, proc in children if proc is not None]

    def _child_exited(self, name: str, proc: subprocess.Popen[bytes]) -> int | None:
        """React to a child that ended: E-stop if it carried safety I/O; the status to exit
        with if the machine cannot go on without it (task, the realtime host)."""
        how = _exit_description(proc.returncode)
        reason = f"{name} (pid {proc.pid}) {how}"
        lost = self.board.mark_lost(proc.pid, reason)
        if lost is not None or proc in (self.task, self.host):
            self.board.request_estop(reason, is_braking=True)
        self._make_lost_outputs_safe()
        for told in self.board.take_unreported():
            self.outbox.error(f"E-stop: {told.reason}")
        if lost is None and proc in (self.task, self.host):
            self.outbox.error(f"E-stop: {reason}")
        self.outbox.flush()
        say(f"{reason}" + ("; shutting down" if proc in (self.task, self.host) else ""))
        if proc is self.task:
            self._save_positions_for_task()
            return 1
        if proc is self.host:
            return 1
        return None

    def _make_lost_outputs_safe(self) -> None:
        """A lost iocontrol (dead or frozen) no longer writes its HAL outputs, which hold
        their last values: the E-stop chain would stay closed. Write their safe values,
        through any signal they drive, once per loss."""
        for lost in self.board.lost():
            if lost.name != "iocontrol" or lost.pid in self.made_safe:
                continue
            self.made_safe.add(lost.pid)
            from iocontrol.controller import SAFE_OUTPUTS

            hal = self._hal().hal
            for pin_name, value in SAFE_OUTPUTS.items():
                found = hal.find_pin(pin_name)
                if found is not None:
                    pin = found[1]
                    hal.write_slot(pin["type"], hal.ptr[pin["slot"]], value)

    def _save_positions_for_task(self, timeout: float = BRAKE_TIMEOUT_S + 1.0) -> None:
        """Task died without saving the joint positions: save the ones motion reports once
        it has braked to rest (task/positions.py), so the next start knows where it is."""
        name = (self.ini.find("TRAJ", "POSITION_FILE") or "").strip()
        if not name:
            return
        path = Path(name).expanduser()
        path = path if path.is_absolute() else self.folder / path
        status = None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with contextlib.suppress(NmlError):
                status = self.nml[MOTION_STATUS].peek()
            if status is not None and status.traj.inpos and not status.traj.current_vel:
                break
            time.sleep(0.01)
        if status is None:
            return
        try:
            write_positions(path, [joint.output for joint in status.joint])
        except OSError as exc:
            self.outbox.error(f"cannot save the joint positions to {path}: {exc}")

    # ------------------------------------------------------------------ shut-down
    def stop(self) -> None:
        """Stop everything that was started, newest first; safe to call at any point."""
        if not self.is_owner:
            return  # refused before starting anything: another machine's things stay
        say("shutting down")
        if self.board is not None:
            self.board.begin_shutdown()  # processes leaving now are not lost
        if self.bridges is not None:
            self.bridges.stop()
        _terminate(self.display, "display")
        _terminate(self.task, "task", timeout=10)
        if self.is_hal_loaded and self.host is not None and self.host.poll() is None:
            with contextlib.suppress(Exception):  # HAL may be half made after a failed start
                self._hal().run_words(["unload", "all"])
        if self.hal_session is not None:
            self.hal_session.hal.close()
        _terminate(self.host, "realtime host")
        if self.nml is not None:
            if self.outbox is not None:
                self.outbox.flush()
            self.nml.close()
        if self.board is not None:
            self.board.unlink()
        remove_runtime_info()
        leftovers = remove_instance_objects()
        if leftovers:
            say(f"removed {len(leftovers)} shared-memory objects left by crashed processes")
        if self.instance_lock is not None:
            release_instance(self.instance_lock)
            self.instance_lock = None
        say("stopped")


def die_with_parent() -> None:
    """In a child before exec: SIGTERM when the launcher dies, even by kill -9, so a killed
    launcher never leaves a machine running without its master (Linux PR_SET_PDEATHSIG)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def _master_process(config: NmlConfig) -> str:
    """The NML process that creates the buffers: ours is ``cnc``, LinuxCNC's ``emcsvr``."""
    masters = [p.name for p in config.processes if p.is_master]
    if "cnc" in masters:
        return "cnc"
    if not masters:
        raise LaunchError(f"{config.path}: no P line is master of the buffers")
    return masters[0]


def _terminate(proc: subprocess.Popen[bytes] | None, name: str, timeout: float = 5) -> None:
    if proc is None or proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(timeout)
    except subprocess.TimeoutExpired:
        say(f"{name} did not stop within {timeout:g} s: killing it")
        proc.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(5)


def say(text: str) -> None:
    print(f"cnc: {text}", file=sys.stderr, flush=True)


def _exit_description(returncode: int) -> str:
    if returncode < 0:
        try:
            return f"was killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"was killed by signal {-returncode}"
    return f"exited with status {returncode}"


def _last_config_file() -> Path:
    base = os.environ.get("XDG_CONFIG_HOME") or os.path.expanduser("~/.config")
    return Path(base) / "cnc" / "last-config"


def _remember_last_config(ini_path: str) -> None:
    """For ``cnc run -l``: the INI file of the last machine started."""
    with contextlib.suppress(OSError):
        path = _last_config_file()
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, ini_path + "\n")


def last_config() -> str | None:
    """``-l``: the last INI file started here, else LinuxCNC's (``~/.linuxcncrc``
    ``[PICKCONFIG]LAST_CONFIG``, written by its configuration picker)."""
    with contextlib.suppress(OSError):
        return _last_config_file().read_text().strip() or None
    with contextlib.suppress(OSError, IniError):
        return IniFile.load(os.path.expanduser("~/.linuxcncrc")).find("PICKCONFIG", "LAST_CONFIG")
    return None


def parse_arguments(argv: list[str]) -> tuple[argparse.Namespace, LaunchOptions]:
    """``linuxcnc``'s command line: options, then the INI file, then arguments for the
    display (LinuxCNC's EXTRA_ARGS)."""
    parser = argparse.ArgumentParser(
        prog="cnc run",
        description=__doc__.split("\n\n")[0],
        epilog="Options are LinuxCNC's: linuxcnc [options] INI becomes cnc run [options] INI.",
    )
    parser.add_argument("--headless", action="store_true", help="run without [DISPLAY]DISPLAY")
    parser.add_argument("-d", dest="is_debug", action="store_true", help="debug: echo HAL commands")
    parser.add_argument("-v", dest="is_verbose", action="store_true", help="verbose HAL commands")
    parser.add_argument(
        "-r", dest="is_runtests", action="store_true", help="accepted (output is never redirected)"
    )
    parser.add_argument("-l", dest="is_last", action="store_true", help="the last INI file used")
    parser.add_argument(
        "-k", dest="is_keep_going", action="store_true", help="go on past HAL errors"
    )
    parser.add_argument(
        "-H",
        dest="hal_dirs",
        action="append",
        default=[],
        metavar="DIR",
        help="search DIR for HAL files first (repeatable)",
    )
    parser.add_argument("-t", dest="tpmod", default="", help="trajectory planner module")
    parser.add_argument("-m", dest="homemod", default="", help="homing module")
    parser.add_argument("ini", nargs="?", help="the machine's INI file ('-': the last one)")
    parser.add_argument("display_args", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if "--headless" in args.display_args:  # also accepted after the INI file
        args.display_args.remove("--headless")
        args.headless = True
    for folder in args.hal_dirs:
        if not os.path.isdir(folder):
            parser.error(f"-H {folder}: not a folder")
    options = LaunchOptions(
        is_keep_going=args.is_keep_going,
        is_verbose=args.is_verbose,
        is_debug=args.is_debug,
        hal_dirs=[os.path.abspath(d) for d in reversed(args.hal_dirs)],  # the last -H first
        tpmod=args.tpmod,
        homemod=args.homemod,
        display_args=args.display_args,
    )
    if args.is_last or args.ini == "-":
        args.ini = last_config()
        if args.ini is None:
            parser.error("-l: no INI file was used before")
    elif args.ini is None:
        parser.error("the INI file is required (or -l for the last one used)")
    return args, options


def main(argv: list[str]) -> int:
    args, options = parse_arguments(argv)
    protect_output()  # `cnc run ... | head` must not kill the machine when head exits
    try:
        launcher = Launcher(args.ini, is_headless=args.headless, options=options)
    except IniError as exc:  # nothing was started
        for line in str(exc).splitlines():  # every problem found (cnc.inischema)
            say(line)
        return 1

    def on_signal(signum: int, _frame: object) -> None:
        launcher.is_stopping = True

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    status = 1
    try:
        launcher.start()
        status = launcher.wait()
        display_status = launcher.display_status()
        if display_status is not None:  # the display ended the run: its status is ours
            status = display_status
    except (LaunchError, NmlError, IniError) as exc:
        say(str(exc))
    finally:
        launcher.stop()
    return status
