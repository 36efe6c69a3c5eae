"""Names of the project's POSIX shared-memory segments and semaphores, and their cleanup.

Every OS object the controller creates is named ``/cnc.<instance>.<kind>.<name>``. The
instance (environment variable ``CNC_INSTANCE``, default ``main``) keeps two machines, or a
test and a running machine, apart, and lets a launcher or a test remove everything one
instance created, even after a crash. POSIX semaphores show up in /dev/shm as ``sem.<name>``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import posix_ipc

INSTANCE_ENV = "CNC_INSTANCE"
DEFAULT_INSTANCE = "main"
SHM_DIR = Path("/dev/shm")
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]")


def current_instance() -> str:
    return _UNSAFE.sub("_", os.environ.get(INSTANCE_ENV, DEFAULT_INSTANCE)) or DEFAULT_INSTANCE


def ipc_name(kind: str, name: str, instance: str | None = None) -> str:
    """The OS name of one object, e.g. ``ipc_name('shm', 'emcStatus')``."""
    inst = current_instance() if instance is None else _UNSAFE.sub("_", instance)
    return f"/cnc.{inst}.{kind}.{_UNSAFE.sub('_', name)}"


def instance_objects(instance: str | None = None) -> list[str]:
    """OS names of every segment and semaphore of an instance that exists now."""
    prefix = ipc_name("", "", instance)[1:].rstrip(".")
    found = []
    for entry in SHM_DIR.iterdir() if SHM_DIR.is_dir() else []:
        if entry.name.startswith(prefix + "."):
            found.append("/" + entry.name)
        elif entry.name.startswith("sem." + prefix + "."):
            found.append("/" + entry.name[4:])
    return sorted(found)


def remove_instance_objects(instance: str | None = None) -> list[str]:
    """Unlink every segment and semaphore of an instance; returns the names removed."""
    prefix = ipc_name("", "", instance)[1:].rstrip(".")
    removed = []
    for entry in SHM_DIR.iterdir() if SHM_DIR.is_dir() else []:
        try:
            if entry.name.startswith(prefix + "."):
                posix_ipc.unlink_shared_memory("/" + entry.name)
                removed.append("/" + entry.name)
            elif entry.name.startswith("sem." + prefix + "."):
                posix_ipc.unlink_semaphore("/" + entry.name[4:])
                removed.append("/" + entry.name[4:])
        except posix_ipc.ExistentialError:
            pass
    return removed
