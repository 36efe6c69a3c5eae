"""``python -m iocontrol -ini CONFIG.ini``: the iocontrol process (LinuxCNC's ``io -ini FILE``).

Exit status 0 after SIGTERM / SIGINT, 1 if it cannot start (bad INI, no NML buffers, HAL
component already present); the reason is printed on stderr as ``file:line: cause`` where
a file is at fault.
"""

from __future__ import annotations

import argparse
import sys

from cnc.ini import IniError
from cnc.stdio import protect_output
from iocontrol.config import load_io_config
from iocontrol.controller import run


def main(argv: list[str] | None = None) -> int:
    protect_output()  # a closed stderr pipe must not kill it (cnc/stdio.py)
    parser = argparse.ArgumentParser(
        prog="iocontrol", description="e-stop, coolant, lube and tool changer I/O over HAL"
    )
    parser.add_argument("-ini", "--ini", dest="ini", required=True, help="the machine's INI file")
    args = parser.parse_args(argv)
    try:
        config = load_io_config(args.ini)
    except IniError as exc:
        print(f"iocontrol: {exc}", file=sys.stderr)
        return 1
    for warning in config.warnings:
        print(f"iocontrol: {warning}", file=sys.stderr)
    return run(config)


if __name__ == "__main__":
    sys.exit(main())
