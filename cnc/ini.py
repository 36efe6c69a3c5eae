"""INI files as LinuxCNC reads them (CFG-*).

- ``[SECTION]`` headers; ``KEY = VALUE`` lines; keys and sections are case sensitive.
- Lines whose first non-blank character is ``#`` or ``;`` are comments; a ``#`` or ``;``
  later in a line is part of the value (LinuxCNC has no end-of-line comments).
- A trailing backslash continues the value on the next line.
- A key may repeat (``HALFILE``, ``[FILTER]PROGRAM_EXTENSION``): ``find`` returns the first
  value, ``findall`` every value in file order.
- ``#INCLUDE file`` inserts another file (``~`` expanded, relative paths from the including
  file's folder), as the ``linuxcnc`` launcher does before anything reads the INI.

Every value remembers the file and line it came from, so a bad value can be reported as
``file:line: cause`` by whoever interprets it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

_TRUE_WORDS = {"1", "true", "yes", "on"}
_FALSE_WORDS = {"0", "false", "no", "off"}
_MAX_INCLUDE_DEPTH = 10


class IniError(ValueError):
    """A malformed INI file or value; ``str()`` is ``file:line: cause``."""

    def __init__(self, file: str, line: int, cause: str) -> None:
        super().__init__(f"{file}:{line}: {cause}")
        self.file = file
        self.line = line
        self.cause = cause


@dataclass(frozen=True)
class IniValue:
    value: str
    file: str
    line: int


class IniFile:
    """A parsed INI file; the Python face of LinuxCNC's ``linuxcnc.ini``."""

    def __init__(self, path: str = "<string>") -> None:
        self.path = path
        self._sections: dict[str, list[tuple[str, IniValue]]] = {}

    # ----------------------------------------------------------------- loading
    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> IniFile:
        ini = cls(str(path))
        ini._parse_file(Path(path), depth=0, section=None)
        return ini

    @classmethod
    def from_text(cls, text: str, path: str = "<string>") -> IniFile:
        ini = cls(path)
        ini._parse_lines(text.splitlines(), path, Path(path).parent, depth=0, section=None)
        return ini

    def _parse_file(self, path: Path, depth: int, section: str | None) -> str | None:
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError as exc:
            raise IniError(str(path), 0, f"cannot read INI file: {exc.strerror}") from exc
        return self._parse_lines(text.splitlines(), str(path), path.parent, depth, section)

    def _parse_lines(
        self, lines: list[str], file: str, folder: Path, depth: int, section: str | None
    ) -> str | None:
        index = 0
        while index < len(lines):
            lineno = index + 1
            raw = lines[index]
            index += 1
            while raw.endswith("\\") and index < len(lines):
                raw = raw[:-1] + lines[index]
                index += 1
            stripped = raw.strip()
            if not stripped:
                continue
            if stripped.upper().startswith("#INCLUDE"):
                section = self._include(stripped, file, lineno, folder, depth, section)
                continue
            if stripped[0] in "#;":
                continue
            if stripped.startswith("["):
                end = stripped.find("]")
                if end < 0:
                    raise IniError(file, lineno, f"section header without ']': {stripped}")
                section = stripped[1:end].strip()
                if not section:
                    raise IniError(file, lineno, "empty section name")
                self._sections.setdefault(section, [])
                continue
            if "=" not in stripped:
                raise IniError(file, lineno, f"expected KEY = VALUE, got: {stripped}")
            if section is None:
                raise IniError(file, lineno, "KEY = VALUE before any [SECTION]")
            key, value = stripped.split("=", 1)
            key = key.strip()
            if not key:
                raise IniError(file, lineno, "empty key before '='")
            self._sections[section].append((key, IniValue(value.strip(), file, lineno)))
        return section

    def _include(
        self, line: str, file: str, lineno: int, folder: Path, depth: int, section: str | None
    ) -> str | None:
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise IniError(file, lineno, "#INCLUDE without a file name")
        if depth >= _MAX_INCLUDE_DEPTH:
            raise IniError(file, lineno, "#INCLUDE nested too deeply (a loop?)")
        target = Path(os.path.expanduser(parts[1].strip()))
        if not target.is_absolute():
            target = folder / target
        if not target.is_file():
            raise IniError(file, lineno, f"#INCLUDE file not found: {target}")
        return self._parse_file(target, depth + 1, section)

    # ----------------------------------------------------------------- queries
    def sections(self) -> list[str]:
        return list(self._sections)

    def has_section(self, section: str) -> bool:
        return section in self._sections

    def items(self, section: str) -> list[tuple[str, str]]:
        return [(key, entry.value) for key, entry in self._sections.get(section, [])]

    def entry(self, section: str, key: str) -> IniValue | None:
        for name, entry in self._sections.get(section, []):
            if name == key:
                return entry
        return None

    def entries(self, section: str, key: str) -> list[IniValue]:
        """Every ``[section]key`` in file order, each with its file and line."""
        return [entry for name, entry in self._sections.get(section, []) if name == key]

    def find(self, section: str, key: str, default: str | None = None) -> str | None:
        """First value of ``[section]key``, or ``default`` (``linuxcnc.ini.find``)."""
        found = self.entry(section, key)
        return default if found is None else found.value

    def findall(self, section: str, key: str) -> list[str]:
        """Every value of ``[section]key`` in file order (``linuxcnc.ini.findall``)."""
        return [entry.value for name, entry in self._sections.get(section, []) if name == key]

    def _convert(self, section: str, key: str, kind: str, convert):  # type: ignore[no-untyped-def]
        found = self.entry(section, key)
        if found is None:
            return None
        try:
            return convert(found.value)
        except ValueError:
            raise IniError(
                found.file, found.line, f"[{section}]{key} = '{found.value}' is not {kind}"
            ) from None

    def get_float(self, section: str, key: str, default: float | None = None) -> float | None:
        value = self._convert(section, key, "a number", float)
        return default if value is None else value

    def get_int(self, section: str, key: str, default: int | None = None) -> int | None:
        value = self._convert(section, key, "an integer", lambda text: int(text, 0))
        return default if value is None else value

    def get_bool(self, section: str, key: str, default: bool | None = None) -> bool | None:
        def to_bool(text: str) -> bool:
            word = text.strip().lower()
            if word in _TRUE_WORDS:
                return True
            if word in _FALSE_WORDS:
                return False
            raise ValueError(text)

        value = self._convert(section, key, "a boolean (0/1, yes/no, true/false)", to_bool)
        return default if value is None else value

    def require(self, section: str, key: str) -> str:
        """The value of ``[section]key``; an IniError naming the file if it is missing."""
        value = self.find(section, key)
        if value is None:
            raise IniError(self.path, 0, f"missing required [{section}]{key}")
        return value
