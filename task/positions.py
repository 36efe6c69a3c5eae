"""[TRAJ]POSITION_FILE: the joint positions a machine without absolute encoders restarts from.

LinuxCNC's format: one joint position per line. Written atomically when task shuts down
(after motion has stopped), or by the launcher from motion's last report when task died.

A run leaves a marker beside the file (``.<name>.running``) from start-up until the
positions are saved: a start that finds it knows the last run ended without saving (the
whole machine killed, a power cut), so the saved positions are stale: they are not
restored and the joints must be homed.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence
from pathlib import Path

from cnc.atomicfile import atomic_write_text


class PositionFileError(Exception):
    """The file exists but cannot be read; the message says where and why."""


def marker(path: str | os.PathLike[str]) -> Path:
    target = Path(path)
    return target.with_name(f".{target.name}.running")


def read_positions(path: str | os.PathLike[str]) -> list[float]:
    """The saved joint positions ([] if there is no file). Raises PositionFileError."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    except (OSError, UnicodeDecodeError) as exc:
        raise PositionFileError(f"{path}: cannot read saved positions ({exc})") from None
    values = []
    for number, line in enumerate(text.splitlines(), start=1):
        for word in line.split():
            try:
                value = float(word)
            except ValueError:
                raise PositionFileError(f"{path}:{number}: '{word}' is not a number") from None
            if value != value or value in (float("inf"), float("-inf")):
                raise PositionFileError(f"{path}:{number}: '{word}' is not a position")
            values.append(value)
    return values


def write_positions(path: str | os.PathLike[str], positions: Sequence[float]) -> None:
    """Save the positions (all joints, as LinuxCNC writes them) and end the run's marker.
    Raises OSError (full disk, read-only folder): the caller tells the operator."""
    atomic_write_text(path, "".join(f"{value:.17f}\n" for value in positions))
    with contextlib.suppress(FileNotFoundError):
        marker(path).unlink()


def begin_run(path: str | os.PathLike[str]) -> bool:
    """Mark the positions as in use by this run; False if the last run never saved them."""
    flag = marker(path)
    was_clean = not flag.exists()
    with contextlib.suppress(OSError):  # (a read-only folder: nothing to save there either)
        flag.write_text(f"{os.getpid()}\n", encoding="utf-8")
    return was_clean
