"""Replaceable modules (ARCH-007/008): load by name and check the interface.

A replacement trajectory planner, homing or kinematics module must provide every function
the default provides; ``require`` refuses an incomplete one with an error that lists every
missing name, so a user sees the whole problem at once.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from types import ModuleType


class ModuleInterfaceError(ImportError):
    """A module could not be loaded or does not provide the required interface."""


def import_module(name: str, builtin_package: str, what: str) -> ModuleType:
    """Import ``name``: a built-in module of ``builtin_package`` or a dotted module path."""
    if not name or not all(part.isidentifier() for part in name.split(".")):
        raise ModuleInterfaceError(f"invalid {what} module name {name!r}")
    candidates = [name] if "." in name else [f"{builtin_package}.{name}", name]
    errors = []
    for candidate in candidates:
        try:
            return importlib.import_module(candidate)
        except ModuleNotFoundError as exc:
            if exc.name is not None and not candidate.startswith(exc.name):
                raise  # the module exists but one of its own imports is missing
            errors.append(candidate)
    raise ModuleInterfaceError(f"{what} module {name!r} not found (tried {', '.join(errors)})")


def missing_names(obj: object, required: Iterable[str]) -> list[str]:
    """The names of ``required`` that ``obj`` lacks as a function or property."""
    missing = []
    for name in required:
        value = getattr(obj, name, None)
        if not (callable(value) or isinstance(value, property)):
            missing.append(name)
    return missing


def require(obj: object, required: Iterable[str], what: str) -> None:
    """Raise ModuleInterfaceError listing every required function ``obj`` lacks."""
    missing = missing_names(obj, required)
    if missing:
        raise ModuleInterfaceError(f"{what} is incomplete: missing {', '.join(missing)}")
