"""Where ``[HAL]HALFILE`` entries are found: LinuxCNC's HAL library search.

A ``HALFILE`` value is a file name, optionally followed by arguments for a Tcl file
(``HALFILE = LIB:basic_sim.tcl -no_sim_spindle``). The file is found as LinuxCNC's launcher
finds it:

- ``LIB:name``: in the HAL library only (``hal/lib/``, LinuxCNC's ``hallib``);
- an absolute path: as it is (``~`` expanded, as ``inivar -tildeexpand`` does);
- any other name: the first readable file along the search path, which is the folders given
  with ``cnc run -H DIR`` (newest first), then the configuration's folder, then the HAL
  library (LinuxCNC's ``HALLIB_PATH=.:$HALLIB_DIR``).

The library's folder is exported as ``HALLIB_DIR`` and the search path as ``HALLIB_PATH``
(colon separated), as LinuxCNC exports them; Tcl HAL files use ``$::env(HALLIB_DIR)`` to
source the library's procedures.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from hal.core import HalError

#: the project's HAL library (LinuxCNC's ``hallib``): same file names, same roles
LIBRARY_DIR = Path(__file__).resolve().parent / "lib"
LIB_PREFIX = "LIB:"


@dataclass(frozen=True)
class HalFile:
    """One ``[HAL]HALFILE`` entry, found."""

    path: Path
    args: list[str] = field(default_factory=list)  # ``::argv`` of a Tcl file
    how: str = "REL"  # LinuxCNC's "Found file(...)" tag: LIB, ABS, REL or lib

    @property
    def is_tcl(self) -> bool:
        return self.path.suffix == ".tcl"


def search_path(config_dir: str | os.PathLike[str], extra_dirs: Sequence[str] = ()) -> list[Path]:
    """The folders searched for a plain HAL file name, in order."""
    return [*(Path(d) for d in extra_dirs), Path(config_dir), LIBRARY_DIR]


def split_entry(value: str) -> tuple[str, list[str]]:
    """``"LIB:basic_sim.tcl -no_sim_spindle"`` -> ``("LIB:basic_sim.tcl", ["-no_sim_spindle"])``:
    the first word names the file, the others are its arguments (split at blanks, as the
    launcher's shell ``read`` does)."""
    words = value.split()
    if not words:
        raise HalError("empty HALFILE entry")
    return words[0], words[1:]


def find_halfile(
    value: str, config_dir: str | os.PathLike[str], extra_dirs: Sequence[str] = ()
) -> HalFile:
    """The file a ``[HAL]HALFILE`` value names; HalError saying where it looked if none."""
    name, args = split_entry(value)
    if name.startswith(LIB_PREFIX):
        rest = name[len(LIB_PREFIX) :]
        if not rest:
            raise HalError(f"ill-formed HAL file name '{name}': nothing after 'LIB:'")
        path = LIBRARY_DIR / rest
        if not _is_readable_file(path):
            raise HalError(f"HAL file '{name}' not found in the HAL library ({LIBRARY_DIR})")
        return HalFile(path, args, "LIB")
    path = Path(name).expanduser()
    if path.is_absolute():
        if not _is_readable_file(path):
            raise HalError(f"HAL file '{name}' not found")
        return HalFile(path, args, "ABS")
    folders = search_path(config_dir, extra_dirs)
    for folder in folders:
        candidate = folder / path
        if _is_readable_file(candidate):
            how = "lib" if folder == LIBRARY_DIR else "REL"
            return HalFile(candidate, args, how)
    looked = ", ".join(str(f) for f in folders)
    raise HalError(f"HAL file '{name}' not found (looked in {looked})")


def exported_environment(
    config_dir: str | os.PathLike[str], extra_dirs: Sequence[str] = ()
) -> dict[str, str]:
    """``HALLIB_DIR`` and ``HALLIB_PATH`` as LinuxCNC's launcher exports them."""
    return {
        "HALLIB_DIR": str(LIBRARY_DIR),
        "HALLIB_PATH": ":".join(str(f) for f in search_path(config_dir, extra_dirs)),
    }


def _is_readable_file(path: Path) -> bool:
    return path.is_file() and os.access(path, os.R_OK)
