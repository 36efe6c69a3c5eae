"""``cnc sh``: a command shell for the controller, in the spirit of LinuxCNC's linuxcncrsh.

    cnc sh [INI_OR_NML] [-k] [-c "CMD; CMD ..."] [FILE]

Without ``-c`` or FILE it is interactive (line editing and history through readline);
with them, or with commands piped on stdin, it runs them in order and stops at the first
one that fails, unless ``-k``. ``;`` separates commands on one line; a line starting with
``#`` is a comment. A single argument ending in ``.ini`` or ``.nml`` names the machine
(default: the running one), any other is a script FILE.

Every command ends with one line: ``DONE``, or ``ERROR: why`` (an unknown command, a bad
argument, the controller's refusal with its error-channel message, no answer in time).
Commands sent to the controller wait until it has finished them (``set timeout S``, default
60 s). Operator messages that arrive meanwhile are printed. The exit status is 0 if every
command succeeded, 1 otherwise (2: bad arguments of ``cnc sh`` itself, 130: interrupted).
Numbers accept ``.`` or ``,`` as decimal separator.

``COMMANDS`` is the one table of commands; ``help`` lists it.
"""

from __future__ import annotations

import argparse
import cmd
import contextlib
import math
import os
import sys
import textwrap
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO, TypeVar

import cnc
from cnc.ui import formatting as fmt
from cnc.ui.controller import Controller, Message

PROMPT = "cnc> "
DEFAULT_TIMEOUT_S = 60.0  # how long a command may take (a long MDI move, homing)
WAIT_STEP_S = 1.0  # `wait` checks the controller at least this often
IDLE_POLL_S = 0.05  # `wait`: period of status polls until the interpreter is idle
HISTORY_FILE = Path("~/.cnc_sh_history")
HISTORY_LENGTH = 1000
HELP_WIDTH, HELP_COLUMN = 79, 41  # `help`: line width, width of the usage column

T = TypeVar("T")


class UsageError(Exception):
    """A command typed wrongly; the text says what is wrong."""


class CommandError(Exception):
    """The controller refused a command or did not finish it in time."""


@dataclass(frozen=True)
class Command:
    """One shell command: ``run(shell, text)`` gets the text after the command's name."""

    usage: str  # "jog JOINT|AXIS +|-|stop [SPEED]": the name, then the arguments
    summary: str  # for the list of commands
    details: str  # for `help NAME` (the summary if empty)
    run: Callable[[Shell, str], None]

    @property
    def name(self) -> str:
        return self.usage.split()[0]


COMMANDS: dict[str, Command] = {}  # name -> command, filled by @command below
ALIASES = {"exit": "quit", "abort": "stop", "?": "help"}


def command(
    usage: str, summary: str, details: str = ""
) -> Callable[[Callable[[Shell, str], None]], Any]:
    """Register the decorated function as the command described by ``usage``."""

    def register(run: Callable[[Shell, str], None]) -> Callable[[Shell, str], None]:
        entry = Command(usage, summary, details, run)
        COMMANDS[entry.name] = entry
        return run

    return register


# ------------------------------------------------------------------ the shell
class Shell:
    """Runs command lines against one controller and prints their outcome to ``out``."""

    def __init__(self, controller: Controller, out: TextIO | None = None) -> None:
        self.controller = controller
        self.out = out or sys.stdout
        self.timeout = DEFAULT_TIMEOUT_S
        self.is_quitting = False

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    def execute(self, text: str) -> bool:
        """Run one command; print its output, then DONE or ERROR. Whether it succeeded."""
        parts = text.split(maxsplit=1)
        if not parts:
            return True
        name = ALIASES.get(parts[0].lower(), parts[0].lower())
        rest = parts[1].strip() if len(parts) > 1 else ""
        entry = COMMANDS.get(name)
        if entry is None:
            self.say(f"ERROR: unknown command '{fmt.clean(name)}' (help lists the commands)")
            return False
        for message in self._read_messages():  # earlier messages, not this command's
            self.say(str(message))
        failure = self._attempt(entry, rest)
        # Error messages that arrive while a command runs make it fail, and say why.
        errors = [message.text for message in self._read_messages()]
        if errors:
            failure = "; ".join(fmt.clean(text) for text in errors)
        self.say("DONE" if failure is None else f"ERROR: {failure}")
        return failure is None

    def _attempt(self, entry: Command, rest: str) -> str | None:
        """Run a command; None if it succeeded, else why it failed."""
        try:
            entry.run(self, rest)
        except UsageError as exc:
            return f"{entry.name}: {exc} (usage: {entry.usage})"
        except CommandError as exc:
            return str(exc)
        except cnc.error as exc:
            self.controller.reset()  # not running: find it again at the next command
            return str(exc)
        except (ValueError, TypeError, OverflowError) as exc:  # the API's argument checks
            return f"{entry.name}: {exc}"
        except Exception as exc:  # a bug here must not end a script with a traceback
            return f"{entry.name}: unexpected {type(exc).__name__}: {exc}"
        return None

    def _read_messages(self) -> list[Message]:
        """The new error messages; the other operator messages are printed now."""
        try:
            messages = self.controller.read_messages()
        except cnc.error:
            return []  # not running: the command's own failure says so
        for message in messages:
            if not message.is_error:
                self.say(str(message))
        return [message for message in messages if message.is_error]

    def send(self, method: str, *args: Any) -> None:
        """Call ``cnc.command().<method>(*args)`` and wait until the controller has
        finished it; CommandError if it reports an error or takes longer than the
        timeout."""
        commands = self.controller.command
        getattr(commands, method)(*args)
        result = commands.wait_complete(self.timeout)
        if result == cnc.RCS_ERROR:
            raise CommandError("the controller reported an error")
        if result != cnc.RCS_DONE:
            raise CommandError(
                f"not finished after {self.timeout:g} s (it may still be running; "
                "'set timeout S' waits longer)"
            )

    def start(self, method: str, *args: Any) -> None:
        """Call ``cnc.command().<method>(*args)`` and wait only until the controller took
        it (a program run is answered when the program ends: ``wait`` waits for that);
        CommandError if it refuses it."""
        commands = self.controller.command
        getattr(commands, method)(*args)
        if commands.wait_complete(0) == cnc.RCS_ERROR:
            raise CommandError("the controller reported an error")

    def status(self) -> cnc.stat:
        """The controller's status, polled now."""
        return self.controller.poll()


# ------------------------------------------------------------------ argument helpers
ON_OFF = {"on": True, "off": False}


def words(text: str, least: int, most: int | None = None) -> list[str]:
    """The arguments, checking how many there are."""
    found = text.split()
    most = least if most is None else most
    if not least <= len(found) <= most:
        expected = str(least) if least == most else f"{least} to {most}"
        raise UsageError(f"expects {expected} argument{'' if least == most == 1 else 's'}")
    return found


def choice(word: str, choices: dict[str, T]) -> T:
    """The value of a keyword argument (case-insensitive)."""
    try:
        return choices[word.lower()]
    except KeyError:
        raise UsageError(f"'{fmt.clean(word)}' is not one of {'|'.join(choices)}") from None


def real(word: str, what: str, minimum: float = -math.inf) -> float:
    """A number argument ('.' or ',' as decimal separator) of at least ``minimum``."""
    try:
        value = fmt.parse_float(word)
    except ValueError as exc:
        raise UsageError(f"{what}: {exc}") from None
    if value < minimum:
        raise UsageError(f"{what} must be at least {minimum:g}")
    return value


def integer(word: str, what: str) -> int:
    try:
        return int(word)
    except ValueError:
        raise UsageError(f"{what}: '{fmt.clean(word)}' is not a whole number") from None


def joint_or_all(word: str) -> int:
    """``all`` (-1, every joint) or a joint number."""
    return -1 if word.lower() == "all" else integer(word, "joint")


# ------------------------------------------------------------------ machine and task
@command("estop on|off", "press (on) or reset (off) e-stop")
def _estop(shell: Shell, text: str) -> None:
    is_on = choice(*words(text, 1), ON_OFF)
    shell.send("state", cnc.STATE_ESTOP if is_on else cnc.STATE_ESTOP_RESET)


@command("machine on|off", "turn the machine on or off")
def _machine(shell: Shell, text: str) -> None:
    is_on = choice(*words(text, 1), ON_OFF)
    shell.send("state", cnc.STATE_ON if is_on else cnc.STATE_OFF)


@command("mode manual|auto|mdi", "set the task mode")
def _mode(shell: Shell, text: str) -> None:
    modes = {"manual": cnc.MODE_MANUAL, "auto": cnc.MODE_AUTO, "mdi": cnc.MODE_MDI}
    shell.send("mode", choice(*words(text, 1), modes))


@command("home all|JOINT", "home all joints or one")
def _home(shell: Shell, text: str) -> None:
    shell.send("home", joint_or_all(*words(text, 1)))


@command("unhome all|JOINT", "mark all joints or one as not homed")
def _unhome(shell: Shell, text: str) -> None:
    shell.send("unhome", joint_or_all(*words(text, 1)))


@command(
    "jog JOINT|AXIS +|-|stop|incr DIST [SPEED]",
    "jog a joint or an axis",
    "Jog a joint (0, 1 ...) or an axis (X, Y ...; teleop mode) continuously in the + or - "
    "direction until 'jog N stop', or by DIST. SPEED in units per minute; default: the "
    "INI's [DISPLAY]DEFAULT_LINEAR_VELOCITY or DEFAULT_ANGULAR_VELOCITY.",
)
def _jog(shell: Shell, text: str) -> None:
    args = words(text, 2, 4)
    target, action = args[0], args[1].lower()
    is_axis = len(target) == 1 and target.upper() in fmt.AXIS_LETTERS
    index = fmt.AXIS_LETTERS.index(target.upper()) if is_axis else integer(target, "joint")
    jjogmode = 0 if is_axis else 1  # LinuxCNC: 1 jogs a joint, 0 an axis (teleop)
    if action == "stop":
        words(text, 2)
        shell.send("jog", cnc.JOG_STOP, jjogmode, index)
    elif action == "incr":
        distance, *speed = words(text, 3, 4)[2:]
        velocity = _jog_speed(shell, speed, is_axis, index)
        shell.send("jog", cnc.JOG_INCREMENT, jjogmode, index, velocity, real(distance, "distance"))
    else:
        sign = choice(action, {"+": 1.0, "-": -1.0})
        velocity = _jog_speed(shell, words(text, 2, 3)[2:], is_axis, index)
        shell.send("jog", cnc.JOG_CONTINUOUS, jjogmode, index, sign * velocity)


@command(
    "vector VX VY VZ [VA VB VC]",
    "move at a cartesian velocity (teleop mode)",
    "Teleop mode: move at this velocity, per axis in units per minute, until 'vector 0 0 0'. "
    "Joint and axis limits slow it as a whole, keeping its direction.",
)
def _vector(shell: Shell, text: str) -> None:
    speeds = [real(word, "speed") / 60.0 for word in words(text, 3, 6)]
    shell.send("teleop_vector", *speeds)


def _jog_speed(shell: Shell, given: list[str], is_axis: bool, index: int) -> float:
    """The jog speed in units per second (what the API takes): the SPEED given in units
    per minute, else the INI's default for linear or angular jogs (units per second)."""
    if given:
        return real(given[0], "speed", minimum=0.0) / 60.0
    if is_axis:
        is_angular = fmt.AXIS_LETTERS[index] in "ABC"
    else:
        joint = fmt.item(shell.status().joint, index, {})
        is_angular = isinstance(joint, dict) and joint.get("jointType") == cnc.ANGULAR
    key = "DEFAULT_ANGULAR_VELOCITY" if is_angular else "DEFAULT_LINEAR_VELOCITY"
    default = shell.controller.ini_number("DISPLAY", key)
    if default is None:
        raise UsageError(f"give a SPEED: the INI file has no [DISPLAY]{key}")
    return default


@command("mdi GCODE", "execute a line of G-code (MDI mode)")
def _mdi(shell: Shell, text: str) -> None:
    if not text:
        raise UsageError("expects a line of G-code")
    shell.send("mdi", text)


@command("open FILE", "open a G-code program (AUTO mode)")
def _open(shell: Shell, text: str) -> None:
    if not text:
        raise UsageError("expects a file name")
    path = os.path.abspath(os.path.expanduser(text))
    if not os.path.isfile(path):
        raise CommandError(f"{path}: no such file")
    shell.send("program_open", path)


@command("run [LINE]", "run the open program (from LINE)")
def _run(shell: Shell, text: str) -> None:
    line = [integer(word, "line") for word in words(text, 0, 1)]
    shell.start("auto", cnc.AUTO_RUN, line[0] if line else 0)


@command("pause", "pause the running program")
def _pause(shell: Shell, text: str) -> None:
    words(text, 0)
    shell.send("auto", cnc.AUTO_PAUSE)


@command("resume", "resume the paused program")
def _resume(shell: Shell, text: str) -> None:
    words(text, 0)
    shell.send("auto", cnc.AUTO_RESUME)


@command("step", "run one line of the program, pause")
def _step(shell: Shell, text: str) -> None:
    words(text, 0)
    shell.send("auto", cnc.AUTO_STEP)


@command("stop", "abort the program, MDI and jogs")
def _stop(shell: Shell, text: str) -> None:
    words(text, 0)
    shell.send("abort")


@command("feed PERCENT", "set the feed override")
def _feed(shell: Shell, text: str) -> None:
    shell.send("feedrate", _percent(*words(text, 1)))


@command("rapid PERCENT", "set the rapid override")
def _rapid(shell: Shell, text: str) -> None:
    shell.send("rapidrate", _percent(*words(text, 1)))


def _percent(word: str) -> float:
    """A percentage ("50" or "50%") as a scale (0.5)."""
    return real(word.removesuffix("%"), "percent", minimum=0.0) / 100.0


@command(
    "spindle fwd|rev|off [RPM]",
    "start or stop the spindle",
    "Start the spindle forward or in reverse at RPM (default: the programmed S), or stop it.",
)
def _spindle(shell: Shell, text: str) -> None:
    args = words(text, 1, 2)
    direction = choice(
        args[0], {"fwd": cnc.SPINDLE_FORWARD, "rev": cnc.SPINDLE_REVERSE, "off": cnc.SPINDLE_OFF}
    )
    if direction == cnc.SPINDLE_OFF:
        words(text, 1)
        shell.send("spindle", cnc.SPINDLE_OFF)
        return
    if len(args) == 2:
        speed = real(args[1], "RPM", minimum=0.0)
    else:
        speed = fmt.item(shell.status().settings, 2, 0.0)
        if not speed > 0:
            raise UsageError("give an RPM: no S word has been programmed")
    shell.send("spindle", direction, speed)


@command("flood on|off", "turn flood coolant on or off")
def _flood(shell: Shell, text: str) -> None:
    is_on = choice(*words(text, 1), ON_OFF)
    shell.send("flood", cnc.FLOOD_ON if is_on else cnc.FLOOD_OFF)


@command("mist on|off", "turn mist coolant on or off")
def _mist(shell: Shell, text: str) -> None:
    is_on = choice(*words(text, 1), ON_OFF)
    shell.send("mist", cnc.MIST_ON if is_on else cnc.MIST_OFF)


# set NAME -> the command method taking on (1) or off (0)
SWITCHES = {
    "optional_stop": "set_optional_stop",
    "block_delete": "set_block_delete",
    "teleop": "teleop_enable",
}


@command(
    "set NAME VALUE",
    "set a switch or the timeout",
    "set optional_stop|block_delete|teleop on|off: switch M1 stops, block delete (/), "
    "teleop mode (axis jogging). set timeout S: how long a command may take (default 60).",
)
def _set(shell: Shell, text: str) -> None:
    name, value = words(text, 2)
    if name.lower() == "timeout":  # a setting of the shell, not of the controller
        shell.timeout = real(value, "timeout", minimum=0.0)
        return
    method = choice(name, SWITCHES)
    shell.send(method, 1 if choice(value, ON_OFF) else 0)


# ------------------------------------------------------------------ waiting, looking
@command(
    "wait [TIMEOUT]",
    "wait until the machine is idle",
    "Wait until the last command has finished, the interpreter is idle, motion is in "
    "position and no joint is homing, at most TIMEOUT seconds (default: no limit).",
)
def _wait(shell: Shell, text: str) -> None:
    limit = [real(word, "timeout", minimum=0.0) for word in words(text, 0, 1)]
    deadline = time.monotonic() + limit[0] if limit else math.inf
    commands = shell.controller.command
    if commands.serial:  # a command was sent: wait for its end first
        while commands.wait_complete(min(WAIT_STEP_S, _left(deadline))) == -1:
            if _left(deadline) == 0:
                raise CommandError("the last command is still running")
    while not _is_idle(shell.status()):
        if _left(deadline) == 0:
            raise CommandError("the machine is still busy")
        time.sleep(min(IDLE_POLL_S, _left(deadline)))


def _is_idle(status) -> bool:
    """Nothing runs: the interpreter is idle, motion in position, no joint homing (homing
    is acknowledged when it starts, as in LinuxCNC, and goes on after)."""
    homing = [joint.get("homing", 0) for joint in status.joint[: status.joints]]
    return status.interp_state == cnc.INTERP_IDLE and status.inpos and not any(homing)


def _left(deadline: float) -> float:
    return max(0.0, deadline - time.monotonic())


# show WHAT -> the status sections it prints, in order
SECTIONS: dict[str, tuple[Callable[[fmt.Status], list[str]], ...]] = {
    "pos": (fmt.position_lines, fmt.offset_lines),
    "joints": (fmt.joint_lines,),
    "state": (fmt.state_lines, fmt.program_lines, fmt.override_lines, fmt.spindle_lines),
    "tool": (fmt.tool_lines,),
    "gcodes": (fmt.active_codes,),
}


@command("show pos|joints|state|tool|gcodes|all", "print the status (default all)")
def _show(shell: Shell, text: str) -> None:
    what = words(text, 0, 1) or ["all"]
    if what[0].lower() == "all":
        sections = [section for group in SECTIONS.values() for section in group]
    else:
        sections = list(choice(what[0], SECTIONS))
    status = shell.status()
    for section in sections:
        for line in section(status):
            shell.say(line)


@command("errors", "print the last operator messages")
def _errors(shell: Shell, text: str) -> None:
    words(text, 0)
    history = shell.controller.history
    for message in history:
        shell.say(message.stamped())
    if not history:
        shell.say("no messages")


@command("sleep S", "do nothing for S seconds")
def _sleep(shell: Shell, text: str) -> None:
    time.sleep(real(*words(text, 1), "seconds", minimum=0.0))


@command("help [COMMAND]", "list the commands, describe one")
def _help(shell: Shell, text: str) -> None:
    asked = words(text, 0, 1)
    if asked:
        name = ALIASES.get(asked[0].lower(), asked[0].lower())
        entry = choice(name, COMMANDS)
        shell.say(entry.usage)
        for line in textwrap.wrap(entry.details or entry.summary, HELP_WIDTH - 4):
            shell.say(f"    {line}")
        return
    for entry in COMMANDS.values():
        shell.say(f"  {entry.usage:<{HELP_COLUMN}} {entry.summary}")
    shell.say("';' separates commands; numbers take '.' or ','; 'help NAME' says more")


@command("quit", "leave (also: exit, Ctrl-D)")
def _quit(shell: Shell, text: str) -> None:
    words(text, 0)
    shell.is_quitting = True


# ------------------------------------------------------------------ scripts, interaction
def split_commands(text: str, origin: str) -> Iterator[tuple[str, str]]:
    """The commands of a script or ``-c`` text as (``origin:line``, command)."""
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("#"):
            continue
        for part in line.split(";"):
            if part.strip():
                yield f"{origin}:{number}", part.strip()


def run_script(shell: Shell, commands: Iterable[tuple[str, str]], is_keep_going: bool) -> int:
    """Run commands, echoing each after the prompt; stop at the first failure unless
    ``is_keep_going``. The exit status: 0 if all succeeded, else 1."""
    has_failed = False
    for where, text in commands:
        shell.say(f"{PROMPT}{text}")
        if not shell.execute(text):
            has_failed = True
            if not is_keep_going:
                print(f"cnc sh: {where}: stopped at the first error (-k goes on)", file=sys.stderr)
                break
        if shell.is_quitting:
            break
    return 1 if has_failed else 0


class _Prompt(cmd.Cmd):
    """The interactive loop: readline editing, history and completion of command names."""

    prompt = PROMPT

    def __init__(self, shell: Shell) -> None:
        super().__init__()
        self.shell = shell
        self.has_failed = False

    def onecmd(self, line: str) -> bool:  # every line goes to the shell's command table
        if line == "EOF":  # Ctrl-D
            self.shell.say("")
            return True
        for _, text in split_commands(line, "input"):
            if not self.shell.execute(text):
                self.has_failed = True
            if self.shell.is_quitting:
                return True
        return False

    def emptyline(self) -> bool:
        return False  # cmd.Cmd would repeat the last command

    def completenames(self, text: str, *ignored: Any) -> list[str]:
        return [name for name in COMMANDS if name.startswith(text.lower())]


def interact(shell: Shell) -> int:
    """The interactive shell; Ctrl-C interrupts a command, Ctrl-D or quit leaves."""
    prompt = _Prompt(shell)
    history = _load_history()
    intro: str | None = "cnc sh: 'help' lists the commands, 'quit' leaves"
    try:
        while True:
            try:
                prompt.cmdloop(intro)
                break
            except KeyboardInterrupt:
                shell.say("\ninterrupted")
                intro = None
    finally:
        _save_history(history)
    return 1 if prompt.has_failed else 0


def _load_history() -> Any:
    """readline with the saved history, if readline is available."""
    try:
        import readline
    except ImportError:
        return None
    with contextlib.suppress(OSError):
        readline.read_history_file(HISTORY_FILE.expanduser())
    readline.set_history_length(HISTORY_LENGTH)
    return readline


def _save_history(readline: Any) -> None:
    if readline is not None:
        with contextlib.suppress(OSError):
            readline.write_history_file(HISTORY_FILE.expanduser())


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cnc sh",
        description="Command shell for the controller (like linuxcncrsh); 'help' lists the "
        "commands.",
    )
    parser.add_argument(
        "paths",
        nargs="*",
        metavar="INI_OR_NML|FILE",
        help="the machine (a .ini or .nml file; default: the running one), then a script",
    )
    parser.add_argument("-c", dest="commands", metavar="COMMANDS", help="run these commands")
    parser.add_argument(
        "-k",
        "--keep-going",
        dest="is_keep_going",
        action="store_true",
        help="go on after a failed command",
    )
    return parser


def _source_and_script(paths: list[str]) -> tuple[str | None, str | None]:
    """(INI or NML file, script file) from the positional arguments."""
    if len(paths) == 2:
        return paths[0], paths[1]
    if len(paths) == 1 and Path(paths[0]).suffix.lower() in (".ini", ".nml"):
        return paths[0], None
    return None, (paths[0] if paths else None)


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if len(args.paths) > 2:
        parser.error("give at most an INI or NML file and a script file")
    source, script = _source_and_script(args.paths)
    if script is not None and args.commands is not None:
        parser.error("give -c COMMANDS or a script FILE, not both")
    try:
        commands = None
        if args.commands is not None:
            commands = list(split_commands(args.commands, "-c"))
        elif script is not None:
            commands = list(split_commands(Path(script).read_text(encoding="utf-8"), script))
        elif not sys.stdin.isatty():
            commands = list(split_commands(sys.stdin.read(), "stdin"))
        controller = Controller(source)
    except (OSError, UnicodeDecodeError) as exc:
        print(f"cnc sh: cannot read {script or 'stdin'}: {exc}", file=sys.stderr)
        return 2
    except cnc.error as exc:
        print(f"cnc sh: {exc}", file=sys.stderr)
        return 2
    shell = Shell(controller)
    try:
        if commands is None:
            return interact(shell)
        return run_script(shell, commands, args.is_keep_going)
    except KeyboardInterrupt:
        print("cnc sh: interrupted", file=sys.stderr)
        return 130
    finally:
        controller.close()


if __name__ == "__main__":
    sys.exit(main())
