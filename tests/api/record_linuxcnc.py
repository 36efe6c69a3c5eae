"""Record what LinuxCNC's ``linuxcnc`` module offers, for test_linuxcnc_parity.py.

    /usr/bin/python3 tests/api/record_linuxcnc.py > tests/api/linuxcnc_module.json

Run with a Python that has LinuxCNC 2.9's module (Debian's linuxcnc-uspace); LinuxCNC need
not be running: a stat object that is not connected shows the type of every attribute.
"""

from __future__ import annotations

import json
import re
import sys


def describe(value: object) -> object:
    """A value's shape: its type name; tuples with length and first item; dicts by key."""
    if isinstance(value, tuple):
        return ["tuple", len(value), describe(value[0]) if value else None]
    if isinstance(value, dict):
        return ["dict", {key: type(item).__name__ for key, item in value.items()}]
    return type(value).__name__


def main() -> int:
    import linuxcnc  # type: ignore[import-not-found]  (only where LinuxCNC is installed)

    status = linuxcnc.stat()
    command = linuxcnc.command()
    sample_tool = repr(linuxcnc.tool((0,) * linuxcnc.tool.n_fields))
    record = {
        "constants": {
            name: getattr(linuxcnc, name)
            for name in dir(linuxcnc)
            if not name.startswith("_") and type(getattr(linuxcnc, name)) is int
        },
        "stat": {
            name: describe(getattr(status, name))
            for name in dir(status)
            if not name.startswith("_") and name != "poll"
        },
        "command": sorted(name for name in dir(command) if not name.startswith("_")),
        "tool": re.findall(r"(\w+)=", sample_tool),
    }
    json.dump(record, sys.stdout, indent=1, sort_keys=True)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
