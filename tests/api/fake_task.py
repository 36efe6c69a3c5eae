"""A stand-in for task in the API tests: a real process on the other end of the buffers.

    python fake_task.py NML_FILE [--fail TEXT] [--hang TEXT]

Attaches as process ``emc`` (task's P lines), prints ``ready``, then for every command read
from emcCommand prints one JSON line ``{"type": NAME, "fields": {...}}`` and answers as task
does: EMC_STAT with the command's serial in ``echo_serial_number`` and status EXEC, then
DONE. An MDI command equal to the ``--fail`` text ends in ERROR (with an operator error on
emcError, as task reports it); one equal to the ``--hang`` text stays EXEC forever. Operator
messages (command.error_msg ...) are forwarded to emcError, as task forwards them, and
EMC_TASK_SET_MODE changes ``task.mode``.
"""

from __future__ import annotations

import argparse
import json
import sys

from nml import emc
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from nml.message import RCS_STATUS

OPERATOR_MESSAGES = (emc.EMC_OPERATOR_ERROR, emc.EMC_OPERATOR_TEXT, emc.EMC_OPERATOR_DISPLAY)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("nml")
    parser.add_argument("--fail", default="")
    parser.add_argument("--hang", default="")
    args = parser.parse_args()
    with Nml(load_config(args.nml), "emc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
        commands, status_buffer, errors = nml[EMC_COMMAND], nml[EMC_STATUS], nml[EMC_ERROR]
        status = emc.EMC_STAT()
        print("ready", flush=True)
        while True:
            command = commands.blocking_read(-1)
            if command is None:
                continue
            print(json.dumps({"type": command.NAME, "fields": command.to_python()}), flush=True)
            status.echo_serial_number = command.serial_number
            status.command_type = command.TYPE
            status.status = RCS_STATUS.EXEC
            status_buffer.write(status)
            text = getattr(command, "command", None) if command.NAME.endswith("EXECUTE") else None
            if text is not None and text == args.hang:
                continue
            if isinstance(command, OPERATOR_MESSAGES):
                errors.write(command)
            if isinstance(command, emc.EMC_TASK_SET_MODE):
                status.task.mode = command.mode
            if text is not None and text == args.fail:
                errors.write(emc.EMC_OPERATOR_ERROR(error=f"failed: {text}"))
                status.status = RCS_STATUS.ERROR
            else:
                status.status = RCS_STATUS.DONE
            status_buffer.write(status)


if __name__ == "__main__":
    sys.exit(main())
