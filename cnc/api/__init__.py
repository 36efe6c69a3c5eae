"""LinuxCNC's ``linuxcnc`` Python module, for this controller: ``import cnc as linuxcnc``.

The public names are reached through the ``cnc`` package (``cnc.stat``, ``cnc.command``,
``cnc.STATE_ESTOP`` ...), which loads them on first use (see ``lookup``), so that
``import cnc`` stays cheap for commands such as ``cnc rs274``. Where things live:

- ``constants``: LinuxCNC's integer constants (plain ints, no imports);
- ``errors``: ``cnc.error``;
- ``inifile``: ``cnc.ini(path)``, LinuxCNC's ``linuxcnc.ini``;
- ``connection``: which NML file to use and how to attach to the controller's buffers;
- ``status``: ``stat`` (and the ``tool`` record of ``stat.tool_table``);
- ``commands``: ``command``;
- ``operator``: ``error_channel``.

``cnc/README.md`` describes the API, the contract task follows and what differs from LinuxCNC.
"""

from __future__ import annotations

import importlib
from typing import Any

from cnc.api.errors import error as error  # (also `from cnc.api import error`)

# Public name -> submodule of cnc.api that defines it; constants are found in `constants`.
_HOMES = {
    "error": "cnc.api.errors",
    "stat": "cnc.api.status",
    "tool": "cnc.api.status",
    "command": "cnc.api.commands",
    "error_channel": "cnc.api.operator",
}


def lookup(name: str) -> Any:
    """The value of the public name ``cnc.<name>``; AttributeError if there is none."""
    home = _HOMES.get(name)
    if home is not None:
        return getattr(importlib.import_module(home), name)
    if name == "nmlfile":
        from cnc.api.connection import default_nml_file

        return str(default_nml_file())
    from cnc.api import constants

    if name in constants.__all__:
        return getattr(constants, name)
    raise AttributeError(f"module 'cnc' has no attribute '{name}'")


def public_names() -> list[str]:
    """Every name ``lookup`` knows (for ``dir(cnc)``)."""
    from cnc.api import constants

    return sorted([*_HOMES, "nmlfile", *constants.__all__])
