"""LinuxCNC tool table files (TOOL-001..012).

One tool per line::

    T<tool> P<pocket> [X..W<offset>] [D<diam>] [I<frontangle>] [J<backangle>] [Q<orient>] [;comment]

Words are separated by blanks and are case-insensitive; everything after ``;`` is the comment.

The table keeps LinuxCNC's *tooldata index* model (TOOL-011/012): index 0 is the spindle. With a
nonrandom changer, tools are stored at indices 1, 2, ... in load order and the file pocket
numbers are kept only for saving; with a random changer, the pocket number is the index.

``load`` checks every line. With ``strict=True`` (the default) a line LinuxCNC would
misread (a number with trailing garbage such as ``Z1,5``, ``nan``, a missing T or P word)
raises ``ToolTableError`` (``str()`` is ``file:line: cause``); a line LinuxCNC skips as
unreadable (an old-format header, a word without a number) is skipped too, and said in
``warnings`` (``ToolTableError``s) with ``has_unreadable_lines`` set: such a table must
never be saved over its file, which would lose those lines. What LinuxCNC accepts although
it is odd (pocket 0 or a tool number below 1 in a nonrandom table) is loaded, with a
warning. With ``strict=False`` every bad line is skipped and returned, which is what
LinuxCNC's ``tooldata_load`` does. ``save`` writes the file atomically through
``cnc.atomicfile``. Nothing here knows about the interpreter.
"""

from __future__ import annotations

import math
import os
import re

from cnc.atomicfile import atomic_write_text
from nml.axes import AXIS_LETTERS

CANON_POCKETS_MAX = 1001  # TOOL-009: pockets 0..1000, index 0 is the spindle
AXES = AXIS_LETTERS  # the offsets' letters, in EmcPose order


class ToolTableError(ValueError):
    """A bad tool table line; ``str()`` is ``file:line: cause``."""

    def __init__(self, file: str, line: int, cause: str) -> None:
        super().__init__(f"{file}:{line}: {cause}")
        self.file = file
        self.line = line
        self.cause = cause


class ToolEntry:
    """One tool record (TOOL-006); ``offset`` holds X Y Z A B C U V W.

    A plain class with a dataclass's constructor, ``==`` and repr: importing dataclasses
    (with inspect) would cost ``cnc rs274`` some 8 ms of its start-up.
    """

    _FIELDS = (
        "toolno",
        "pocketno",
        "offset",
        "diameter",
        "frontangle",
        "backangle",
        "orientation",
        "comment",
    )

    def __init__(
        self,
        toolno: int = -1,
        pocketno: int = -1,
        offset: list[float] | None = None,
        diameter: float = 0.0,
        frontangle: float = 0.0,
        backangle: float = 0.0,
        orientation: int = 0,
        comment: str = "",
    ) -> None:
        self.toolno = toolno
        self.pocketno = pocketno
        self.offset = [0.0] * 9 if offset is None else offset
        self.diameter = diameter
        self.frontangle = frontangle
        self.backangle = backangle
        self.orientation = orientation
        self.comment = comment

    def _values(self) -> tuple:
        return tuple(getattr(self, name) for name in self._FIELDS)

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._values() == other._values()

    __hash__ = None  # mutable, as a dataclass with eq

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={getattr(self, name)!r}" for name in self._FIELDS)
        return f"ToolEntry({fields})"

    def copy(self) -> ToolEntry:
        return ToolEntry(
            self.toolno,
            self.pocketno,
            list(self.offset),
            self.diameter,
            self.frontangle,
            self.backangle,
            self.orientation,
            self.comment,
        )


def _parse_int(text: str) -> int:
    """Like C's ``sscanf("%d")``: leading sign and digits, trailing garbage ignored."""
    digits = ""
    for k, ch in enumerate(text):
        if ch.isdigit() or (k == 0 and ch in "+-"):
            digits += ch
        else:
            break
    return int(digits)


def _parse_float(text: str) -> float:
    """Like C's ``sscanf("%lf")`` on the longest numeric prefix."""
    best = None
    for end in range(len(text), 0, -1):
        try:
            best = float(text[:end])
            break
        except ValueError:
            continue
    if best is None or text[:1].lower() in ("i", "n"):
        raise ValueError(text)
    return best


def parse_line(text: str, *, exact: bool = False) -> ToolEntry | None:
    """Parse one tool table line; ``None`` for blank and comment-only lines.

    Raises ValueError naming the bad word. With ``exact`` every word must be a complete
    number (TOOL-010); otherwise numbers are read like ``sscanf`` does.
    """
    if text.startswith(";"):
        return None
    body, _, comment = text.partition(";")
    if len(body) <= 1:
        return None
    entry = ToolEntry(comment=comment.rstrip("\r\n"))
    seen_t = seen_p = False
    for token in body.split(" "):
        token = token.strip("\r\n\t")
        if not token:
            continue
        letter, value = token[0].upper(), token[1:]
        try:
            if letter in "TPQ":
                number = int(value) if exact else _parse_int(value)
                if letter == "T":
                    entry.toolno, seen_t = number, True
                elif letter == "P":
                    entry.pocketno, seen_p = number, True
                else:
                    entry.orientation = number
            elif letter in AXES or letter in "DIJ":
                number_f = float(value) if exact else _parse_float(value)
                if letter == "D":
                    entry.diameter = number_f
                elif letter == "I":
                    entry.frontangle = number_f
                elif letter == "J":
                    entry.backangle = number_f
                else:
                    entry.offset[AXES.index(letter)] = number_f
            else:
                raise ValueError(f"unknown word {_shown(token)}")
        except ValueError as exc:
            if str(exc).startswith("unknown word"):
                raise
            raise ValueError(f"bad number in word {_shown(token)}") from None
    _check_finite(entry)
    if exact and not seen_t:
        raise ValueError("T word missing")
    if exact and not seen_p:
        raise ValueError("P word missing")
    return entry


def _shown(word: str) -> str:
    """A word quoted for a message; binary garbage as a Python literal."""
    return f"'{word}'" if word.isprintable() else repr(word[:20])


def _check_finite(entry: ToolEntry) -> None:
    """ValueError naming the first value that is nan or infinite (LinuxCNC's ``sscanf``
    reads ``Z+nan``, which then turns G43 and every move after it into no motion)."""
    values = [*zip(AXES, entry.offset, strict=True), ("D", entry.diameter)]
    values += [("I", entry.frontangle), ("J", entry.backangle)]
    for letter, value in values:
        if not math.isfinite(value):
            raise ValueError(f"{letter} = {value} is not a finite number")


_SCANF_INT = re.compile(r"[ \t]*[+-]?\d")
_SCANF_FLOAT = re.compile(r"[ \t]*[+-]?(\d|\.\d|inf|nan)", re.IGNORECASE)


def _is_readable_by_linuxcnc(line: str) -> bool:
    """Whether LinuxCNC's ``sscanf`` reading takes every word of the line (maybe misreading
    a value: ``Z1,5`` as Z1, ``Zinf``), rather than skipping the line as invalid."""
    body = line.partition(";")[0]
    for token in body.split(" "):
        token = token.strip("\r\n\t")
        if not token:
            continue
        letter, value = token[0].upper(), token[1:]
        if letter in "TPQ":
            if not _SCANF_INT.match(value):
                return False
        elif letter in AXES or letter in "DIJ":
            if not _SCANF_FLOAT.match(value):
                return False
        else:
            return False
    return True


class ToolTable:
    """Tool records by tooldata index; index 0 is the spindle."""

    def __init__(self, random_toolchanger: bool = False) -> None:
        self.random_toolchanger = random_toolchanger
        self.entries: dict[int, ToolEntry] = {}
        self.last_index = 0
        self.warnings: list[ToolTableError] = []  # of the last load (strict)
        self.has_unreadable_lines = False  # the last load skipped lines: never save over it

    # ------------------------------------------------------------------ access
    def get(self, idx: int) -> ToolEntry:
        entry = self.entries.get(idx)
        return entry.copy() if entry is not None else ToolEntry()

    def put(self, idx: int, entry: ToolEntry) -> None:
        """Store a copy of ``entry`` at ``idx``; IndexError, or ValueError for a value that
        is not finite (the table never holds one, so it never writes one)."""
        if not 0 <= idx < CANON_POCKETS_MAX:
            raise IndexError(f"tool index {idx} out of range")
        _check_finite(entry)
        self.entries[idx] = entry.copy()
        if idx > self.last_index:
            self.last_index = idx

    def find_index_for_tool(self, toolno: int) -> int:
        """The tooldata index holding ``toolno``, or -1 (LinuxCNC's search order)."""
        if toolno == -1:
            return -1
        if not self.random_toolchanger and toolno == 0:
            return 0
        found = -1
        for idx in range(0, self.last_index + 1):
            entry = self.entries.get(idx)
            if entry is not None and entry.toolno == toolno:
                found = idx
                if found == 0:
                    continue
                break
        return found

    def clear(self) -> None:
        self.entries.clear()
        self.last_index = 0

    # ------------------------------------------------------------------- files
    def load(self, path: str | os.PathLike[str], *, strict: bool = True) -> list[str]:
        """Read a tool table file; returns the lines skipped (only when not strict)."""
        name = os.fspath(path)
        with open(name, encoding="utf-8", errors="replace") as handle:
            lines = handle.read().splitlines(keepends=True)
        return self.load_lines(lines, name, strict=strict)

    def load_lines(
        self, lines: list[str], name: str = "<tools>", *, strict: bool = True
    ) -> list[str]:
        self.clear()
        self.warnings = []
        self.has_unreadable_lines = False
        skipped: list[str] = []
        next_index = 1
        for lineno, line in enumerate(lines, 1):
            try:
                entry = parse_line(line, exact=strict)
            except ValueError as exc:
                if not strict:
                    skipped.append(line)
                    continue
                if _is_readable_by_linuxcnc(line):  # it would misread the line: refused
                    raise ToolTableError(name, lineno, str(exc)) from None
                self.warnings.append(
                    ToolTableError(name, lineno, f"{exc}: line skipped, as LinuxCNC does")
                )
                self.has_unreadable_lines = True
                continue
            if entry is None:
                continue
            try:
                if self.random_toolchanger:
                    idx = entry.pocketno
                    if not 0 <= idx < CANON_POCKETS_MAX and strict:  # LinuxCNC skips it
                        self.warnings.append(
                            ToolTableError(
                                name,
                                lineno,
                                f"pocket {idx} out of range 0..{CANON_POCKETS_MAX - 1}: "
                                "line skipped, as LinuxCNC does",
                            )
                        )
                        self.has_unreadable_lines = True
                        continue
                    if not 0 <= idx < CANON_POCKETS_MAX:
                        raise ValueError(f"pocket {idx} out of range 0..{CANON_POCKETS_MAX - 1}")
                    if strict and entry.toolno < 0:
                        raise ValueError(f"tool number {entry.toolno} must be >= 0")
                else:
                    if strict and entry.toolno <= 0:
                        self._warn(name, lineno, f"tool number {entry.toolno} is not positive")
                    # (LinuxCNC numbers a non-random changer's pockets itself: P0 is kept
                    # as written, as it is for a random one, and said)
                    if strict and entry.pocketno <= 0:
                        self._warn(name, lineno, f"pocket {entry.pocketno} is not positive")
                    if entry.pocketno == -1 and not strict:
                        idx = 0  # LinuxCNC stores a line without P in the spindle slot
                    else:
                        idx = next_index
                        if idx >= CANON_POCKETS_MAX:
                            raise ValueError("too many tools")
                        next_index += 1
            except ValueError as exc:
                if strict:
                    raise ToolTableError(name, lineno, str(exc)) from None
                skipped.append(line)
                continue
            self.put(idx, entry)
            if not self.random_toolchanger:
                spindle = self.entries.get(0)
                if spindle is not None and spindle.toolno == entry.toolno:
                    self.put(0, entry)
        return skipped

    def _warn(self, name: str, lineno: int, cause: str) -> None:
        self.warnings.append(ToolTableError(name, lineno, f"{cause} (accepted, as LinuxCNC)"))

    def format(self) -> str:
        out = []
        start = 0 if self.random_toolchanger else 1
        for idx in range(start, self.last_index + 1):
            entry = self.entries.get(idx)
            if entry is None or entry.toolno == -1:
                continue
            pocket = idx if self.random_toolchanger else entry.pocketno
            parts = [f"T{entry.toolno:<3d} P{pocket:<3d}"]
            values = [("D", entry.diameter), *list(zip(AXES, entry.offset, strict=True))]
            values += [("I", entry.frontangle), ("J", entry.backangle)]
            for letter, value in values:
                if value:
                    parts.append(f" {letter}{value:+f}")
            if entry.orientation:
                parts.append(f" Q{entry.orientation}")
            parts.append(f" ;{entry.comment}\n")
            out.append("".join(parts))
        return "".join(out)

    def save(self, path: str | os.PathLike[str]) -> None:
        atomic_write_text(path, self.format())
