"""Which NML file the API uses, and attaching to the controller's buffers as a UI does.

The NML file, in order of precedence:

1. the argument of ``stat()`` / ``command()`` / ``error_channel()``: an NML file, or an INI
   file (name ending in ``.ini``) whose ``[EMC]NML_FILE`` names it, relative to the INI's
   folder (``configs/common/cnc.nml`` if the key is absent);
2. ``cnc.nmlfile``, if the script assigned it (as LinuxCNC scripts assign
   ``linuxcnc.nmlfile``);
3. the NML file of the running machine, from its runtime-info file (``cnc.runtime``);
4. ``configs/common/cnc.nml``.

The API attaches as process ``xemc``, the user-interface P lines of LinuxCNC's NML files and
ours. Buffers that do not exist yet (controller not started) give ``cnc.error`` at once,
instead of waiting for the P line's timeout.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import time
import weakref
from pathlib import Path

import posix_ipc

from cnc.api.errors import error
from cnc.ini import IniError, IniFile
from cnc.runtime import read_runtime_info
from nml.channels import DEFAULT_NML_FILE, load_config
from nml.config import NmlConfig
from nml.errors import NmlError
from nml.ipcnames import current_instance, ipc_name
from nml.shmem import ShmBuffer

UI_PROCESS = "xemc"


def default_nml_file() -> Path:
    """The NML file used when none is named: ``cnc.nmlfile``, the running machine's, ours."""
    assigned = sys.modules["cnc"].__dict__.get("nmlfile")
    if assigned:
        return Path(assigned)
    info = read_runtime_info()
    return info.nml if info is not None else DEFAULT_NML_FILE


def resolve_nml_file(source: str | os.PathLike[str] | None) -> Path:
    """The NML file for an API object's argument (None, an NML file or an INI file)."""
    if source is None:
        return default_nml_file()
    path = Path(source)
    if path.suffix.lower() != ".ini":
        return path
    try:
        value = IniFile.load(path).find("EMC", "NML_FILE")
    except IniError as exc:
        raise error(str(exc)) from None
    if not value:
        return DEFAULT_NML_FILE
    nml = Path(os.path.expanduser(value))
    return nml if nml.is_absolute() else path.parent / nml


def load_nml(path: Path) -> NmlConfig:
    """The parsed NML file (parsed again only when the file changes)."""
    try:
        return _parsed(str(path), path.stat().st_mtime_ns)
    except OSError as exc:
        raise error(f"{path}: cannot read NML file: {exc.strerror}") from None
    except NmlError as exc:
        raise error(str(exc)) from None


@functools.lru_cache(maxsize=8)
def _parsed(path: str, mtime_ns: int) -> NmlConfig:
    return load_config(path)


def is_running(buffer: str) -> bool:
    """Whether the controller has created ``buffer`` (its shared-memory segment exists)."""
    try:
        posix_ipc.SharedMemory(ipc_name("shm", buffer)).close_fd()
    except posix_ipc.ExistentialError:
        return False
    return True


LIVENESS_CHECK_S = 0.2  # how often a link checks that the controller still runs
ATTACH_NOW_S = 0.5  # what a constructor waits for a buffer's lock before attaching later


class Link:
    """The buffers of one API object, attached on first use, detached by ``close()``.

    An owner calls ``close_with(owner)`` so that its buffers are detached when it is
    garbage-collected, which frees the connection slots (``max_procs``) it held.
    """

    def __init__(self, source: str | os.PathLike[str] | None) -> None:
        self.nml_path = resolve_nml_file(source)
        self.config = load_nml(self.nml_path)
        self._buffers: dict[str, ShmBuffer] = {}
        self._checked_at = 0.0

    def close_with(self, owner: object) -> None:
        weakref.finalize(owner, self.close)

    def buffer(self, name: str, lock_timeout: float | None = None) -> ShmBuffer:
        """The attached buffer ``name``; ``cnc.error`` if the controller is not running.

        Every LIVENESS_CHECK_S the buffers are checked: once the controller has stopped
        they are dropped (the next use says it is not running, or attaches to the buffers
        of a controller started since), so a UI never shows a frozen machine."""
        now = time.monotonic()
        if now - self._checked_at > LIVENESS_CHECK_S:
            self._checked_at = now
            if any(buffer.is_orphaned() for buffer in self._buffers.values()):
                self.close()
        found = self._buffers.get(name)
        if found is None:
            found = self._buffers[name] = self._attach(name, lock_timeout)
        return found

    def try_attach(self, name: str) -> None:
        """Attach now if the controller runs (else on first use). A buffer whose lock a
        stuck process holds is attached later: making an API object never hangs."""
        if name not in self._buffers and is_running(name):
            with contextlib.suppress(error):
                self.buffer(name, lock_timeout=ATTACH_NOW_S)

    def _attach(self, name: str, lock_timeout: float | None = None) -> ShmBuffer:
        if name not in self.config.buffers:
            raise error(f"{self.nml_path}: no buffer '{name}' in this NML file")
        if not is_running(name):
            raise error(
                f"{name}: the controller is not running (instance '{current_instance()}', "
                f"NML file {self.nml_path})"
            )
        try:
            buffer = ShmBuffer(
                self.config.buffers[name],
                self.config.process(UI_PROCESS, name),
                lock_timeout=lock_timeout,
            )
        except NmlError as exc:
            raise error(str(exc)) from None
        if buffer.is_orphaned():
            buffer.close()
            raise error(f"{name}: the controller is not running (its buffers were left over)")
        return buffer

    def close(self) -> None:
        for buffer in self._buffers.values():
            buffer.close()
        self._buffers.clear()
