"""``python -m cnc.halui [-ini CONFIG.ini]``: LinuxCNC's ``halui -ini FILE``.

Without ``-ini`` the INI file of the machine being started is used (``$CNC_INI_FILE``, set by
``cnc run`` for the programs it starts). Exit status 0 after SIGTERM / SIGINT, 1 if halui
cannot start (bad INI value as ``file:line: cause``, no HAL, a ``halui`` already there).
"""

from __future__ import annotations

import argparse
import os
import sys

from cnc.halui.config import load_config
from cnc.halui.core import warn
from cnc.ini import IniError
from cnc.stdio import protect_output

INI_ENV = "CNC_INI_FILE"


def main(argv: list[str] | None = None) -> int:
    protect_output()  # a closed stderr pipe must not kill it (cnc/stdio.py)
    parser = argparse.ArgumentParser(
        prog="halui", description="drive the machine from HAL pins (buttons, knobs, lamps)"
    )
    parser.add_argument(
        "-ini", "--ini", dest="ini", default=os.environ.get(INI_ENV), help="the machine's INI file"
    )
    args = parser.parse_args(argv)
    if not args.ini:
        warn(f"no INI file: give -ini FILE (or set {INI_ENV})")
        return 1
    try:
        config = load_config(args.ini)
    except IniError as exc:
        warn(str(exc))
        return 1
    from cnc.halui.process import run  # HAL and NML only once the INI file is good

    return run(config)


if __name__ == "__main__":
    sys.exit(main())
