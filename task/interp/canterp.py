"""canterp: the interpreter of printed canonical calls (LinuxCNC's ``canterp.so`` plug-in).

It reads a file of canonical calls as ``rs274 -g`` prints them, one a line::

      4 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, -0.1, 0, 0, 0, 0, 0, 0)

ignores the first two columns and makes the same call on its canon, so a recorded run can be
replayed (``cnc rs274 -p canterp.so -g FILE``, as LinuxCNC's ``rs274 -p canterp.so``).

It accepts what LinuxCNC's plug-in accepts, quirks included: the calls listed in ``_CALLS``
with their arguments read as C's ``sscanf`` reads them (the whole count must convert; text
after it is ignored), ``CANON_UNITS_CM`` selects millimetres, ``STRAIGHT_PROBE`` wants six
numbers, ``INIT_CANON`` does nothing visible, and the first double quote of an argument list
and the last one after it are dropped (so ``COMMENT("a "b" c")`` gives ``a "b" c``). Any
other line is an error, reported as the plug-in reports it (``ERROR 5`` and the line text
``<Canterp::line_text>``). It has no modal state: ``init()`` makes no calls.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from .canon import (
    CANON_WORKPIECE,
    CANON_XYZ,
    CLOCKWISE,
    CONTINUOUS,
    COUNTERCLOCKWISE,
    EXACT_PATH,
    EXACT_STOP,
    PLANE_XY,
    PLANE_XZ,
    PLANE_YZ,
    UNITS_INCHES,
    UNITS_MM,
)
from .errors import INTERP_ENDFILE, INTERP_ERROR, INTERP_OK, InterpError

NAME = "canterp"  # the plug-in name rs274 -p and [TASK]INTERPRETER select it by
LINE_TEXT = "<Canterp::line_text>"  # what it reports as the text of any line
LINELEN = 256  # its line buffer: longer lines are read in pieces, as fgets() reads them

# one sscanf conversion: %lf, %d, %i (C's base prefixes) and %s
_SCAN = {
    "f": re.compile(r"\s*([+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan))", re.I),
    "d": re.compile(r"\s*([+-]?\d+)"),
    "i": re.compile(r"\s*([+-]?(?:0[xX][0-9a-fA-F]+|0[0-7]*|[1-9]\d*))"),
    "s": re.compile(r"\s*(\S+)"),
}


def _c_int(text: str) -> int:
    """A %i conversion: 0x... is hexadecimal, 0... octal, anything else decimal."""
    sign, digits = (-1, text[1:]) if text[:1] == "-" else (1, text.lstrip("+"))
    if digits[:2] in ("0x", "0X"):
        return sign * int(digits[2:], 16)
    if digits[:1] == "0" and len(digits) > 1:
        return sign * int(digits, 8)
    return sign * int(digits)


def scan(text: str, kinds: str) -> list:
    """The values C's ``sscanf`` converts from ``text`` with conversions ``kinds`` (``f``
    %lf, ``d`` %d, ``i`` %i, ``s`` %s), up to the first that fails."""
    values: list = []
    pos = 0
    for kind in kinds:
        match = _SCAN[kind].match(text, pos)
        if match is None:
            break
        word = match.group(1)
        if kind == "f":
            values.append(float(word))
        elif kind == "d":
            values.append(int(word))
        elif kind == "i":
            values.append(_c_int(word))
        else:
            values.append(word)
        pos = match.end()
    return values


def parse(line: str) -> tuple[str, str, str]:
    """(name, arguments, command) of one line: arguments with commas made spaces and the
    quotes dropped as the plug-in drops them; ('', '', '') for a line without a call.
    Raises InterpError for a name followed by something other than ``(``, or a missing ``)``."""
    match = re.match(r"\s*\S+\s+\S+\s+(?=\S)", line)
    if match is None:
        return "", "", ""
    rest = line[match.end() :]
    name = re.match(r"[^\s(]*", rest).group()
    after = rest[len(name) :].lstrip()
    if not after:
        return name, "", name
    if after[0] != "(":
        raise InterpError(f"ERROR {INTERP_ERROR}")
    end = after.find(")")
    if end < 0:
        raise InterpError(f"ERROR {INTERP_ERROR}")
    inside = after[1:end]
    first = inside.find('"')
    args = inside if first < 0 else inside[:first] + inside[first + 1 :]
    if first >= 0:
        last = args.rfind('"', first)
        if last >= 0:
            args = args[:last]
    return name, args.replace(",", " "), f"{name}({inside})"


def _words(table: dict[str, int]) -> Callable[[str], int | None]:
    return table.get


# call name -> (its conversions, or a table of its one symbolic argument; the call)
_UNITS = _words(
    {"CANON_UNITS_MM": UNITS_MM, "CANON_UNITS_CM": UNITS_MM, "CANON_UNITS_INCHES": UNITS_INCHES}
)
_REFERENCES = _words({"CANON_WORKPIECE": CANON_WORKPIECE, "CANON_XYZ": CANON_XYZ})
_PLANES = _words(
    {"CANON_PLANE_XY": PLANE_XY, "CANON_PLANE_YZ": PLANE_YZ, "CANON_PLANE_XZ": PLANE_XZ}
)
_MOTION_MODES = _words(
    {"CANON_EXACT_PATH": EXACT_PATH, "CANON_EXACT_STOP": EXACT_STOP, "CANON_CONTINUOUS": CONTINUOUS}
)
_DIRECTIONS = {"CANON_CLOCKWISE": CLOCKWISE, "CANON_COUNTERCLOCKWISE": COUNTERCLOCKWISE}


class Canterp:
    """The canterp plug-in, with the parts of the interpreter's interface rs274 uses."""

    def __init__(self, canon) -> None:
        self.canon = canon
        canon.linetext = lambda: LINE_TEXT
        self.linetext = LINE_TEXT
        self.ini = None
        # where diagnostics go (a standalone run passes stderr)
        self.report: Callable[[str], object] = lambda text: None
        self._lines: list[str] | None = None
        self._pos = 0
        self.filename = ""
        self._call: tuple[str, str, str] = ("", "", "")

    # ------------------------------------------------------------- life cycle
    def init(self) -> int:
        return INTERP_OK

    def record_error_stack(self) -> None:
        """rs274 -s: the plug-in has no stack to show."""

    def release_python(self) -> None:
        """The plug-in embeds no Python."""

    def open(self, filename: str) -> int:
        try:
            with open(filename, encoding="latin-1", newline="") as stream:
                text = stream.read()
        except OSError:
            raise InterpError(f"ERROR {INTERP_ERROR}") from None
        self._lines = [
            piece
            for line in text.splitlines(keepends=True)
            for piece in (line[k : k + LINELEN - 1] for k in range(0, len(line), LINELEN - 1))
        ]
        self._pos = 0
        self.filename = filename
        return INTERP_OK

    def close(self) -> int:
        return INTERP_OK

    def exit(self) -> int:
        return INTERP_OK

    # ------------------------------------------------------------- reading, running
    def read(self, command: str | None = None) -> int:
        """The next line of the file (or ``command``); INTERP_ENDFILE at the end."""
        if command is None:
            if self._lines is None:
                raise InterpError(f"ERROR {INTERP_ERROR}")
            if self._pos >= len(self._lines):
                return INTERP_ENDFILE
            command = self._lines[self._pos]
            self._pos += 1
        self._call = ("", "", "")
        self._call = parse(command)
        return INTERP_OK

    def execute(self, command: str | None = None) -> int:
        """Makes the call read last (or that of ``command``)."""
        if command is not None:
            self.read(command)
        name, args, whole = self._call
        if not name:
            return INTERP_OK
        handler = _CALLS.get(name)
        if handler is None or not handler(self.canon, args):
            if handler is None:
                self.report(f"canterp: unrecognized canonical command {whole}\n")
            raise InterpError(f"ERROR {INTERP_ERROR}")
        return INTERP_OK


# ------------------------------------------------------------------ the calls
# Each takes (canon, arguments) and returns False when the arguments do not convert.
def _numbers(kinds: str, call: Callable, count: int | None = None) -> Callable[..., bool]:
    """A call whose arguments are sscanf conversions; ``count``: how many must convert
    (all by default)."""
    wanted = len(kinds) if count is None else count

    def run(canon, args: str) -> bool:
        values = scan(args, kinds)
        if len(values) != wanted:
            return False
        call(canon, *values, *[0.0] * (len(kinds) - len(values)))
        return True

    return run


def _symbol(lookup: Callable[[str], int | None], call: Callable) -> Callable[..., bool]:
    """A call whose one argument is a name, compared whole (spaces count)."""

    def run(canon, args: str) -> bool:
        value = lookup(args)
        if value is None:
            return False
        call(canon, value)
        return True

    return run


def _bare(method: str) -> Callable[..., bool]:
    """A call without arguments (whatever is written between the parentheses)."""

    def run(canon, args: str) -> bool:
        getattr(canon, method)()
        return True

    return run


def _text(method: str) -> Callable[..., bool]:
    def run(canon, args: str) -> bool:
        getattr(canon, method)(args)
        return True

    return run


def _orient(canon, args: str) -> bool:
    values = scan(args, "dfs")
    if len(values) != 3 or values[2] not in _DIRECTIONS:
        return False
    canon.ORIENT_SPINDLE(values[0], values[1], _DIRECTIONS[values[2]])
    return True


def _init_canon(canon, args: str) -> bool:
    """INIT_CANON: the printing canon prints nothing for it."""
    init = getattr(canon, "INIT_CANON", None)
    if init is not None:
        init()
    return True


_CALLS: dict[str, Callable[..., bool]] = {
    "STRAIGHT_FEED": _numbers("fffffffff", lambda c, *v: c.STRAIGHT_FEED(-1, *v)),
    "STRAIGHT_TRAVERSE": _numbers("fffffffff", lambda c, *v: c.STRAIGHT_TRAVERSE(-1, *v)),
    "ARC_FEED": _numbers("ffffifffffff", lambda c, *v: c.ARC_FEED(-1, *v)),
    "STRAIGHT_PROBE": _numbers("fffffffff", lambda c, *v: c.STRAIGHT_PROBE(-1, *v, 0), 6),
    "USE_LENGTH_UNITS": _symbol(_UNITS, lambda c, v: c.USE_LENGTH_UNITS(v)),
    "SET_FEED_REFERENCE": _symbol(_REFERENCES, lambda c, v: c.SET_FEED_REFERENCE(v)),
    "SELECT_PLANE": _symbol(_PLANES, lambda c, v: c.SELECT_PLANE(v)),
    "SET_MOTION_CONTROL_MODE": _symbol(
        _MOTION_MODES, lambda c, v: c.SET_MOTION_CONTROL_MODE(v, 0.0)
    ),
    "COMMENT": _text("COMMENT"),
    "MESSAGE": _text("MESSAGE"),
    "MIST_OFF": _bare("MIST_OFF"),
    "MIST_ON": _bare("MIST_ON"),
    "FLOOD_OFF": _bare("FLOOD_OFF"),
    "FLOOD_ON": _bare("FLOOD_ON"),
    "SET_FEED_RATE": _numbers("f", lambda c, v: c.SET_FEED_RATE(v)),
    "SELECT_TOOL": _numbers("d", lambda c, v: c.SELECT_TOOL(v)),
    "CHANGE_TOOL": _numbers("d", lambda c, v: c.CHANGE_TOOL(v)),
    "DWELL": _numbers("f", lambda c, v: c.DWELL(v)),
    "START_SPEED_FEED_SYNCH": _numbers("dfd", lambda c, s, r, v: c.START_SPEED_FEED_SYNCH(s, r, v)),
    "STOP_SPEED_FEED_SYNCH": _bare("STOP_SPEED_FEED_SYNCH"),
    "SET_SPINDLE_SPEED": _numbers("if", lambda c, s, v: c.SET_SPINDLE_SPEED(s, v)),
    "START_SPINDLE_CLOCKWISE": _numbers("d", lambda c, s: c.START_SPINDLE_CLOCKWISE(s)),
    "START_SPINDLE_COUNTERCLOCKWISE": _numbers(
        "d", lambda c, s: c.START_SPINDLE_COUNTERCLOCKWISE(s)
    ),
    "STOP_SPINDLE_TURNING": _numbers("d", lambda c, s: c.STOP_SPINDLE_TURNING(s)),
    "ORIENT_SPINDLE": _orient,
    "DISABLE_SPEED_OVERRIDE": _numbers("d", lambda c, s: c.DISABLE_SPEED_OVERRIDE(s)),
    "ENABLE_SPEED_OVERRIDE": _numbers("d", lambda c, s: c.ENABLE_SPEED_OVERRIDE(s)),
    "DISABLE_FEED_OVERRIDE": _bare("DISABLE_FEED_OVERRIDE"),
    "ENABLE_FEED_OVERRIDE": _bare("ENABLE_FEED_OVERRIDE"),
    "PROGRAM_STOP": _bare("PROGRAM_STOP"),
    "OPTIONAL_PROGRAM_STOP": _bare("OPTIONAL_PROGRAM_STOP"),
    "PROGRAM_END": _bare("PROGRAM_END"),
    "PALLET_SHUTTLE": _bare("PALLET_SHUTTLE"),
    "INIT_CANON": _init_canon,
    "TURN_PROBE_OFF": _bare("TURN_PROBE_OFF"),
    "TURN_PROBE_ON": _bare("TURN_PROBE_ON"),
}
