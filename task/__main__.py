"""``python -m task -ini CONFIG.ini``: the task process (LinuxCNC's milltask).

Started by the launcher after the NML buffers, the realtime host with motion and iocontrol
exist. SIGTERM or SIGINT end it cleanly: parameters and positions are saved atomically.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys

from cnc.ini import IniError, IniFile
from cnc.stdio import protect_output
from nml.channels import (
    EMC_COMMAND,
    EMC_ERROR,
    EMC_STATUS,
    MOTION_COMMAND,
    MOTION_STATUS,
    TOOL_COMMAND,
    TOOL_STATUS,
    Nml,
    load_config,
)
from nml.errors import NmlError
from task.interp.errors import InterpError

NML_PROCESS = "emc"  # task's P lines in LinuxCNC's NML files
BUFFERS = [
    EMC_COMMAND,
    EMC_STATUS,
    EMC_ERROR,
    TOOL_COMMAND,
    TOOL_STATUS,
    MOTION_COMMAND,
    MOTION_STATUS,
]


def main(argv: list[str] | None = None) -> int:
    protect_output()  # a closed stderr pipe must not kill it (cnc/stdio.py)
    parser = argparse.ArgumentParser(prog="task", description=__doc__.split("\n\n")[0])
    parser.add_argument("-ini", "--ini", required=True, help="the machine's INI file")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="task: %(message)s")
    try:
        ini = IniFile.load(args.ini)
        nml_file = ini.find("EMC", "NML_FILE") or os.environ.get("CNC_NML_FILE")
        if nml_file and not os.path.isabs(nml_file):
            nml_file = os.path.join(os.path.dirname(os.path.abspath(args.ini)), nml_file)
        nml = Nml(load_config(nml_file), NML_PROCESS, BUFFERS)
    except (IniError, NmlError) as exc:
        print(f"task: {exc}", file=sys.stderr)
        return 1
    from task.controller import Task

    is_running = True

    def stop(signum: int, _frame: object) -> None:
        nonlocal is_running
        is_running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    try:
        task = Task(ini, nml)
        task.start()
        while is_running:
            task.cycle()
        task.shutdown()
    except (IniError, InterpError) as exc:
        print(f"task: {exc}", file=sys.stderr)
        return 1
    finally:
        nml.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
