"""``cnc run CONFIG.ini``: start a machine from its INI file, like LinuxCNC's ``linuxcnc``.

Start-up, in LinuxCNC's order (ARCH-009/010): the NML buffers (this process is their master),
the realtime host, iocontrol ([EMCIO]EMCIO, as the userspace HAL component ``iocontrol``),
[HAL]HALUI (``halui`` is ``cnc.halui``), the HAL files ([HAL]HALFILE, then [HAL]HALCMD
lines, with ``[SECTION]KEY`` taken from the INI), task ([TASK]TASK), the display
([DISPLAY]DISPLAY), then [HAL]POSTGUI_HALFILE.

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
from pathlib import Path

from cnc.ini import IniError
from cnc.inischema import check_machine
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

READY_TIMEOUT_S = 20.0
PR_SET_PDEATHSIG = 1
# [DISPLAY]DISPLAY values that are our own user interfaces (anything else is run as given)
OUR_DISPLAYS = {"top": ["top"], "sh": ["sh"], "web": ["ui", "web"]}


class LaunchError(Exception):
    """A start-up step failed; the message says which and why."""


class Launcher:
    def __init__(self, ini_path: str, is_headless: bool = False) -> None:
        self.ini_path = os.path.abspath(ini_path)  # not through symlinks, as LinuxCNC
        self.folder = Path(self.ini_path).parent
        self.is_headless = is_headless
        # the INI file against the schema, its tool table and .var file, before anything starts
        self.config = check_machine(self.ini_path)
        self.ini = self.config.ini
        for warning in self.config.warnings:
            say(f"warning: {warning}")
        self.nml: Nml | None = None
        self.host: subprocess.Popen[bytes] | None = None
        self.task: subprocess.Popen[bytes] | None = None
        self.display: subprocess.Popen[bytes] | None = None
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
        # replaceable trajectory planner and homing modules, read by motmod (ARCH-008)
        for section, key, env in (
            ("TRAJ", "TPMOD", "CNC_TPMOD"),
            ("EMCMOT", "HOMEMOD", "CNC_HOMEMOD"),
        ):
            value = (self.ini.find(section, key) or "").strip()
            if value:
                os.environ[env] = value
        self._start_host()
        if self.ini.find("EMCIO", "EMCIO"):
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
        for hal_file in self.ini.findall("HAL", "HALFILE"):
            self._run_hal_file(hal_file)
        for line in self.ini.findall("HAL", "HALCMD"):
            self._halcmd(*shlex.split(line))
        self._halcmd("start")  # the threads run from now on, as LinuxCNC starts them here
        self._start_task()
        self._start_display()
        postgui_files = self.ini.findall("HAL", "POSTGUI_HALFILE")
        if postgui_files:
            self._wait_for_display_pins()
        for hal_file in postgui_files:
            self._run_hal_file(hal_file)
        write_runtime_info(self.ini_path, nml_file)  # scripts find it from now on
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

    def _run_hal_file(self, name: str) -> None:
        path = Path(name).expanduser()
        if not path.is_absolute():
            path = self.folder / path
        if not path.exists():
            raise LaunchError(f"{self.ini_path}: [HAL] file not found: {path}")
        if path.suffix == ".tcl":
            raise LaunchError(f"{path}: Tcl HAL files are not supported; use halcmd syntax")
        say(f"running {path.name}")
        self.is_hal_loaded = True
        if self._hal().run_file(str(path)):
            raise LaunchError(f"{path} failed (see the message above)")

    def _halcmd(self, *words: str) -> None:
        """One halcmd command in this process's halcmd session (it prints file:line errors)."""
        self.is_hal_loaded = True
        if not self._hal().run_words(list(words)):
            raise LaunchError(f"halcmd {' '.join(words)} failed (see the message above)")

    def _hal(self):
        """The launcher's halcmd session, with ``[SECTION]KEY`` taken from the INI; made
        once the realtime host runs (a halcmd process per step costs ~0.3 s each)."""
        if self.hal_session is None:
            from hal.halcmd import HalCmd

            os.chdir(self.folder)  # HAL files name their files relative to the config
            self.hal_session = HalCmd(ini=self.ini)
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
        status = self.nml[EMC_STATUS]
        deadline = time.monotonic() + READY_TIMEOUT_S
        while status.peek() is None:
            if self.task.poll() is not None:
                raise LaunchError(f"task exited at start-up (status {self.task.returncode})")
            if time.monotonic() > deadline:
                raise LaunchError(f"task did not publish its status within {READY_TIMEOUT_S} s")
            time.sleep(0.01)

    def _start_display(self) -> None:
        display = (self.ini.find("DISPLAY", "DISPLAY") or "").strip()
        if self.is_headless or not display:
            say("no display (headless): stop with Ctrl-C or SIGTERM")
            return
        words = shlex.split(display)
        if words[0] in OUR_DISPLAYS:
            command = [
                sys.executable,
                "-m",
                "cnc",
                *OUR_DISPLAYS[words[0]],
                *words[1:],
                self.ini_path,
            ]
        else:
            command = [*words, "-ini", self.ini_path]  # as LinuxCNC starts its GUIs
        say(f"starting the display: {' '.join(words)}")
        try:
            self.display = subprocess.Popen(command, cwd=self.folder)
        except OSError as exc:
            raise LaunchError(f"cannot start [DISPLAY]DISPLAY = {display}: {exc}") from None

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
            self._hal().wait_ready("web", self.display, timeout=READY_TIMEOUT_S)
        except HalError as exc:
            raise LaunchError(f"the display's HAL pins: {exc}") from None

    # ------------------------------------------------------------------ running
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


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc run", description=__doc__.split("\n\n")[0])
    parser.add_argument("ini", help="the machine's INI file")
    parser.add_argument("--headless", action="store_true", help="run without [DISPLAY]DISPLAY")
    args = parser.parse_args(argv)
    protect_output()  # `cnc run ... | head` must not kill the machine when head exits
    try:
        launcher = Launcher(args.ini, is_headless=args.headless)
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
    except (LaunchError, NmlError, IniError) as exc:
        say(str(exc))
    finally:
        launcher.stop()
    return status
