"""halcmd: LinuxCNC's HAL command language, for HAL files and the command line.

``cnc halcmd [-f FILE] [-i INI] [-k] [-s] [-e] [-q|-Q|-v|-V] [-R] [COMMAND ARGS...]``.
Without a command or file it reads commands interactively with a ``halcmd:`` prompt. Errors
name the file and line (``file:line: cause``). As in LinuxCNC: ``-q`` (the default) prints
errors and what commands are asked to print; ``-Q`` also silences show/list/status/save;
``-v`` (and ``-V``) adds a ``file:line:`` message for what each command did; ``-e`` echoes
each command on stderr; ``-R`` releases a HAL mutex left held by a crashed program and exits.
Realtime commands (loadrt, unloadrt) go to the realtime host, started on the first
``loadrt``; everything else acts on HAL shared memory directly.
"""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TextIO

from hal import show, tools
from hal.core import (
    HAL_IN,
    HAL_OUT,
    HAL_RO,
    NSLOTS,
    TYPE_NAMES,
    TYPES_BY_NAME,
    Hal,
    HalError,
    format_value,
    is_compliant_name,
    parse_value,
    release_hal_mutex,
)
from hal.hallib import find_halfile  # LinuxCNC's HAL file search (the INI's folder, LIB:)
from hal.rtapi_app import HostClient, purge_dead_components, release_if_unused
from nml.shmem import is_process_alive

# halcmd's message levels: -Q, -q (default), -v, -V
VERBOSITY_SILENT, VERBOSITY_ERRORS, VERBOSITY_INFO, VERBOSITY_DEBUG = 0, 1, 2, 3
USR_READY_PACIFY_S = 2.0  # LinuxCNC's halcmd says it is still waiting after 2 s
# LinuxCNC's lock bits: tune = load + config, so setp and start/stop stay allowed
LOCK_LEVELS = {"none": 0, "load": 1, "config": 2, "params": 4, "run": 8, "tune": 3, "all": 255}
# halcmd's variable names: letters, digits, '.', '-', '_'; parentheses allow any name
_INI_REF = re.compile(r"\[([^\]]*)\](?:\(([^)]*)\)|([A-Za-z0-9._-]+))")
_ENV_REF = re.compile(r"\$(?:\(([^)]*)\)|([A-Za-z0-9._-]+))")
_ARROWS = ("=>", "<=", "<=>")
# LinuxCNC's HAL tools that HAL files start with loadusr, and what does their job here
USERSPACE_TOOLS = {
    "halsampler": [sys.executable, "-m", "cnc", "hal", "sample"],
    "halstreamer": [sys.executable, "-m", "cnc", "hal", "stream"],
    "halui": [sys.executable, "-m", "cnc.halui"],
    "mb2hal": [sys.executable, "-m", "hal.modbus.mb2hal"],
    "hy_vfd": [sys.executable, "-m", "hal.modbus.hy_vfd"],
    "motion-logger": [sys.executable, "-m", "motion.logger"],
    "mqtt-publisher": [sys.executable, "-m", "cnc.bridges.mqtt_publisher"],
    "xhc-hb04": [sys.executable, "-m", "hal.xhc_hb04"],
    # simulated hardware for the sim configs (not LinuxCNC programs)
    "hm2_sim": [sys.executable, "-m", "hal.hm2.sim"],
    "hy_vfd_sim": [sys.executable, "-m", "hal.modbus.vfd_sim"],
}


def userspace_command(args: list[str]) -> list[str]:
    """What runs for ``loadusr PROGRAM ARGS``: our tool for LinuxCNC's HAL tools, and this
    Python for a Python program (``python3 x.py`` or a file whose ``#!`` line names
    python), so that its ``import hal`` is ours whatever interpreter its first line names."""
    program, rest = args[0], args[1:]
    if program in USERSPACE_TOOLS:
        return [*USERSPACE_TOOLS[program], *rest]
    if program in ("python", "python3"):
        return [sys.executable, *rest]
    path = shutil.which(program) if "/" not in program else program
    if path is not None:
        with contextlib.suppress(OSError), open(path, "rb") as handle:
            first = handle.readline(256)
            if first.startswith(b"#!") and b"python" in first:
                return [sys.executable, path, *rest]
    return args


# halsampler and halstreamer run in a fork of this process (ForkedTool): the hal.tools verb
FORKED_TOOLS = {"halsampler": "sample", "halstreamer": "stream"}


class ForkedTool:
    """``loadusr halsampler ...`` run in a fork of this process rather than in a new Python:
    HAL's modules are loaded already, so the tool starts within milliseconds, as LinuxCNC's C
    one does. A new interpreter takes 0.1 s to over a second, while a sampler of depth 100
    on a 1 ms thread fills in 0.1 s and then drops samples. The part of ``Popen`` that
    halcmd uses."""

    def __init__(self, args: list[str], child_setup: Callable[[], None] | None) -> None:
        self.args = args
        self.returncode: int | None = None
        verb = FORKED_TOOLS[args[0]]
        for stream in (sys.stdout, sys.stderr):
            stream.flush()  # (or the child would write the parent's buffered text again)
        self.pid = os.fork()
        if self.pid == 0:  # the child: run the tool, never return into halcmd
            code = 1
            try:
                for number in (signal.SIGINT, signal.SIGTERM, signal.SIGPIPE):
                    signal.signal(number, signal.SIG_DFL)
                null = os.open(os.devnull, os.O_RDONLY)
                os.dup2(null, 0)
                if child_setup is not None:
                    child_setup()
                code = tools.main([verb, *args[1:]])
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 0
            except BaseException:  # whatever happens, the child must end here
                traceback.print_exc()
            finally:
                with contextlib.suppress(Exception):
                    sys.stdout.flush()
                    sys.stderr.flush()
                os._exit(code)

    @staticmethod
    def can_run(program: str) -> bool:
        """Forking is safe only in a single-threaded process (no lock held by another
        thread can be copied locked into the child)."""
        return program in FORKED_TOOLS and threading.active_count() == 1

    def poll(self) -> int | None:
        if self.returncode is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if deadline is not None and time.monotonic() > deadline:
                raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
            time.sleep(0.005)
        return self.returncode  # type: ignore[return-value]


# ---------------------------------------------------------------- helpers
def strip_comment(line: str) -> str:
    """The line up to a ``#`` outside double quotes (halcmd's comment rule)."""
    is_quoted = False
    for index, char in enumerate(line):
        if char == '"':
            is_quoted = not is_quoted
        elif char == "#" and not is_quoted:
            return line[:index]
    if is_quoted:
        raise HalError("unterminated quoted string")
    return line


def tokenize(line: str) -> list[str]:
    """Split a (comment-free, substituted) HAL line into words; double quotes group."""
    lexer = shlex.shlex(line, posix=True)
    lexer.whitespace_split = True
    lexer.commenters = ""
    try:
        return list(lexer)
    except ValueError as exc:
        raise HalError(f"bad quoting: {exc}") from None


def logical_lines(lines: Iterable[str]) -> Iterable[tuple[int, str]]:
    """(first line number, text) with backslash continuations joined."""
    pending, start = "", 0
    for number, raw in enumerate(lines, 1):
        text = raw.rstrip("\n").rstrip("\r")
        if not pending:
            start = number
        if text.endswith("\\"):
            pending += text[:-1]
            continue
        yield start, pending + text
        pending = ""
    if pending:
        yield start, pending


class HalCmd:
    """One halcmd session: runs commands against the HAL of the current instance."""

    def __init__(
        self,
        hal: Hal | None = None,
        *,
        ini: Any = None,
        is_keep_going: bool = False,
        is_script: bool = False,
        verbosity: int = 1,
        out: TextIO | None = None,
        err: TextIO | None = None,
        host: HostClient | None = None,
    ) -> None:
        self.hal = hal or Hal()
        self.ini = ini
        self.is_keep_going = is_keep_going
        self.is_script = is_script
        self.verbosity = verbosity
        self.out = out or sys.stdout
        self.err = err or sys.stderr
        self.host = host or HostClient()
        self.is_echo = False
        self.is_quit = False
        self.where = ""
        self.user_procs: dict[str, subprocess.Popen[bytes] | ForkedTool] = {}
        # run in each loadusr'd program before exec (the launcher ties them to its life)
        self.child_setup: Callable[[], None] | None = None
        self.warned_names: set[str] = set()
        #: this session's own HAL component (``join_hal``), "" when none
        self.own_component = ""
        self.verbs: dict[str, Callable[[list[str]], None]] = {
            name[3:]: getattr(self, name) for name in dir(self) if name.startswith("do_")
        }

    # ------------------------------------------------------------ running
    def join_hal(self) -> None:
        """Appear in HAL as user component ``halcmd<pid>`` while running, as LinuxCNC's
        halcmd does (``show comp`` and ``list comp`` list it)."""
        name = f"halcmd{os.getpid()}"
        if name not in self.hal.meta["comps"]:
            with self.hal.edit():
                self.hal.new_component(name, "user")
                self.hal.ready(name)
            self.own_component = name

    def leave_hal(self) -> None:
        if self.own_component:
            with contextlib.suppress(HalError):
                self.hal.remove_component(self.own_component)
            self.own_component = ""

    def error(self, cause: str) -> None:
        prefix = f"{self.where}: " if self.where else ""
        print(f"{prefix}{cause}", file=self.err, flush=True)

    @property
    def is_quiet(self) -> bool:
        """-Q: show, list, status and save print nothing (errors still do)."""
        return self.verbosity == VERBOSITY_SILENT

    def info(self, text: str) -> None:
        """A -v message: what a command did, as ``file:line: text`` on stdout."""
        if self.verbosity >= VERBOSITY_INFO:
            print(f"{self.where or '<commandline>:0'}: {text}", file=self.out, flush=True)

    def run_lines(self, lines: Iterable[str], source: str) -> int:
        """Run commands; returns the number of failed commands (stops at the first unless -k)."""
        failures = 0
        for number, text in logical_lines(lines):
            self.where = f"{source}:{number}"
            if not self.run_line(text, number):
                failures += 1
                if not self.is_keep_going:
                    break
            if self.is_quit:
                break
        return failures

    def run_file(self, path: str) -> int:
        try:
            with open(path, encoding="utf-8", errors="replace") as handle:
                lines = handle.readlines()
        except OSError as exc:
            self.error(f"cannot open '{path}': {exc.strerror}")
            return 1
        return self.run_lines(lines, path)

    def run_line(self, text: str, number: int = 0) -> bool:
        """Run one command line; False (and an error printed) when it failed."""
        try:
            words = tokenize(self.substitute(strip_comment(text)))
        except HalError as exc:
            self.error(str(exc))
            return False
        if not words:
            return True
        if self.is_echo:  # -e or 'echo': each command on stderr, as halcmd does
            print(f"({number})<echo>: {' '.join(words)}", file=self.err, flush=True)
        return self.run_words(words)

    def run_words(self, words: list[str]) -> bool:
        if len(words) == 3 and words[1] == "=":
            words = ["setp", words[0], words[2]]
        verb = words[0].lower()
        handler = self.verbs.get(verb)
        if handler is None:
            self.error(f"Unknown command '{words[0]}'")
            return False
        try:
            handler(words[1:])
        except HalError as exc:
            self.error(str(exc))
            return False
        except (KeyError, IndexError, ValueError) as exc:
            self.error(f"{verb}: {type(exc).__name__}: {exc}")
            return False
        return True

    def substitute(self, line: str) -> str:
        """Replace ``[SECTION]KEY`` / ``[SECTION](KEY)`` by INI values and ``$VAR`` /
        ``$(VAR)`` by environment values, in the whole line before it is split into words
        (so ``loadrt [KINS]KINEMATICS`` may bring its own arguments), as halcmd does."""

        def ini_value(found: re.Match[str]) -> str:
            section, key = found.group(1), found.group(2) or found.group(3)
            if self.ini is None:
                raise HalError(f"Ini variable '[{section}]{key}' used but no INI file (-i)")
            value = self.ini.find(section, key)
            if value is None:
                raise HalError(f"Ini variable '[{section}]{key}' not found")
            return value

        def env_value(found: re.Match[str]) -> str:
            name = found.group(1) or found.group(2)
            value = os.environ.get(name)
            if value is None:
                raise HalError(f"Environment variable '{name}' not found")
            return value

        if "[" in line:
            if "]" not in line[line.index("[") :]:
                raise HalError("Missing close square bracket")
            line = _INI_REF.sub(ini_value, line)
        if "$" in line:
            line = _ENV_REF.sub(env_value, line)
        return line

    @staticmethod
    def _need(args: list[str], low: int, high: int | None, usage: str) -> None:
        if len(args) < low or (high is not None and len(args) > high):
            raise HalError(f"usage: {usage}")

    def _check_lock(self, level: int, action: str) -> None:
        if self.hal.meta["lock"] & level:
            raise HalError(f"HAL is locked, {action} is not permitted")

    # ------------------------------------------------------------ components
    def do_loadrt(self, args: list[str]) -> None:
        self._need(args, 1, None, "loadrt name [key=value...]")
        self._check_lock(1, "loading")
        if not self.host.is_running():
            purge_dead_components(self.hal)  # leftovers of a host that crashed
        self.host.ensure()
        self.host.call({"cmd": "loadrt", "name": args[0], "args": args[1:]})
        self.info(f"Realtime module '{args[0]}' loaded")

    def do_unloadrt(self, args: list[str]) -> None:
        self._need(args, 1, 1, "unloadrt name|all")
        if not self.host.is_running():
            raise HalError(f"component '{args[0]}' not loaded")
        if args[0] == "all":
            self.host.call({"cmd": "unloadall"})
        else:
            self.host.call({"cmd": "unloadrt", "name": args[0]})
            self.info(f"Realtime module '{args[0]}' unloaded")

    def do_loadusr(self, args: list[str]) -> None:
        self._need(args, 1, None, "loadusr [-W|-w|-i|-n name] program [args...]")
        is_wait_ready = is_wait_exit = is_ignore_rc = False
        comp_name = None
        while args and args[0].startswith("-"):
            flag = args.pop(0)
            if flag in ("-W", "-Wn", "-nW"):
                is_wait_ready = True
            if flag in ("-n", "-Wn", "-nW"):
                comp_name = args.pop(0)
            elif flag == "-w":
                is_wait_exit = True
            elif flag == "-i":
                is_ignore_rc = True
            elif flag not in ("-W",):
                raise HalError(f"loadusr: unknown option '{flag}'")
        if not args:
            raise HalError("loadusr: no program given")
        comp_name = comp_name or Path(args[0]).stem
        proc: subprocess.Popen[bytes] | ForkedTool
        try:
            if ForkedTool.can_run(args[0]):
                proc = ForkedTool(args, self.child_setup)
            else:
                args = userspace_command(args)
                proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, preexec_fn=self.child_setup)
        except OSError as exc:
            raise HalError(f"loadusr: cannot run '{args[0]}': {exc.strerror}") from None
        self.user_procs[comp_name] = proc
        if is_wait_exit:
            rc = proc.wait()
            if rc and not is_ignore_rc:
                raise HalError(f"program '{args[0]}' failed, returned {rc}")
            self.info(f"Program '{args[0]}' finished")
            return
        if is_wait_ready:
            self.wait_ready(comp_name, proc)
            self.info(f"Component '{comp_name}' ready")
        self.info(f"Program '{args[0]}' started")

    def wait_ready(self, comp_name: str, proc: subprocess.Popen[bytes] | ForkedTool) -> None:
        """Until ``proc`` has made component ``comp_name`` ready (``loadusr -W``); HalError
        if it exits first. As LinuxCNC's halcmd, no time limit (a loaded machine starts
        slowly, it must not fail to start): after 2 s it says what it waits for, then a dot
        a second; Ctrl-C ends the wait."""
        started = time.monotonic()
        next_word = started + USR_READY_PACIFY_S
        is_pacifying = False
        while True:
            comp = self.hal.meta["comps"].get(comp_name)
            if comp and comp["is_ready"]:
                break
            if proc.poll() is not None:
                if is_pacifying:
                    print(file=sys.stderr)
                raise HalError(f"{Path(proc.args[0]).name} exited without becoming ready")
            now = time.monotonic()
            if now >= next_word:
                text = f"Waiting for component '{comp_name}' to become ready"
                text = "." if is_pacifying else text
                print(text, end="", file=sys.stderr, flush=True)
                is_pacifying = True
                next_word = now + 1.0
            time.sleep(0.01)
        if is_pacifying:
            print(file=sys.stderr)

    def do_waitusr(self, args: list[str]) -> None:
        self._need(args, 1, 1, "waitusr name")
        comp = self.hal.meta["comps"].get(args[0])
        if comp is None or comp["kind"] != "user":
            raise HalError(f"component '{args[0]}' not found or not a user space component")
        self.info(f"Waiting for component '{args[0]}'")
        proc = self.user_procs.pop(args[0], None)
        if proc is not None:
            proc.wait()
        while (comp := self.hal.meta["comps"].get(args[0])) is not None:
            if not is_process_alive(comp["pid"]):
                # it died without removing its component: do it for it
                with contextlib.suppress(HalError):
                    self.hal.remove_component(args[0])
                break
            time.sleep(0.05)
        self.info(f"Component '{args[0]}' finished")

    def do_unloadusr(self, args: list[str]) -> None:
        self._need(args, 1, 1, "unloadusr name|all")
        meta = self.hal.meta
        names = [
            n
            for n, c in meta["comps"].items()
            if c["kind"] == "user"
            and (args[0] == "all" or n == args[0])
            and c["pid"] != os.getpid()
        ]
        if not names and args[0] != "all":
            raise HalError(f"user space component '{args[0]}' not found")
        for name in names:
            self._stop_user(name, meta["comps"][name]["pid"])

    def _stop_user(self, name: str, pid: int) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGTERM)
        deadline = time.monotonic() + 5
        while name in self.hal.meta["comps"] and time.monotonic() < deadline:
            proc = self.user_procs.get(name)
            if proc is not None:
                proc.poll()
            if not is_process_alive(pid):
                break  # died without removing its component: remove it below
            time.sleep(0.02)
        if name in self.hal.meta["comps"]:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
            with contextlib.suppress(HalError):
                self.hal.remove_component(name)
        proc = self.user_procs.pop(name, None)
        if proc is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=5)

    def do_unload(self, args: list[str]) -> None:
        self._need(args, 1, 1, "unload name|all")
        self._check_lock(1, "unloading")
        comps = self.hal.meta["comps"]
        if args[0] == "all":
            self.do_unloadusr(["all"])
            if self.host.is_running():
                self.host.call({"cmd": "unloadall"})
            return
        comp = comps.get(args[0])
        if comp is None:
            raise HalError(f"component '{args[0]}' not found")
        if comp["kind"] == "user":
            self.do_unloadusr(args)
        else:
            self.do_unloadrt(args)

    # ------------------------------------------------------------ signals and links
    def warn_name(self, kind: str, name: str) -> None:
        """Warn (once per name) about names that break HAL-005's naming rules."""
        if not is_compliant_name(name) and name not in self.warned_names:
            self.warned_names.add(name)
            print(
                f"{self.where + ': ' if self.where else ''}Warning: {kind} name '{name}' does "
                "not follow the HAL naming rules (lowercase letters, digits, '.' and '-')",
                file=self.err,
            )

    def do_newsig(self, args: list[str]) -> None:
        self._need(args, 2, 2, "newsig signame type")
        self._check_lock(2, "newsig")
        if args[1] not in TYPES_BY_NAME:
            raise HalError(f"Unknown signal type '{args[1]}'")
        self.hal.new_signal(args[0], TYPES_BY_NAME[args[1]])
        self.warn_name("signal", args[0])

    def do_delsig(self, args: list[str]) -> None:
        self._need(args, 1, 1, "delsig signame|all")
        self._check_lock(2, "delsig")
        names = list(self.hal.meta["sigs"]) if args[0] == "all" else [args[0]]
        for name in names:
            self.hal.delete_signal(name)
            self.info(f"Signal '{name}' deleted'")  # sic: halcmd's stray quote

    def do_net(self, args: list[str]) -> None:
        self._need(args, 1, None, "net signame [=>|<=|<=>] pin...")
        self._check_lock(2, "net")
        sig, pins = args[0], [a for a in args[1:] if a not in _ARROWS]
        meta = self.hal.meta
        if self.hal.find_pin(sig) is not None:
            raise HalError(f"Signal name '{sig}' must not be the same as a pin.")
        found = []
        for name in pins:
            pin = self.hal.find_pin(name)
            if pin is None:
                raise HalError(f"Pin '{name}' does not exist")
            if pin[1]["sig"] is not None and pin[1]["sig"] != sig:
                raise HalError(f"Pin '{name}' was already linked to signal '{pin[1]['sig']}'")
            found.append(pin)
        with self.hal.edit():
            if sig not in meta["sigs"]:
                if not found:
                    raise HalError(f"signal '{sig}' does not exist and no pins given")
                self.hal.new_signal(sig, found[0][1]["type"])
                self.warn_name("signal", sig)
            # writers first, so a second writer is refused before anything is linked
            ordered = sorted(found, key=lambda p: p[1]["dir"] == HAL_IN)
            for name, _ in ordered:
                self.hal.link(name, sig)
        for name in pins:
            self.info(f"Pin '{name}' linked to signal '{sig}'")

    def do_linkps(self, args: list[str]) -> None:
        args = [a for a in args if a not in _ARROWS]
        self._need(args, 2, 2, "linkps pinname signame")
        self._check_lock(2, "linkps")
        self.hal.link(args[0], args[1])
        self.info(f"Pin '{args[0]}' linked to signal '{args[1]}'")

    def do_linksp(self, args: list[str]) -> None:
        args = [a for a in args if a not in _ARROWS]
        self._need(args, 2, 2, "linksp signame pinname")
        self._check_lock(2, "linksp")
        self.hal.link(args[1], args[0])
        self.info(f"Pin '{args[1]}' linked to signal '{args[0]}'")

    def do_linkpp(self, args: list[str]) -> None:
        args = [a for a in args if a not in _ARROWS]
        self._need(args, 2, 2, "linkpp pin1 pin2")
        self._check_lock(2, "linkpp")
        first = self.hal.find_pin(args[0])
        if first is None:
            raise HalError(f"pin '{args[0]}' not found")
        with self.hal.edit():  # LinuxCNC names the new signal after the first pin
            self.hal.new_signal(args[0], first[1]["type"])
            self.hal.link(args[0], args[0])
            self.hal.link(args[1], args[0])
        for name in args:
            self.info(f"Pin '{name}' linked to signal '{args[0]}'")

    def do_unlinkp(self, args: list[str]) -> None:
        self._need(args, 1, 1, "unlinkp pinname")
        self._check_lock(2, "unlinkp")
        self.hal.unlink(args[0])
        self.info(f"Pin '{args[0]}' unlinked")

    # ------------------------------------------------------------ values
    def do_setp(self, args: list[str]) -> None:
        self._need(args, 2, 2, "setp name value")
        self._check_lock(4, "setp")
        self.info(f"setting parameter '{args[0]}' to '{args[1]}'")
        param = self.hal.find_param(args[0])
        if param is not None:
            _name, info = param
            if info["dir"] == HAL_RO:
                raise HalError(f"param '{args[0]}' is not writable")
            self.hal.write_slot(info["type"], info["slot"], self._parse(info["type"], args[1]))
            self.info(f"Parameter '{args[0]}' set to {args[1]}")
            return
        pin = self.hal.find_pin(args[0])
        if pin is None:
            raise HalError(f"parameter or pin '{args[0]}' not found")
        _name, info = pin
        if info["dir"] == HAL_OUT:
            raise HalError(f"pin '{args[0]}' is not writable")
        if info["sig"] is not None:
            raise HalError(f"pin '{args[0]}' is connected to a signal")
        self.hal.write_slot(info["type"], info["slot"], self._parse(info["type"], args[1]))
        self.info(f"Pin '{args[0]}' set to {args[1]}")

    @staticmethod
    def _parse(hal_type: int, text: str) -> int | float:
        return parse_value(hal_type, text)

    def do_sets(self, args: list[str]) -> None:
        self._need(args, 2, 2, "sets signame value")
        self._check_lock(4, "sets")
        sig = self.hal.meta["sigs"].get(args[0])
        if sig is None:
            raise HalError(f"signal '{args[0]}' not found")
        if sig["writers"]:  # I/O pins share a signal with whoever sets it, as in LinuxCNC
            raise HalError(f"signal '{args[0]}' already has writer(s)")
        self.hal.write_slot(sig["type"], sig["slot"], parse_value(sig["type"], args[1]))
        self.info(f"Signal '{args[0]}' set to {args[1]}")

    def _lookup(self, name: str) -> tuple[str, int, int | float]:
        """(kind, type, value) of a pin or parameter."""
        param = self.hal.find_param(name)
        if param is not None:
            info = param[1]
            return "param", info["type"], self.hal.read_slot(info["type"], info["slot"])
        pin = self.hal.find_pin(name)
        if pin is not None:
            return "pin", pin[1]["type"], self.hal.pin_value(pin[1])
        raise HalError(f"pin or parameter '{name}' not found")

    def do_getp(self, args: list[str]) -> None:
        self._need(args, 1, 1, "getp name")
        _, hal_type, value = self._lookup(args[0])
        print(format_value(hal_type, value, is_show=False), file=self.out)

    def do_ptype(self, args: list[str]) -> None:
        self._need(args, 1, 1, "ptype name")
        print(TYPE_NAMES[self._lookup(args[0])[1]], file=self.out)

    def do_gets(self, args: list[str]) -> None:
        self._need(args, 1, 1, "gets signame")
        sig = self.hal.meta["sigs"].get(args[0])
        if sig is None:
            raise HalError(f"signal '{args[0]}' not found")
        value = self.hal.read_slot(sig["type"], sig["slot"])
        print(format_value(sig["type"], value, is_show=False), file=self.out)

    def do_stype(self, args: list[str]) -> None:
        self._need(args, 1, 1, "stype signame")
        sig = self.hal.meta["sigs"].get(args[0])
        if sig is None:
            raise HalError(f"signal '{args[0]}' not found")
        print(TYPE_NAMES[sig["type"]], file=self.out)

    # ------------------------------------------------------------ functions and threads
    def do_addf(self, args: list[str]) -> None:
        self._need(args, 2, 3, "addf funcname threadname [position]")
        self._check_lock(2, "addf")
        try:
            position = int(args[2]) if len(args) == 3 else -1
        except ValueError:
            raise HalError(f"addf: position '{args[2]}' is not a whole number") from None
        self.hal.add_funct(args[0], args[1], position)
        self.info(f"Function '{args[0]}' added to thread '{args[1]}'")

    def do_delf(self, args: list[str]) -> None:
        self._need(args, 1, 2, "delf funcname [threadname]")
        self._check_lock(2, "delf")
        if len(args) == 2:
            threads = [args[1]]
        else:
            threads = [t for t, i in self.hal.meta["threads"].items() if args[0] in i["functs"]]
            if not threads:
                raise HalError(f"function '{args[0]}' not linked to any thread")
        for thread in threads:
            self.hal.del_funct(args[0], thread)
            self.info(f"Function '{args[0]}' removed from thread '{thread}'")

    def do_start(self, args: list[str]) -> None:
        self._check_lock(8, "start")
        self.hal.set_running(True)
        self.info("Realtime threads started")

    def do_stop(self, args: list[str]) -> None:
        self._check_lock(8, "stop")
        self.hal.set_running(False)
        self.info("Realtime threads stopped")

    # ------------------------------------------------------------ aliases and locks
    def do_alias(self, args: list[str]) -> None:
        self._need(args, 3, 3, "alias pin|param name alias")
        kind, real, alias = args
        table, objects = self._alias_tables(kind)
        if real not in self.hal.meta[objects]:
            raise HalError(f"{kind} '{real}' not found")
        with self.hal.edit() as meta:
            if alias in meta["pins"] or alias in meta["params"] or alias in meta[table]:
                raise HalError(f"duplicate name '{alias}'")
            meta[table] = {k: v for k, v in meta[table].items() if v != real}
            meta[table][alias] = real
        self.info(f"{kind} '{real}' aliased to '{alias}'")

    def do_unalias(self, args: list[str]) -> None:
        self._need(args, 2, 2, "unalias pin|param alias")
        table, _ = self._alias_tables(args[0])
        with self.hal.edit() as meta:
            name = args[1]
            if name not in meta[table]:
                name = next((k for k, v in meta[table].items() if v == args[1]), "")
            if not name:
                raise HalError(f"alias '{args[1]}' not found")
            del meta[table][name]
        self.info(f"{args[0]} '{args[1]}' unaliased")

    @staticmethod
    def _alias_tables(kind: str) -> tuple[str, str]:
        if kind == "pin":
            return "pin_alias", "pins"
        if kind in ("param", "parameter"):
            return "param_alias", "params"
        raise HalError(f"Unknown alias type '{kind}'")

    def do_lock(self, args: list[str]) -> None:
        level = LOCK_LEVELS.get(args[0] if args else "all")
        if level is None:
            raise HalError(f"Unknown lock type '{args[0]}'")
        with self.hal.edit() as meta:
            meta["lock"] = level
        self.info("Locking completed")

    def do_unlock(self, args: list[str]) -> None:
        level = LOCK_LEVELS.get(args[0] if args else "all")
        if level is None:
            raise HalError(f"Unknown unlock type '{args[0]}'")
        with self.hal.edit() as meta:
            meta["lock"] &= ~level
        self.info("Unlocking completed")

    # ------------------------------------------------------------ misc
    def do_echo(self, args: list[str]) -> None:
        self.is_echo = True
        print("Echo on", file=self.out)

    def do_unecho(self, args: list[str]) -> None:
        self.is_echo = False
        print("Echo off", file=self.out)

    def do_source(self, args: list[str]) -> None:
        self._need(args, 1, 1, "source filename")
        where = self.where
        failures = self.run_file(args[0])
        self.where = where
        if failures:
            raise HalError(f"source of '{args[0]}' failed")

    def do_quit(self, args: list[str]) -> None:
        self.is_quit = True

    do_exit = do_quit

    def do_help(self, args: list[str]) -> None:
        if args:
            text = HELP.get(args[0])
            if text is None:
                raise HalError(f"No help for unknown command '{args[0]}'")
            print(text, file=self.out)
            return
        print("Available commands:", file=self.out)
        for verb, text in HELP.items():
            print(f"  {verb:<14} {text.splitlines()[0]}", file=self.out)

    def do_status(self, args: list[str]) -> None:
        if self.is_quiet:
            return
        meta = self.hal.meta
        lock = meta["lock"]
        lines = ["HAL locking status:", f"  current lock value {lock} ({lock:02x})"]
        if not lock:
            lines.append("  HAL_LOCK_NONE - nothing is locked")
        for bit, text in (
            (1, "HAL_LOCK_LOAD    - loading of new components is locked"),
            (2, "HAL_LOCK_CONFIG  - link and addf is locked"),
            (4, "HAL_LOCK_PARAMS  - setting params is locked"),
            (8, "HAL_LOCK_RUN     - running/stopping HAL is locked"),
        ):
            if lock & bit:
                lines.append(f"  {text}")
        lines += [
            "HAL memory status",
            f"  used/total value slots:     {meta['next_slot'] - len(meta['free'])}/{NSLOTS}",
            f"  active components:          {len(meta['comps'])}",
            f"  active pins:                {len(meta['pins'])}",
            f"  active parameters:          {len(meta['params'])}",
            f"  active aliases:             {len(meta['pin_alias']) + len(meta['param_alias'])}",
            f"  active signals:             {len(meta['sigs'])}",
            f"  active functions:           {len(meta['functs'])}",
            f"  active threads:             {len(meta['threads'])}",
        ]
        print("\n".join(lines), file=self.out)

    # ------------------------------------------------------------ show / list / save
    def do_show(self, args: list[str]) -> None:
        if self.is_quiet:
            return
        kind = args[0] if args else None
        text = show.show(self.hal, kind, args[1:], is_script=self.is_script)
        print(text, file=self.out, end="")

    def do_list(self, args: list[str]) -> None:
        if not args:
            raise HalError("'list' requires type'")  # (sic)
        if self.is_quiet:
            return
        print(show.listing(self.hal, args[0], args[1:]), file=self.out, end="")

    def do_save(self, args: list[str]) -> None:
        self._need(args, 0, 2, "save [type] [filename]")
        if self.is_quiet:
            return
        text = show.save(self.hal, args[0] if args else "all")
        if len(args) > 1:
            try:
                Path(args[1]).write_text(text, encoding="utf-8")
            except OSError:
                raise HalError(f"Can't open 'save' destination '{args[1]}'") from None
        else:
            print(text, file=self.out, end="")

    def do_setexact_for_test_suite_only(self, args: list[str]) -> None:
        """Let thread periods be exactly what was asked for (ours always are): allowed
        before the first thread only, as in LinuxCNC."""
        with self.hal.edit() as meta:
            if meta["threads"]:
                raise HalError("HAL_LIB: Cannot run 'setexact' after a thread has been created")
            meta["is_period_exact"] = True
        print(
            f"{self.where + ': ' if self.where else ''}HAL_LIB: HAL will pretend that the exact "
            "base period requested is possible.\nThis mode is not suitable for running real "
            "hardware.",
            file=self.err,
        )

    # ------------------------------------------------------------ interactive
    def interactive(self, stream: TextIO) -> int:
        failures = 0
        is_tty = stream.isatty()
        if is_tty:
            with contextlib.suppress(ImportError):
                import readline  # noqa: F401 - line editing and history for input()
        number = 0
        while not self.is_quit:
            if is_tty:
                try:
                    line = input("halcmd: ")
                except EOFError:
                    break
            else:
                line = stream.readline()
                if not line:
                    break
            number += 1
            self.where = "" if is_tty else f"<stdin>:{number}"
            if not self.run_line(line, number):
                failures += 1
        return failures


HELP = {
    "loadrt": "loadrt name [key=value...]\n  Loads realtime component 'name' into the host.",
    "loadusr": "loadusr [-W|-w|-i|-n name] program [args...]\n  Starts a user space program;"
    " -W waits for its component to be ready, -w for it to exit.",
    "waitusr": "waitusr name\n  Waits for user space component 'name' to exit.",
    "unload": "unload name|all\n  Unloads a component (realtime or user space).",
    "unloadrt": "unloadrt name|all\n  Unloads a realtime component.",
    "unloadusr": "unloadusr name|all\n  Stops a user space component.",
    "net": "net signame [pin...]\n  Creates signal 'signame' if needed and links the pins.",
    "newsig": "newsig signame type\n  Creates a signal of type bit, float, s32, u32, s64, u64.",
    "delsig": "delsig signame|all\n  Deletes signals, unlinking their pins.",
    "linkps": "linkps pinname signame\n  Links a pin to a signal.",
    "linksp": "linksp signame pinname\n  Links a signal to a pin.",
    "linkpp": "linkpp pin1 pin2\n  Links two pins through a signal named after the first.",
    "unlinkp": "unlinkp pinname\n  Unlinks a pin from its signal.",
    "setp": "setp name value\nname = value\n  Sets a parameter or an unconnected input pin.",
    "getp": "getp name\n  Prints the value of a pin or parameter.",
    "ptype": "ptype name\n  Prints the type of a pin or parameter.",
    "sets": "sets signame value\n  Sets a signal that has no writer.",
    "gets": "gets signame\n  Prints the value of a signal.",
    "stype": "stype signame\n  Prints the type of a signal.",
    "addf": "addf funcname threadname [position]\n  Adds a function to a thread.",
    "delf": "delf funcname [threadname]\n  Removes a function from a thread.",
    "start": "start\n  Starts running the realtime threads' functions.",
    "stop": "stop\n  Stops running the realtime threads' functions.",
    "show": "show [comp|pin|sig|param|funct|thread|alias|all] [pattern]\n  Shows HAL objects.",
    "list": "list comp|pin|sig|param|funct|thread [pattern]\n  Lists names only.",
    "save": "save [all|comp|alias|sig|net|netl|param|thread] [file]\n  Prints HAL commands"
    " that rebuild the current configuration.",
    "source": "source filename\n  Runs the commands of another HAL file.",
    "alias": "alias pin|param name alias\n  Gives a pin or parameter a second name.",
    "unalias": "unalias pin|param alias\n  Removes an alias.",
    "lock": "lock [none|tune|all]\n  Locks HAL against changes.",
    "unlock": "unlock [tune|all]\n  Unlocks HAL.",
    "status": "status\n  Prints the HAL lock status and object counts.",
    "echo": "echo\n  Echoes each command before running it.",
    "unecho": "unecho\n  Stops echoing commands.",
    "help": "help [command]\n  Lists commands or explains one.",
    "quit": "quit\n  Leaves the interactive halcmd.",
    "exit": "exit\n  Leaves the interactive halcmd.",
}


def parse_options(argv: list[str]) -> tuple[dict[str, Any], list[str]]:
    """halcmd's getopt-style options; returns (options, remaining command words)."""
    opts: dict[str, Any] = {
        "file": None,
        "ini": None,
        "keep": False,
        "script": False,
        "verbosity": VERBOSITY_ERRORS,
        "echo": False,
        "release_mutex": False,
    }
    args = list(argv)
    while args and args[0].startswith("-") and len(args[0]) > 1:
        flag = args.pop(0)
        for index, letter in enumerate(flag[1:]):
            rest = flag[index + 2 :]
            if letter in "fi":
                value = rest or (args.pop(0) if args and not args[0].startswith("-") else None)
                if letter == "i" and value is None:
                    raise HalError("-i needs an INI file")
                opts["file" if letter == "f" else "ini"] = value if value is not None else "-"
                break
            if letter == "k":
                opts["keep"] = True
            elif letter == "s":
                opts["script"] = True
            elif letter == "q":
                opts["verbosity"] = VERBOSITY_ERRORS
            elif letter == "Q":
                opts["verbosity"] = VERBOSITY_SILENT
            elif letter == "v":
                opts["verbosity"] = VERBOSITY_INFO
            elif letter == "V":
                opts["verbosity"] = VERBOSITY_DEBUG
            elif letter == "e":
                opts["echo"] = True
            elif letter == "R":
                opts["release_mutex"] = True
            elif letter == "h":
                opts["help"] = True
            else:
                raise HalError(f"unknown option '-{letter}'")
    return opts, args


def make_session(opts: dict[str, Any], **kwargs: Any) -> HalCmd:
    ini = None
    if opts["ini"]:
        from cnc.ini import IniFile

        ini = IniFile.load(opts["ini"])
    session = HalCmd(
        ini=ini,
        is_keep_going=opts["keep"],
        is_script=opts["script"],
        verbosity=opts["verbosity"],
        **kwargs,
    )
    session.is_echo = opts["echo"]
    session.join_hal()
    return session


def run_session(session: HalCmd, opts: dict[str, Any], words: list[str]) -> int:
    if opts["file"] and opts["file"] != "-":
        failures = session.run_file(opts["file"])
    elif words:
        failures = 0 if session.run_words(words) else 1
    else:
        failures = session.interactive(sys.stdin)
    return 1 if failures else 0


def run_ini_halfiles(ini_path: str, *, is_postgui: bool = False, **kwargs: Any) -> int:
    """Run an INI file's ``[HAL]HALFILE`` entries in order, then its ``[HAL]HALCMD`` lines,
    as LinuxCNC's launcher does (``POSTGUI_HALFILE`` entries when ``is_postgui``).

    Returns the number of failed commands; errors are printed as ``file:line: cause``.
    The realtime host must already run (or is started by the first ``loadrt``).
    """
    from cnc.ini import IniFile

    ini = IniFile.load(ini_path)
    session = HalCmd(ini=ini, **kwargs)
    failures = 0
    try:
        key = "POSTGUI_HALFILE" if is_postgui else "HALFILE"
        for value in ini.findall("HAL", key):
            try:
                path = find_halfile(value, Path(ini_path).resolve().parent).path
                if path.suffix == ".tcl":
                    raise HalError(f"HAL file '{value}': Tcl HAL files are not supported")
            except HalError as exc:
                session.where = f"{ini_path}: [HAL]{key}"
                session.error(str(exc))
                return failures + 1
            failures += session.run_file(str(path))
            if failures and not session.is_keep_going:
                return failures
        if not is_postgui:
            for number, line in enumerate(ini.findall("HAL", "HALCMD"), 1):
                session.where = f"{ini_path}: [HAL]HALCMD #{number}"
                if not session.run_line(line, number):
                    failures += 1
                    if not session.is_keep_going:
                        break
        return failures
    finally:
        session.hal.close()


def main(argv: list[str] | None = None) -> int:
    try:
        opts, words = parse_options(sys.argv[1:] if argv is None else argv)
    except HalError as exc:
        print(f"halcmd: {exc}", file=sys.stderr)
        return 2
    if opts.get("help"):
        print(__doc__)
        return 0
    if opts["release_mutex"]:  # like halcmd -R: release, run nothing else
        if release_hal_mutex() is None:
            print("HALCMD: Release Mutex failed!")
            return 1
        return 0
    try:
        session = make_session(opts)
    except Exception as exc:  # a bad INI file: IniError carries file:line
        print(f"halcmd: {exc}", file=sys.stderr)
        return 1
    try:
        return run_session(session, opts, words)
    finally:
        session.leave_hal()
        if not session.host.is_running():
            release_if_unused(session.hal)
        session.hal.close()
