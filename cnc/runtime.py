"""Where a running controller can be found: the runtime-info file.

The launcher holds the instance's lock (``claim_instance``) from its first step to its
last, calls ``write_runtime_info(ini, nml)`` once the machine is ready (HAL files, task,
display and POSTGUI files done) and ``remove_runtime_info()`` when it shuts down. The file is
``${XDG_RUNTIME_DIR:-/tmp}/cnc-<instance>.json`` (instance: ``$CNC_INSTANCE``, default
``main``), written atomically, e.g.::

    {"instance": "main", "ini": "/home/me/mill/mill.ini",
     "nml": "/home/me/cnc/configs/common/cnc.nml", "pid": 4242}

``cnc.stat()``, ``cnc.command()`` and ``cnc.error_channel()`` without an argument read it to
find the NML file of the running machine. A file whose launcher (``pid``) is gone is stale
and ignored.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
from dataclasses import dataclass
from pathlib import Path

from cnc.atomicfile import atomic_write_text
from nml.ipcnames import current_instance
from nml.shmem import is_process_alive


@dataclass(frozen=True)
class RuntimeInfo:
    instance: str
    ini: Path
    nml: Path
    pid: int


def runtime_info_path(instance: str | None = None) -> Path:
    """The runtime-info file of an instance (default: the current one)."""
    folder = os.environ.get("XDG_RUNTIME_DIR") or "/tmp"
    return Path(folder) / f"cnc-{instance or current_instance()}.json"


def write_runtime_info(ini_path: str | os.PathLike[str], nml_path: str | os.PathLike[str]) -> Path:
    """Record that this process runs the machine of ``ini_path`` with ``nml_path``."""
    path = runtime_info_path()
    record = {
        "instance": current_instance(),
        "ini": str(Path(ini_path).resolve()),
        "nml": str(Path(nml_path).resolve()),
        "pid": os.getpid(),
    }
    atomic_write_text(path, json.dumps(record, indent=1) + "\n")
    return path


def read_runtime_info(
    instance: str | None = None, *, is_stale_included: bool = False
) -> RuntimeInfo | None:
    """The running machine of an instance, or None (no file, unreadable, or stale; with
    ``is_stale_included`` a stale one too: what a killed launcher left)."""
    try:
        record = json.loads(runtime_info_path(instance).read_text(encoding="utf-8"))
        info = RuntimeInfo(
            instance=str(record["instance"]),
            ini=Path(record["ini"]),
            nml=Path(record["nml"]),
            pid=int(record["pid"]),
        )
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return info if is_stale_included or is_process_alive(info.pid) else None


def claim_instance() -> int | None:
    """Take the current instance for this process: an open file descriptor holding an
    exclusive lock (released by the kernel when the process ends, even by kill -9), or None
    when another process holds it (a machine is running or starting)."""
    path = runtime_info_path().with_suffix(".lock")
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    return fd


def release_instance(fd: int) -> None:
    """Give the instance back (after shutting down); the lock file goes too."""
    with contextlib.suppress(OSError):
        runtime_info_path().with_suffix(".lock").unlink()
    os.close(fd)


def remove_runtime_info() -> None:
    """Remove the current instance's file if this process wrote it (or its writer is gone)."""
    path = runtime_info_path()
    with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
        pid = int(json.loads(path.read_text(encoding="utf-8"))["pid"])
        if pid == os.getpid() or not is_process_alive(pid):
            path.unlink()
