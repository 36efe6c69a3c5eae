"""``cnc.ini(path)``: LinuxCNC's ``linuxcnc.ini``, over ``cnc.ini.IniFile``.

``cnc.ini`` is also the module that defines ``IniFile``; the ``cnc`` package makes calling
that module open a file the LinuxCNC way (see cnc/__init__.py), so both
``cnc.ini("mill.ini").find("EMC", "MACHINE")`` and ``from cnc.ini import IniFile`` work.
"""

from __future__ import annotations

import os

from cnc.api.errors import error
from cnc.ini import IniError, IniFile


class ini:  # LinuxCNC's name: linuxcnc.ini
    """An INI file, read once; ``cnc.error`` if it cannot be read or parsed."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        try:
            self._file = IniFile.load(path)
        except IniError as exc:
            raise error(f"inifile.open({os.fspath(path)}) failed: {exc}") from None

    def find(self, section: str, key: str, num: int = 1) -> str | None:
        """The ``num``-th (from 1) value of ``[section]key``, or None (also for an empty
        value, as LinuxCNC's)."""
        return self._file.find_nth(section, key, num)

    def findall(self, section: str, key: str) -> list[str]:
        """Every value of ``[section]key`` in file order, up to the first empty one."""
        return self._file.findall(section, key)
