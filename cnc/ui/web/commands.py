"""The page's commands: {"cmd": NAME, ...arguments} -> ``cnc.command`` calls.

``Commands.run(request)`` runs in a worker thread (it waits for the controller); each thread
has its own ``cnc.command`` and ``cnc.stat``, so ``wait_complete`` of one command never
waits for another browser's, and an abort is never queued behind a running MDI line.
Like AXIS, a command switches the task mode it needs first (MDI for ``mdi``, MANUAL for
jogs and homing, AUTO for programs). Bad arguments raise ``CommandError`` with the reason.
"""

from __future__ import annotations

import shlex
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cnc
from cnc.atomicfile import atomic_write_text
from cnc.ui.formatting import parse_float
from cnc.ui.web.offsets import SYSTEMS
from cnc.ui.web.priority import at_job_priority
from cnc.ui.web.settings import Settings
from iocontrol.tooltable import ToolEntry, ToolTable, ToolTableError
from nml.axes import AXIS_LETTERS
from nml.commands import Handlers, Refused, handler

TIMEOUT_S = 10.0  # how long a command may take before the page is told it still runs
PROGRAM_TIMEOUT_S = 3600.0  # an MDI line may be a long move
WAIT_SLICE_S = 0.5
FILTER_TIMEOUT_S = 120.0  # a [FILTER] program converting an image may take a while
MAX_TEXT_BYTES = 8_000_000  # a program sent whole as text (files.get)
TOOL_FILE_LOCK = threading.Lock()  # one tool edit at a time (the file is read, then written)


class CommandError(Refused):
    """A command that could not be sent, or that the controller refused; str() says why.
    ``is_reported``: the controller refused it and said why on the error channel, which
    every page shows already (a quiet refusal, nml/commands.py)."""

    def __init__(self, text: str, is_reported: bool = False) -> None:
        super().__init__(text, is_quiet=is_reported)

    @property
    def is_reported(self) -> bool:
        return self.is_quiet


# ------------------------------------------------------------------ argument helpers
def number(request: dict[str, Any], key: str, minimum: float | None = None) -> float:
    """A number argument: a JSON number, or text with ',' or '.' as decimal separator
    (GUI-003)."""
    value = request.get(key)
    if isinstance(value, bool) or value is None:
        raise CommandError(f"'{key}' must be a number")
    try:
        result = float(value) if isinstance(value, int | float) else parse_float(str(value))
    except ValueError as exc:
        raise CommandError(f"'{key}': {exc}") from None
    if minimum is not None and result < minimum:
        raise CommandError(f"'{key}' must be at least {minimum:g}")
    return result


def whole(request: dict[str, Any], key: str, default: int | None = None) -> int:
    value = request.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int):
        raise CommandError(f"'{key}' must be a whole number")
    return value


def switch(request: dict[str, Any], key: str = "on") -> bool:
    value = request.get(key)
    if not isinstance(value, bool):
        raise CommandError(f"'{key}' must be true or false")
    return value


def text(request: dict[str, Any], key: str) -> str:
    value = request.get(key)
    if not isinstance(value, str) or not value.strip():
        raise CommandError(f"'{key}' must be a non-empty text")
    return value.strip()


class Commands:
    """Runs the page's commands against one controller (``source``: INI, NML or None)."""

    def __init__(self, settings: Settings, source: str | None = None) -> None:
        self.settings = settings
        self.source = source
        self._local = threading.local()
        self.mdi_history: list[str] = _read_history(settings.mdi_history_file)
        self._history_lock = threading.Lock()
        self.is_stopping = threading.Event()  # set when the server shuts down

    # ---------------------------------------------------------------- per-thread objects
    @property
    def command(self) -> cnc.command:
        if getattr(self._local, "command", None) is None:
            self._local.command = cnc.command(self.source)
        return self._local.command

    @property
    def stat(self) -> cnc.stat:
        if getattr(self._local, "stat", None) is None:
            self._local.stat = cnc.stat(self.source)
        self._local.stat.poll()
        return self._local.stat

    def forget(self) -> None:
        """Drop this thread's objects (after the controller stopped or restarted)."""
        self._local.command = self._local.stat = None

    # ---------------------------------------------------------------- running
    def run(self, request: dict[str, Any]) -> str:
        """Run one request; its result text ("DONE" or what happened); CommandError."""
        name = request.get("cmd")
        run = HANDLERS.get(name) if isinstance(name, str) else None
        if run is None:
            raise CommandError(f"unknown command {name!r}")
        try:
            return run(self, request) or "DONE"
        except CommandError as exc:
            raise CommandError(f"{name}: {exc}", exc.is_reported) from None
        except cnc.error as exc:  # the controller is not running, or restarted
            self.forget()
            raise CommandError(f"{name}: {exc}") from None
        except (TypeError, ValueError, OverflowError) as exc:  # refused by the API
            raise CommandError(f"{name}: {exc}") from None

    def send(self, method: str, *args: Any, timeout: float = TIMEOUT_S) -> None:
        """``cnc.command().<method>(*args)``, then wait until the controller finished it."""
        commands = self.command
        getattr(commands, method)(*args)
        deadline = time.monotonic() + timeout
        result = -1
        # Waited in slices, so that a server that stops does not wait for a long move.
        while result == -1 and not self.is_stopping.is_set():
            left = deadline - time.monotonic()
            if left <= 0:
                break
            result = commands.wait_complete(min(left, WAIT_SLICE_S))
        if result == cnc.RCS_ERROR:
            raise CommandError(f"the controller refused {method}", is_reported=True)
        if result != cnc.RCS_DONE:
            raise CommandError(f"{method} not finished after {timeout:g} s (it may still run)")

    def start(self, method: str, *args: Any) -> None:
        """``cnc.command().<method>(*args)``, waiting only until the controller took it: a
        program run is answered when the program ends (as LinuxCNC's task answers it)."""
        commands = self.command
        getattr(commands, method)(*args)
        if commands.wait_complete(0) == cnc.RCS_ERROR:
            raise CommandError(f"the controller refused {method}", is_reported=True)

    def program_scale(self) -> float:
        """Program units per machine unit (G20/G21 of the moment): what an MDI line needs
        to say a length in machine units."""
        mm_per_program_unit = {1: 25.4, 2: 1.0, 3: 10.0}.get(self.stat.program_units, 1.0)
        return 1.0 / (mm_per_program_unit * self.settings.units_per_mm)

    def mdi(self, line: str, timeout: float = TIMEOUT_S) -> None:
        """One MDI line, run to its end."""
        self.ensure_mode(cnc.MODE_MDI)
        self.send("mdi", line, timeout=timeout)

    def ensure_mode(self, mode: int) -> None:
        if self.stat.task_mode != mode:
            self.send("mode", mode)

    def jog_target(self, request: dict[str, Any]) -> tuple[bool, int]:
        """What a jog moves: (is joint, index). An axis letter jogs that world axis once
        every joint is homed (motion is then in teleop, as AXIS jogs in world mode: a
        gantry's two joints move together), its joint before; a "joint" number always
        jogs that joint."""
        joint = self.joint_of(request)
        if "joint" in request:
            return True, joint
        try:
            stat = self.stat
        except cnc.error as exc:  # the controller is not running, or restarted
            self.forget()
            raise CommandError(str(exc)) from None
        homed = stat.homed[: stat.joints]
        if homed and all(homed):
            return False, AXIS_LETTERS.index(self.settings.axes[joint])
        return True, joint

    def joint_of(self, request: dict[str, Any]) -> int:
        """The joint an "axis" letter (trivial kinematics: its place in COORDINATES) or a
        "joint" number names."""
        if "joint" in request:
            return whole(request, "joint")
        letter = str(request.get("axis", "")).upper()
        if len(letter) != 1 or letter not in self.settings.axes:
            raise CommandError(f"unknown axis {request.get('axis')!r}")
        return self.settings.axes.index(letter)

    def remember_mdi(self, line: str) -> list[str]:
        """Add an MDI line to the history (and its file); the whole history."""
        with self._history_lock:
            if not self.mdi_history or self.mdi_history[-1] != line:
                self.mdi_history.append(line)
                path = self.settings.mdi_history_file
                if path is not None:
                    try:
                        with open(path, "a", encoding="utf-8") as file:
                            file.write(line + "\n")
                    except OSError:
                        pass  # a read-only history file must not fail the command
            return list(self.mdi_history)

    # ---------------------------------------------------------------- programs
    def program_path(self, name: str) -> Path:
        """A program file named relative to PROGRAM_PREFIX, never outside it."""
        folder = self.settings.program_prefix
        if folder is None:
            raise CommandError("no [DISPLAY]PROGRAM_PREFIX")
        path = (folder / name).resolve()
        if not path.is_relative_to(folder.resolve()) or not path.is_file():
            raise CommandError(f"no program {name!r}")
        return path

    def program_text(self, name: str) -> dict[str, str]:
        """{"file", "text"} of a program under PROGRAM_PREFIX, at most MAX_TEXT_BYTES."""
        path = self.program_path(name)
        if path.stat().st_size > MAX_TEXT_BYTES:
            raise CommandError(f"{name!r} is larger than {MAX_TEXT_BYTES} bytes")
        return {"file": name, "text": path.read_bytes().decode("utf-8", "replace")}

    def delete_program(self, name: str) -> None:
        """Remove a program under PROGRAM_PREFIX; not the one task has open."""
        path = self.program_path(name)
        try:
            open_file = self.stat.file
        except cnc.error:
            open_file = ""  # no controller: nothing is open
        if open_file and Path(open_file).resolve() == path:
            raise CommandError(f"{name!r} is the open program")
        try:
            path.unlink()
        except OSError as exc:
            raise CommandError(f"cannot remove {path}: {exc.strerror}") from None

    def program_files(self) -> list[str]:
        """Programs under PROGRAM_PREFIX with a [FILTER] extension, relative, sorted."""
        folder = self.settings.program_prefix
        if folder is None or not folder.is_dir():
            return []
        found = []
        for path in folder.rglob("*"):
            if path.is_file() and path.suffix.lower() in self.settings.extensions:
                found.append(path.relative_to(folder).as_posix())
        return sorted(found)


def tool_comments(path: Path | None, is_random: bool) -> dict[int, str]:
    """Tool number -> the comment of its line in the tool table file (empty if unreadable:
    the table itself comes from iocontrol, stat.tool_table)."""
    if path is None:
        return {}
    table = ToolTable(is_random)
    try:
        table.load(path, strict=False)
    except OSError:
        return {}
    return {entry.toolno: entry.comment for entry in table.entries.values()}


def _read_history(path: Path | None) -> list[str]:
    if path is None:
        return []
    try:
        return [line for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    except OSError:
        return []


# ------------------------------------------------------------------ machine
@handler("estop")
def _estop(c: Commands, r: dict[str, Any]) -> None:
    """(an E-stop on: already on the safety board, its stamp in "board_stamp": hub.py)"""
    if switch(r):
        c.send("state", cnc.STATE_ESTOP, r.get("board_stamp", 0))
    else:
        c.send("state", cnc.STATE_ESTOP_RESET)


@handler("machine")
def _machine(c: Commands, r: dict[str, Any]) -> None:
    c.send("state", cnc.STATE_ON if switch(r) else cnc.STATE_OFF)


@handler("mode")
def _mode(c: Commands, r: dict[str, Any]) -> None:
    modes = {"manual": cnc.MODE_MANUAL, "mdi": cnc.MODE_MDI, "auto": cnc.MODE_AUTO}
    mode = modes.get(r.get("mode"))  # type: ignore[arg-type]
    if mode is None:
        raise CommandError("'mode' must be one of manual, mdi, auto")
    c.send("mode", mode)


@handler("home")
def _home(c: Commands, r: dict[str, Any]) -> None:
    joint = whole(r, "joint", -1)
    c.ensure_mode(cnc.MODE_MANUAL)
    c.send("home", joint)


@handler("unhome")
def _unhome(c: Commands, r: dict[str, Any]) -> None:
    joint = whole(r, "joint", -1)
    c.ensure_mode(cnc.MODE_MANUAL)
    c.send("unhome", joint)


@handler("override_limits")
def _override_limits(c: Commands, r: dict[str, Any]) -> None:
    c.ensure_mode(cnc.MODE_MANUAL)
    c.send("override_limits")


@handler("jog")
def _jog(c: Commands, r: dict[str, Any]) -> None:
    """{"action": "start"|"stop"|"increment", "axis": "X" (or "joint": 0), "direction":
    1|-1, "speed": units per minute, "distance": machine units}. Which joint or axis moves:
    ``Commands.jog_target`` (or "target": [is joint, index], the hub's lease of a start)."""
    action = r.get("action")
    is_joint, index = r["target"] if "target" in r else c.jog_target(r)
    mode = int(is_joint)  # jog()'s jjogmode: 1 a joint, 0 a world axis
    if action == "stop":
        c.send("jog", cnc.JOG_STOP, mode, index)
        return
    direction = number(r, "direction")
    speed = number(r, "speed") / 60.0  # the API takes units per second
    if not speed > 0:
        raise CommandError("the jog speed must be above 0")
    velocity = speed if direction >= 0 else -speed
    c.ensure_mode(cnc.MODE_MANUAL)
    is_teleop = c.stat.motion_mode == cnc.TRAJ_MODE_TELEOP
    if is_teleop == is_joint:  # motion jogs joints in free mode, axes in teleop mode
        c.send("teleop_enable", int(not is_joint))
    if action == "start":
        c.send("jog", cnc.JOG_CONTINUOUS, mode, index, velocity)
    elif action == "increment":
        c.send("jog", cnc.JOG_INCREMENT, mode, index, velocity, number(r, "distance", 0.0))
    else:
        raise CommandError("'action' must be one of start, stop, increment")


def _axis_letter(c: Commands, r: dict[str, Any]) -> str:
    letter = str(r.get("axis", "")).upper()
    if len(letter) != 1 or letter not in c.settings.axes:
        raise CommandError(f"unknown axis {r.get('axis')!r}")
    return letter


def _system_number(r: dict[str, Any], default: int = 0) -> int:
    """ "system": "G54".."G59.3" -> its P number (1..9); absent: ``default`` (0: active)."""
    name = r.get("system")
    if name is None:
        return default
    if name not in SYSTEMS:
        raise CommandError(f"'system' must be one of {', '.join(SYSTEMS)}")
    return SYSTEMS.index(name) + 1


def _length(c: Commands, value: float) -> str:
    """A length in machine units, written in program units for an MDI line."""
    return f"{value * c.program_scale():.6f}"


@handler("touch_off")
def _touch_off(c: Commands, r: dict[str, Any]) -> None:
    """Set the offset of coordinate system "system" (default: the active one) so that the
    axis reads "value" (machine units) where it is now (G10 L20)."""
    letter = _axis_letter(c, r)
    value = number(r, "value")
    system = _system_number(r)
    c.mdi(f"G10 L20 P{system} {letter}{_length(c, value)}")


@handler("offset_set")
def _offset_set(c: Commands, r: dict[str, Any]) -> None:
    """Set one axis of a coordinate system's offset to "value" (machine units; G10 L2), or
    its XY rotation to "rotation" (degrees)."""
    system = _system_number(r, default=-1)
    if system < 0:
        raise CommandError("'system' must be given")
    if "rotation" in r:
        c.mdi(f"G10 L2 P{system} R{number(r, 'rotation'):.6f}")
        return
    letter = _axis_letter(c, r)
    c.mdi(f"G10 L2 P{system} {letter}{_length(c, number(r, 'value'))}")


@handler("offset_clear")
def _offset_clear(c: Commands, r: dict[str, Any]) -> None:
    """Zero a coordinate system's offsets and rotation, or G92's ("system": "G92")."""
    if r.get("system") == "G92":
        c.mdi("G92.1")
        return
    system = _system_number(r, default=-1)
    if system < 0:
        raise CommandError("'system' must be given")
    words = " ".join(f"{letter}0" for letter in c.settings.axes)
    c.mdi(f"G10 L2 P{system} {words} R0")


@handler("select_system")
def _select_system(c: Commands, r: dict[str, Any]) -> None:
    """Make "system" (G54..G59.3) the active coordinate system."""
    system = _system_number(r, default=-1)
    if system < 0:
        raise CommandError("'system' must be given")
    c.mdi(SYSTEMS[system - 1])


def _edit_tool_table(c: Commands, change: Callable[[ToolTable, Path], None]) -> None:
    """Apply ``change`` to the tool table file, as LinuxCNC's tool editors do: the file is
    read, changed, rewritten atomically, then iocontrol reloads it
    (EMC_TOOL_LOAD_TOOL_TABLE), so stat.tool_table and the interpreter's copy follow. Not
    while a program or MDI runs (it may change the table itself)."""
    path = c.settings.tool_table
    if path is None:
        raise CommandError("the INI file names no [EMCIO]TOOL_TABLE")
    if c.stat.interp_state != cnc.INTERP_IDLE:
        raise CommandError("not while a program or MDI command runs")
    with TOOL_FILE_LOCK:
        table = ToolTable(c.settings.is_random_toolchanger)
        try:
            table.load(path)
        except ToolTableError as exc:
            raise CommandError(f"{exc}; fix the file first") from None
        except OSError as exc:
            raise CommandError(f"cannot read {path}: {exc.strerror}") from None
        if table.has_unreadable_lines:  # saved, the lines LinuxCNC skips would be lost
            skipped = "; ".join(str(w) for w in table.warnings if "skipped" in str(w))
            raise CommandError(f"{skipped}; fix the file first")
        change(table, path)
        try:
            table.save(path)
        except OSError as exc:
            raise CommandError(f"cannot write {path}: {exc.strerror}") from None
    c.send("load_tool_table")


def _tool_number(r: dict[str, Any]) -> int:
    tool = whole(r, "tool")
    if tool <= 0:
        raise CommandError("'tool' must be at least 1")
    return tool


@handler("tool_set")
def _tool_set(c: Commands, r: dict[str, Any]) -> None:
    """{"tool": n, "z": ..., "diameter": ..., "x": ... and "comment": ... optional}: edit
    one tool (see _edit_tool_table)."""
    tool = _tool_number(r)
    z, diameter = number(r, "z"), number(r, "diameter", 0.0)
    x = number(r, "x") if "x" in r else None
    comment = " ".join(str(r["comment"]).split()) if "comment" in r else None

    def edit(table: ToolTable, path: Path) -> None:
        index = table.find_index_for_tool(tool)
        if index < 0:
            raise CommandError(f"no tool {tool} in {path}")
        entry = table.get(index)
        entry.offset[2] = z
        entry.diameter = diameter
        if x is not None:
            entry.offset[0] = x
        if comment is not None:
            entry.comment = comment
        table.put(index, entry)

    _edit_tool_table(c, edit)


@handler("tool_add")
def _tool_add(c: Commands, r: dict[str, Any]) -> None:
    """{"tool": n, "pocket": p (default n), "z", "diameter", "comment" optional}: a new
    tool (a random tool changer's pocket must be free)."""
    tool = _tool_number(r)
    pocket = whole(r, "pocket", tool)
    if pocket <= 0:
        raise CommandError("'pocket' must be at least 1")
    z = number(r, "z") if "z" in r else 0.0
    diameter = number(r, "diameter", 0.0) if "diameter" in r else 0.0
    comment = " ".join(str(r.get("comment", "")).split())

    def add(table: ToolTable, path: Path) -> None:
        if table.find_index_for_tool(tool) > 0:
            raise CommandError(f"tool {tool} is in {path} already")
        index = pocket if table.random_toolchanger else table.last_index + 1
        if table.random_toolchanger and index in table.entries:
            raise CommandError(f"pocket {pocket} holds a tool already")
        offset = [0.0] * 9
        offset[2] = z
        table.put(index, ToolEntry(tool, pocket, offset, diameter, comment=comment))

    _edit_tool_table(c, add)


@handler("tool_delete")
def _tool_delete(c: Commands, r: dict[str, Any]) -> None:
    """{"tool": n}: remove a tool from the table (not the one in the spindle)."""
    tool = _tool_number(r)
    if c.stat.tool_in_spindle == tool:
        raise CommandError(f"tool {tool} is in the spindle")

    def delete(table: ToolTable, path: Path) -> None:
        index = table.find_index_for_tool(tool)
        if index <= 0:
            raise CommandError(f"no tool {tool} in {path}")
        del table.entries[index]

    _edit_tool_table(c, delete)


# ------------------------------------------------------------------ MDI
@handler("mdi")
def _mdi(c: Commands, r: dict[str, Any]) -> str:
    line = text(r, "text")
    c.ensure_mode(cnc.MODE_MDI)
    c.remember_mdi(line)
    c.send("mdi", line, timeout=PROGRAM_TIMEOUT_S)
    return "DONE"


@handler("mdi_line")
def _mdi_line(c: Commands, r: dict[str, Any]) -> None:
    """One MDI line of the server's own (probing, offsets): not in the history."""
    timeout = r.get("timeout", TIMEOUT_S)
    c.mdi(text(r, "text"), timeout=timeout if isinstance(timeout, int | float) else TIMEOUT_S)


@handler("macro")
def _macro(c: Commands, r: dict[str, Any]) -> None:
    """An [MDI_COMMAND_LIST] button: its ';'-separated lines, each to its end (GUI-014)."""
    index = whole(r, "index")
    if not 0 <= index < len(c.settings.macros):
        raise CommandError(f"no macro {index}")
    c.ensure_mode(cnc.MODE_MDI)
    for line in c.settings.macros[index]["commands"].split(";"):
        if line.strip():
            c.send("mdi", line.strip(), timeout=PROGRAM_TIMEOUT_S)


# ------------------------------------------------------------------ programs
@handler("open")
def _open(c: Commands, r: dict[str, Any]) -> None:
    path = c.program_path(text(r, "file"))
    program = c.settings.filters.get(path.suffix.lower())
    if program is not None:
        path = run_filter(program, path)
    c.ensure_mode(cnc.MODE_AUTO)
    c.send("program_open", str(path))


@handler("save_program")
def _save_program(c: Commands, r: dict[str, Any]) -> str:
    """{"file": name under PROGRAM_PREFIX, "text": the program}: written atomically (task
    may be reading the old one); a new file needs a program extension."""
    name = text(r, "file")
    content = r.get("text")
    if not isinstance(content, str):
        raise CommandError("'text' must be the program's text")
    folder = c.settings.program_prefix
    if folder is None:
        raise CommandError("no [DISPLAY]PROGRAM_PREFIX")
    path = (folder / name).resolve()
    if (
        not path.is_relative_to(folder.resolve())
        or path.suffix.lower() not in c.settings.extensions
    ):
        raise CommandError(f"{name!r}: not a program name in {folder}")
    try:
        atomic_write_text(path, content if content.endswith("\n") else content + "\n")
    except OSError as exc:
        raise CommandError(f"cannot write {path}: {exc.strerror}") from None
    return "saved"


def run_filter(program: str, path: Path) -> Path:
    """Run a [FILTER] program on ``path`` (GUI-015); its output, the G-code task opens, is
    saved as <temp>/cnc-web-filtered/<name>.ngc."""
    folder = Path(tempfile.gettempdir()) / "cnc-web-filtered"
    folder.mkdir(exist_ok=True)
    target = folder / f"{path.stem}.ngc"
    try:
        with open(target, "wb") as output:
            done = subprocess.run(
                [*shlex.split(program), str(path)],
                stdout=output,
                stderr=subprocess.PIPE,
                timeout=FILTER_TIMEOUT_S,
                check=False,
                preexec_fn=at_job_priority,  # (not the server's raised one)
            )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise CommandError(f"filter {program!r}: {exc}") from None
    if done.returncode != 0:
        reason = done.stderr.decode("utf-8", errors="replace").strip().splitlines()
        raise CommandError(
            f"filter {program!r} failed ({done.returncode}): {reason[-1] if reason else ''}"
        )
    return target


@handler("run")
def _run(c: Commands, r: dict[str, Any]) -> None:
    line = whole(r, "line", 0)
    c.ensure_mode(cnc.MODE_AUTO)
    c.start("auto", cnc.AUTO_RUN, line)


@handler("pause")
def _pause(c: Commands, r: dict[str, Any]) -> None:
    c.send("auto", cnc.AUTO_PAUSE)


@handler("resume")
def _resume(c: Commands, r: dict[str, Any]) -> None:
    c.send("auto", cnc.AUTO_RESUME)


@handler("step")
def _step(c: Commands, r: dict[str, Any]) -> None:
    c.ensure_mode(cnc.MODE_AUTO)
    c.send("auto", cnc.AUTO_STEP)


@handler("abort")
def _abort(c: Commands, r: dict[str, Any]) -> None:
    """(already on the safety board, its stamp in "board_stamp": hub.py)"""
    c.send("abort", r.get("board_stamp", 0))


@handler("optional_stop")
def _optional_stop(c: Commands, r: dict[str, Any]) -> None:
    c.send("set_optional_stop", int(switch(r)))


@handler("block_delete")
def _block_delete(c: Commands, r: dict[str, Any]) -> None:
    c.send("set_block_delete", int(switch(r)))


# ------------------------------------------------------------------ overrides, spindle, coolant
def _percent(c: Commands, r: dict[str, Any], low: float, high: float) -> float:
    """The "percent" argument clamped to the INI's limits, as a scale (1.0 = 100 %)."""
    return min(max(number(r, "percent"), low), high) / 100.0


@handler("feedrate")
def _feedrate(c: Commands, r: dict[str, Any]) -> None:
    c.send("feedrate", _percent(c, r, 0.0, c.settings.max_feed_override))


@handler("rapidrate")
def _rapidrate(c: Commands, r: dict[str, Any]) -> None:
    c.send("rapidrate", _percent(c, r, 0.0, c.settings.max_rapid_override))


@handler("spindle_override")
def _spindle_override(c: Commands, r: dict[str, Any]) -> None:
    low, high = c.settings.min_spindle_override, c.settings.max_spindle_override
    c.send("spindleoverride", _percent(c, r, low, high))


@handler("spindle")
def _spindle(c: Commands, r: dict[str, Any]) -> None:
    """{"action": "forward"|"reverse"|"stop"|"faster"|"slower", "speed": rpm (optional)}."""
    action = r.get("action")
    if action == "stop":
        c.send("spindle", cnc.SPINDLE_OFF)
        return
    limits = c.settings.spindle
    if action in ("faster", "slower"):  # by SPINDLE_INCREMENT, within the range
        spindle = c.stat.spindle[0]
        if not spindle["direction"]:
            raise CommandError("the spindle is not turning")
        step = limits["increment"] if action == "faster" else -limits["increment"]
        top = limits["max"] if spindle["direction"] > 0 else limits["max_reverse"]
        speed = min(max(abs(spindle["speed"]) + step, limits["min"]), top)
        action = "forward" if spindle["direction"] > 0 else "reverse"
    else:
        speed = number(r, "speed", 0.0) if "speed" in r else limits["default"]
    directions = {"forward": cnc.SPINDLE_FORWARD, "reverse": cnc.SPINDLE_REVERSE}
    if action not in directions:
        raise CommandError("'action' must be one of forward, reverse, stop, faster, slower")
    check_spindle_speed(c.settings, speed, action == "reverse")
    c.ensure_mode(cnc.MODE_MANUAL)
    c.send("spindle", directions[action], speed)


def check_spindle_speed(settings: Settings, speed: float, is_reverse: bool) -> None:
    """Refuse a manual speed outside the INI's range (GUI-013), naming the key."""
    limits, keys = settings.spindle, settings.spindle_limit_keys
    top, key = (
        (limits["max_reverse"], keys.get("max_reverse"))
        if is_reverse
        else (limits["max"], keys.get("max"))
    )
    if speed > top:
        source = f" ({key})" if key else ""
        raise CommandError(f"{speed:g} rpm is above the maximum, {top:g} rpm{source}")
    if speed < limits["min"]:
        raise CommandError(f"{speed:g} rpm is below the minimum, {limits['min']:g} rpm")


@handler("flood")
def _flood(c: Commands, r: dict[str, Any]) -> None:
    c.send("flood", cnc.FLOOD_ON if switch(r) else cnc.FLOOD_OFF)


@handler("mist")
def _mist(c: Commands, r: dict[str, Any]) -> None:
    c.send("mist", cnc.MIST_ON if switch(r) else cnc.MIST_OFF)


# The page's commands: the @handler functions of this module (nml/commands.py)
HANDLERS = Handlers(sys.modules[__name__])
