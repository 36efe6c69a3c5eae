"""INI files as LinuxCNC 2.9 reads them (CFG-001..003), and ``cnc inivar``.

The syntax, as LinuxCNC's IniFile class and its launcher read it:

- ``[SECTION]`` headers and ``KEY = VALUE`` lines; sections and keys are case sensitive.
  A section is what follows its *first* header: LinuxCNC never looks past it, so keys under
  a repeated header are ignored (with a warning here).
- A line whose first non-blank character is ``#`` or ``;`` is a comment; a ``#`` or ``;``
  later in a line is part of the value (there are no end-of-line comments).
- A trailing backslash joins the next line to the value (at most 20 times).
- A key may repeat (``HALFILE``, ``REMAP``): ``find`` returns the first value, ``findall``
  every value in file order up to the first empty one. An empty value (``KEY =``) counts as
  not set, as in LinuxCNC.
- ``#INCLUDE file`` in the INI file inserts that file's lines (``~`` and ``$VARS`` expanded,
  relative to the INI file's folder). As LinuxCNC's launcher does, only the INI file's own
  ``#INCLUDE`` lines are expanded (one level), and a missing file is a warning, not an error.
- Lines LinuxCNC ignores (no ``=``, a key before any section, a header without ``]``) are
  ignored with a warning. Warnings are ``file:line: text`` in ``IniFile.warnings``.

Every value remembers the file and line it came from, so a bad value can be reported as
``file:line: cause`` by whoever interprets it (``cnc.inischema`` checks every key the
controller reads).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

_TRUE_WORDS = {"1", "true", "yes", "on"}
_FALSE_WORDS = {"0", "false", "no", "off"}
MAX_EXTEND_LINES = 20  # LinuxCNC's limit on backslash continuations
_UNREADABLE_SECTION = "\0"  # keys after a broken or repeated header belong to no section


class IniError(ValueError):
    """A malformed INI file or value; ``str()`` is ``file:line: cause`` (``file: cause``
    when no line applies, e.g. a missing key)."""

    def __init__(self, file: str, line: int, cause: str) -> None:
        super().__init__(f"{file}:{line}: {cause}" if line > 0 else f"{file}: {cause}")
        self.file = file
        self.line = line
        self.cause = cause


class IniValue:
    """One ``KEY = VALUE`` line: its value and where it was written."""

    __slots__ = ("file", "line", "value")

    def __init__(self, value: str, file: str, line: int) -> None:
        self.value = value
        self.file = file
        self.line = line

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"

    def error(self, cause: str) -> IniError:
        return IniError(self.file, self.line, cause)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, IniValue):
            return NotImplemented
        return (self.value, self.file, self.line) == (other.value, other.file, other.line)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"IniValue({self.value!r}, {self.file!r}, {self.line})"


class IniFile:
    """A parsed INI file; the Python face of LinuxCNC's ``linuxcnc.ini``."""

    def __init__(self, path: str = "<string>") -> None:
        self.path = path
        self.warnings: list[str] = []
        self._sections: dict[str, list[tuple[str, IniValue]]] = {}
        self._headers: dict[str, IniValue] = {}  # section -> where its (first) header is
        self._every: list[tuple[str, IniValue]] = []  # every KEY = VALUE, in file order

    # ----------------------------------------------------------------- loading
    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> IniFile:
        """Read ``path`` (and the files it ``#INCLUDE``s); IniError if it cannot be read."""
        ini = cls(os.fspath(path))
        ini._parse(_read_lines(ini.path), ini.path, None, is_top=True)
        return ini

    @classmethod
    def from_text(cls, text: str, path: str = "<string>") -> IniFile:
        ini = cls(path)
        ini._parse(_split_lines(text), path, None, is_top=True)
        return ini

    def _warn(self, file: str, line: int, text: str) -> None:
        self.warnings.append(f"{file}:{line}: {text}")

    def _parse(
        self, lines: list[str], file: str, section: str | None, *, is_top: bool
    ) -> str | None:
        """Read ``lines`` of ``file``, starting in ``section``; returns the section the last
        line is in (an included file's lines continue the including file's section)."""
        index = 0
        while index < len(lines):
            lineno = index + 1
            raw = lines[index]
            index += 1
            extends = 0
            while raw.endswith("\\") and index < len(lines) and extends < MAX_EXTEND_LINES:
                raw = raw[:-1] + lines[index]
                index += 1
                extends += 1
            if extends == MAX_EXTEND_LINES and raw.endswith("\\"):
                self._warn(
                    file,
                    lineno,
                    f"continued on more than {MAX_EXTEND_LINES} lines: "
                    "the value ends there (LinuxCNC refuses it)",
                )
                raw = raw[:-1]
            stripped = raw.strip()
            if not stripped:
                continue
            if stripped.startswith("#INCLUDE") and stripped[8:9] in ("", " ", "\t"):
                if is_top:
                    section = self._include(stripped[8:].strip(), file, lineno, section)
                    continue
                self._warn(
                    file,
                    lineno,
                    "#INCLUDE in an included file is not expanded "
                    "(LinuxCNC expands one level only)",
                )
                continue
            if stripped[0] in "#;":
                continue
            if stripped[0] == "[":
                section = self._header(stripped, file, lineno)
                continue
            key, equals, value = stripped.partition("=")
            key = key.strip()
            if not equals or not key:
                self._warn(file, lineno, f"ignored, not KEY = VALUE: {stripped[:60]}")
                continue
            entry = IniValue(value.strip(), file, lineno)
            self._every.append((key, entry))
            if section is None:
                self._warn(file, lineno, f"{key} before any [SECTION]: ignored")
            elif section != _UNREADABLE_SECTION:
                self._sections[section].append((key, entry))
        return section

    def _header(self, text: str, file: str, lineno: int) -> str:
        end = text.find("]")
        name = text[1:end] if end > 0 else ""
        if not name:
            self._warn(
                file,
                lineno,
                f"not a section header: {text[:60]}; the keys up to the next header are ignored",
            )
            return _UNREADABLE_SECTION
        first = self._headers.get(name)
        if first is not None:
            self._warn(
                file,
                lineno,
                f"[{name}] repeated (first at {first.where}): LinuxCNC "
                "reads only the first, so the keys up to the next header are ignored",
            )
            return _UNREADABLE_SECTION
        self._headers[name] = IniValue("", file, lineno)
        self._sections[name] = []
        return name

    def _include(self, name: str, file: str, lineno: int, section: str | None) -> str | None:
        if not name:
            self._warn(file, lineno, "#INCLUDE without a file name: ignored")
            return section
        target = Path(os.path.expandvars(os.path.expanduser(name)))
        if not target.is_absolute():
            target = Path(file).parent / target
        try:
            lines = _read_lines(str(target))
        except IniError:
            self._warn(file, lineno, f"#INCLUDE {name}: cannot read {target}: ignored")
            return section
        return self._parse(lines, str(target), section, is_top=False)

    # ----------------------------------------------------------------- queries
    def sections(self) -> list[str]:
        return list(self._sections)

    def has_section(self, section: str) -> bool:
        return section in self._sections

    def header(self, section: str) -> IniValue | None:
        """Where ``[section]`` starts (value empty), or None if there is no such section."""
        return self._headers.get(section)

    def items(self, section: str) -> list[tuple[str, str]]:
        return [(key, entry.value) for key, entry in self._sections.get(section, [])]

    def section_entries(self, section: str) -> list[tuple[str, IniValue]]:
        """Every ``KEY = VALUE`` of ``[section]`` in file order, with its file and line."""
        return list(self._sections.get(section, []))

    def entry(self, section: str, key: str) -> IniValue | None:
        """The first ``[section]key`` line (its value may be empty), or None."""
        for name, entry in self._sections.get(section, []):
            if name == key:
                return entry
        return None

    def entries(self, section: str, key: str) -> list[IniValue]:
        """Every ``[section]key`` in file order, each with its file and line."""
        return [entry for name, entry in self._sections.get(section, []) if name == key]

    def find(self, section: str, key: str, default: str | None = None) -> str | None:
        """First value of ``[section]key``, or ``default`` if missing or empty."""
        found = self.entry(section, key)
        return default if found is None or not found.value else found.value

    def findall(self, section: str, key: str) -> list[str]:
        """Every value of ``[section]key`` in file order, up to the first empty one
        (``linuxcnc.ini.findall``)."""
        values = []
        for entry in self.entries(section, key):
            if not entry.value:
                break
            values.append(entry.value)
        return values

    def find_nth(self, section: str | None, key: str, num: int = 1) -> str | None:
        """The ``num``-th (from 1) value of ``key`` in ``section``, or in any section when
        ``section`` is None (as LinuxCNC's ``IniFile::Find``); None if missing or empty."""
        found = self.entries(section, key) if section is not None else self._anywhere(key)
        if not 1 <= num <= len(found) or not found[num - 1].value:
            return None
        return found[num - 1].value

    def _anywhere(self, key: str) -> list[IniValue]:
        return [entry for name, entry in self._every if name == key]

    def _convert(self, section: str, key: str, kind: str, convert):  # type: ignore[no-untyped-def]
        found = self.entry(section, key)
        if found is None or not found.value:
            return None
        try:
            return convert(found.value)
        except ValueError:
            raise found.error(f"[{section}]{key} = '{found.value}' is not {kind}") from None

    def get_float(self, section: str, key: str, default: float | None = None) -> float | None:
        value = self._convert(section, key, "a finite number", parse_float)
        return default if value is None else value

    def get_int(self, section: str, key: str, default: int | None = None) -> int | None:
        value = self._convert(section, key, "an integer", parse_int)
        return default if value is None else value

    def get_bool(self, section: str, key: str, default: bool | None = None) -> bool | None:
        value = self._convert(section, key, "a boolean (1/0, yes/no, true/false)", parse_bool)
        return default if value is None else value

    def require(self, section: str, key: str) -> str:
        """The value of ``[section]key``; an IniError naming the file if it is missing."""
        value = self.find(section, key)
        if value is None:
            raise IniError(self.path, 0, f"missing required [{section}]{key}")
        return value


# --------------------------------------------------------------------------- values
def parse_float(text: str) -> float:
    """A finite decimal number (``1``, ``-2.5``, ``.5``, ``1e-3``); ValueError otherwise.
    Unlike C's ``sscanf``, nothing may follow the number, and nan and inf are refused."""
    value = float(text)
    if value != value or value in (float("inf"), float("-inf")) or "_" in text:
        raise ValueError(text)
    return value


def parse_int(text: str) -> int:
    """A decimal integer, or hexadecimal ``0x1F`` (CFG-002); ValueError otherwise."""
    word = text.strip()
    digits = word.lstrip("+-")
    if digits[:2].lower() == "0x":
        return int(word, 16)
    if "_" in word:
        raise ValueError(text)
    return int(word, 10)


def parse_bool(text: str) -> bool:
    """``1``/``0``, ``yes``/``no``, ``true``/``false`` (and ``on``/``off``), any case."""
    word = text.strip().lower()
    if word in _TRUE_WORDS:
        return True
    if word in _FALSE_WORDS:
        return False
    raise ValueError(text)


# --------------------------------------------------------------------------- files
def _read_lines(path: str) -> list[str]:
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except OSError as exc:
        raise IniError(path, 0, f"cannot read INI file: {exc.strerror}") from None
    return _split_lines(data.decode("utf-8", errors="replace"))


def _split_lines(text: str) -> list[str]:
    """Lines without their ``\\n`` or ``\\r\\n`` (a DOS file reads as a Unix one)."""
    lines = text.removeprefix("\ufeff").split("\n")
    return [line[:-1] if line.endswith("\r") else line for line in lines]


# --------------------------------------------------------------------------- inivar
INIVAR_USAGE = "-var <variable> {-tildeexpand} {-sec <section>} {-ini <INI file>} [-num <nth item>]"


def inivar(argv: list[str] | None = None) -> int:
    """``cnc inivar -var KEY [-sec SECTION] [-ini FILE] [-num N] [-tildeexpand]``: print a
    value, as LinuxCNC's ``inivar`` (its options, messages and exit statuses: 0 found, 1 not
    found or bad arguments, 255 unreadable file). Without ``-sec`` the first ``KEY`` of any
    section is printed; the default file is ``emc.ini``."""
    args = sys.argv[1:] if argv is None else argv
    prog = "inivar"
    options: dict[str, str] = {}
    is_tilde_expanded = False
    index = 0
    while index < len(args):
        word = args[index]
        if word == "-tildeexpand":
            is_tilde_expanded = not is_tilde_expanded
        elif word in ("-ini", "-var", "-sec", "-num"):
            if index == len(args) - 1:
                what = {"-ini": "INI file", "-var": "variable name", "-sec": "section name"}
                detail = (
                    f"{what[word]} not specified after {word}"
                    if word in what
                    else ("line not specified after -num")
                )
                print(f"{prog}: {detail}", file=sys.stderr)
                return 1
            options[word] = args[index + 1]
            index += 1
        else:
            print(f"{prog}: {INIVAR_USAGE}", file=sys.stderr)
            return 1
        index += 1
    num = 1
    if "-num" in options:
        try:
            num = int(options["-num"], 0)
        except ValueError:
            print(f"{prog}: invalid number after -num", file=sys.stderr)
            return 1
    if "-var" not in options:
        print(f"{prog}: no variable supplied", file=sys.stderr)
        return 1
    path = options.get("-ini", "emc.ini")
    try:
        ini = IniFile.load(os.path.expanduser(path))
    except IniError:
        print(f"{prog}: can't open {path}", file=sys.stderr)
        return 255
    section = options.get("-sec")
    value = ini.find_nth(section, options["-var"], num)
    if value is None:
        print(
            f"Can not find -sec {section or '(null)'} -var {options['-var']} -num {num} ",
            file=sys.stderr,
        )
        return 1
    if is_tilde_expanded and value.startswith("~/"):
        value = os.path.expanduser(value)
    print(value)
    return 0


if __name__ == "__main__":
    sys.exit(inivar())
