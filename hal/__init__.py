"""HAL: pins, parameters, signals, functions and threads in shared memory (see README.md; the
component-writing API is ``hal.api``).

``import hal`` is also LinuxCNC's Python ``hal`` module, for user scripts and userspace
components written for LinuxCNC: ``hal.component(name)``, ``hal.HAL_FLOAT``,
``hal.connect(...)``, ``hal.stream(...)``... (``hal.pymodule``, loaded on first use so that
importing ``hal.core`` stays cheap). No name of LinuxCNC's module is a module of ours.
"""

from __future__ import annotations

import importlib
from typing import Any

#: the names of LinuxCNC's Python ``hal`` module, all defined in hal/pymodule.py
LINUXCNC_NAMES = (
    *("HAL_BIT", "HAL_FLOAT", "HAL_S32", "HAL_U32", "HAL_S64", "HAL_U64"),
    *("HAL_IN", "HAL_OUT", "HAL_IO", "HAL_RO", "HAL_RW"),
    *("MSG_NONE", "MSG_ERR", "MSG_WARN", "MSG_INFO", "MSG_DBG", "MSG_ALL"),
    *("component", "item", "Pin", "Param", "stream", "shm", "error"),
    *("component_exists", "component_is_ready", "pin_has_writer"),
    *("new_sig", "connect", "disconnect", "set_p", "get_value"),
    *("get_info_pins", "get_info_signals", "get_info_params"),
    *("set_msg_level", "get_msg_level", "sampler_base", "streamer_base"),
    *("is_sim", "is_rt", "is_kernelspace", "is_userspace", "kernel_version"),
)


def __getattr__(name: str) -> Any:
    if name == "__all__":
        return list(LINUXCNC_NAMES)
    if name in LINUXCNC_NAMES:
        return getattr(importlib.import_module("hal.pymodule"), name)
    raise AttributeError(f"module 'hal' has no attribute '{name}'")


def __dir__() -> list[str]:
    return sorted({*globals(), *LINUXCNC_NAMES})
