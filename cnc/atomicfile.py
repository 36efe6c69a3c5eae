"""Atomic file replacement for every file the controller writes (tool table, .var, positions).

A reader (or a crash) sees either the old file or the new one, never a half-written one.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path


def atomic_write_text(
    path: str | os.PathLike[str], text: str, *, keep_backup: bool = False
) -> None:
    """Replace ``path`` with ``text``: write a temporary file beside it, fsync, rename.

    With ``keep_backup`` the previous content is kept as ``path + '.bak'``, at every call
    that finds a previous file, as LinuxCNC keeps ``.var.bak`` at every save of the .var
    file (scripts remove it, so it must be there).
    """
    target = Path(path)
    if _has_content(target, text):
        # nothing changed: no write, no fsync (the interpreter saves at every synch); the
        # backup of the previous content is this same content
        if keep_backup:
            backup = target.with_name(target.name + ".bak")
            if not _has_content(backup, text):
                _copy_for_backup(target, backup)
        return
    directory = target.parent if str(target.parent) else Path(".")
    import tempfile  # here: it costs start-up time to every process that may write a file

    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as tmp:
            tmp.write(text)
            tmp.flush()
            os.fsync(tmp.fileno())
        if target.exists():
            os.chmod(tmp_name, target.stat().st_mode & 0o7777)
            if keep_backup:
                backup = target.with_name(target.name + ".bak")
                _copy_for_backup(target, backup)
        else:  # a new file gets the mode open() would give it, not mkstemp's 0600
            os.chmod(tmp_name, 0o666 & ~_umask())
        os.replace(tmp_name, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp_name)
        raise
    _fsync_directory(directory)


def _has_content(target: Path, text: str) -> bool:
    try:
        return target.read_text(encoding="utf-8") == text
    except (OSError, UnicodeDecodeError):
        return False


def _copy_for_backup(source: Path, backup: Path) -> None:
    import tempfile

    data = source.read_bytes()
    fd, tmp_name = tempfile.mkstemp(prefix=f".{backup.name}.", dir=backup.parent)
    try:
        with os.fdopen(fd, "wb") as tmp:
            tmp.write(data)
        os.chmod(tmp_name, source.stat().st_mode & 0o7777)
        os.replace(tmp_name, backup)
    except BaseException:  # (a full disk): no half-written backup is left behind
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp_name)
        raise


def _umask() -> int:
    """This process's umask, read without changing it (os.umask would, for a moment,
    for every thread)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return 0o022


def _fsync_directory(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
