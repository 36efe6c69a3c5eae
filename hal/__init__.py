"""HAL: pins, parameters, signals, functions and threads in shared memory (see README.md; the
component-writing API is ``hal.api``).

``import hal`` also gives LinuxCNC's Python API for userspace components:
``hal.component(name)``, ``hal.HAL_FLOAT``, ``hal.HAL_IN``, ``hal.get_value(name)`` ...
(loaded on first use, so importing the package stays cheap).
"""

from __future__ import annotations

import importlib
from typing import Any

_API = {
    *("HAL_BIT", "HAL_FLOAT", "HAL_S32", "HAL_U32", "HAL_S64", "HAL_U64"),
    *("HAL_IN", "HAL_OUT", "HAL_IO", "HAL_RO", "HAL_RW", "HalError", "component"),
    *("component_exists", "component_is_ready", "get_value", "pin_has_writer"),
}


def __getattr__(name: str) -> Any:
    if name in _API:
        api = importlib.import_module("hal.api")
        return getattr(api, name)
    raise AttributeError(f"module 'hal' has no attribute '{name}'")
