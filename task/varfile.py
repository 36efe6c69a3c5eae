"""The interpreter's parameter file (``.var``, [RS274NGC]PARAMETER_FILE) in LinuxCNC's format.

One parameter per line, ``<number><TAB><value>``, numbers ascending, 1 .. 5601.

- Read strictly (the controller: the launcher and task, before the machine starts): blank
  lines and lines starting with ``#`` or ``;`` are skipped; any other line that is not a
  number and a finite value, a number out of range or out of order is an error naming the
  file and line (``VarFileError``). LinuxCNC silently skips such lines, so a damaged file
  became zeros there, and was then written back.
- Read as LinuxCNC reads it (``strict=False``, for ``cnc rs274``, LinuxCNC's oracle): lines
  ``sscanf("%d %lf")`` does not match are skipped, and the errors are LinuxCNC's texts.
- Written atomically, never with a value that is not finite.

Kept apart from the interpreter so that the launcher can check the file before it starts
anything, without importing the interpreter.
"""

from __future__ import annotations

import math
import os
import re

from cnc.atomicfile import atomic_write_text

MAX_PARAMETERS = 5602  # #1 .. #5601
_SSCANF = re.compile(
    r"\s*([-+]?[0-9]++)\s*([-+]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
    r"|(?i:nan|inf(?:inity)?)))"
)
_LINE = re.compile(
    r"\s*([-+]?[0-9]+)[ \t]+([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)\s*"
)


class VarFileError(ValueError):
    """A bad parameter file; ``str()`` is ``file:line: cause`` (``file: cause`` for the
    whole file)."""

    def __init__(self, file: str, line: int, cause: str) -> None:
        super().__init__(f"{file}:{line}: {cause}" if line > 0 else f"{file}: {cause}")
        self.file = file
        self.line = line
        self.cause = cause


def parse_var_text(text: str, name: str = "<var>", *, strict: bool = True) -> dict[int, float]:
    """The parameters of a ``.var`` file's text, by number, in file order."""
    found: dict[int, float] = {}
    previous = 0
    for lineno, line in enumerate(text.split("\n"), 1):
        scanned = _scan_strict(line, name, lineno) if strict else _scan_like_sscanf(line)
        if scanned is None:
            continue
        number, value = scanned
        if not 1 <= number < MAX_PARAMETERS:
            cause = f"parameter number {number} out of range 1 to {MAX_PARAMETERS - 1}"
            raise VarFileError(name, lineno, cause if strict else "Parameter number out of range")
        if number <= previous:
            cause = f"parameter {number} after {previous}: the numbers must be in ascending order"
            raise VarFileError(name, lineno, cause if strict else "Parameter file out of order")
        found[number] = value
        previous = number
    return found


def _scan_strict(line: str, name: str, lineno: int) -> tuple[int, float] | None:
    stripped = line.strip()
    if not stripped or stripped[0] in "#;":
        return None
    match = _LINE.fullmatch(line)
    if match is None:
        shown = " ".join(stripped.split())[:40]
        shown = shown if shown.isprintable() else repr(shown)
        raise VarFileError(name, lineno, f"not '<parameter number> <value>': {shown}")
    number, value = int(match.group(1)), float(match.group(2))
    if not math.isfinite(value):  # (the pattern allows no nan, only too large numbers)
        raise VarFileError(name, lineno, f"parameter {number} = {match.group(2)} is too large")
    return number, value


def _scan_like_sscanf(line: str) -> tuple[int, float] | None:
    """``sscanf(line, "%d %lf") == 2``: a leading integer, blanks, then a number prefix
    (``nan`` and ``inf`` included, trailing text ignored); None when it does not match."""
    match = _SSCANF.match(line)
    if match is None:
        return None
    try:
        return int(match.group(1)), float(match.group(2))
    except ValueError:
        return None


def read_var_file(path: str | os.PathLike[str], *, strict: bool = True) -> dict[int, float]:
    """The parameters in the file at ``path``; VarFileError for a bad or unreadable one."""
    name = os.fspath(path)
    try:
        with open(name, "rb") as handle:
            data = handle.read()
    except OSError as exc:
        raise VarFileError(name, 0, f"cannot read the parameter file: {exc.strerror}") from None
    if not strict:
        return parse_var_text(data.decode("latin-1"), name, strict=False)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise VarFileError(name, line, "not a text file (binary data)") from None
    if "\0" in text:
        raise VarFileError(name, text.count("\n", 0, text.index("\0")) + 1, "binary data")
    return parse_var_text(text, name)


def format_var_file(parameters: dict[int, float], name: str = "<var>") -> str:
    """LinuxCNC's layout (``5220\\t1.000000``); VarFileError for a value that is not finite,
    which is never written."""
    lines = []
    for number in sorted(parameters):
        value = parameters[number]
        if not math.isfinite(value):
            raise VarFileError(name, 0, f"parameter {number} = {value} is not finite: not saved")
        lines.append(f"{number}\t{value:f}\n")
    return "".join(lines)


def write_var_file(path: str | os.PathLike[str], parameters: dict[int, float]) -> None:
    """Replace the file atomically, keeping the previous one as ``.bak`` (as LinuxCNC)."""
    atomic_write_text(path, format_var_file(parameters, os.fspath(path)), keep_backup=True)
