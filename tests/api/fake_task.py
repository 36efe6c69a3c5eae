"""A stand-in for task in the API tests: a real process on the other end of the buffers.

    python fake_task.py NML_FILE [--machine] [--fail TEXT] [--hang TEXT]

Attaches as process ``emc`` (task's P lines), prints ``ready``, then for every command read
from emcCommand prints one JSON line ``{"type": NAME, "fields": {...}}`` and answers as task
does: EMC_STAT with the command's serial in ``echo_serial_number`` and status EXEC, then
DONE. An MDI command equal to the ``--fail`` text ends in ERROR (with an operator error on
emcError, as task reports it); one equal to the ``--hang`` text stays EXEC forever. Operator
messages (command.error_msg ...) are forwarded to emcError, as task forwards them, and
EMC_TASK_SET_MODE changes ``task.mode``, EMC_TASK_PLAN_OPEN ``task.file``. With
``--machine`` it first publishes ``machine_status()`` (an XYZ mm machine in ESTOP, manual
mode, interpreter idle, at X12.5 Y-3.25 Z40 with a G54 offset of X10), and
EMC_TASK_SET_STATE changes ``task.state``, the E-stop flag and motion's enable, as the UI
tests need.
"""

from __future__ import annotations

import argparse
import json
import sys

from nml import emc
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from nml.message import RCS_STATUS

OPERATOR_MESSAGES = (emc.EMC_OPERATOR_ERROR, emc.EMC_OPERATOR_TEXT, emc.EMC_OPERATOR_DISPLAY)

STATE_ESTOP, STATE_ON, MODE_MANUAL = 1, 4, 1  # cnc.STATE_ESTOP ... (no API import here)
EXEC_DONE, INTERP_IDLE, TRAJ_MODE_FREE = 2, 1, 1
# The interpreter's codes at start-up: G1 G17 G40 G21 G90 G94 G54 G49 G99 G64 G97 G91.1 G8
# G92.2 (entry 0 is the line number, -1 a group without a code), M5 M9 M48.
G_CODES = [0, 10, -1, 170, 400, 210, 900, 940, 540, 490, 990, 640, -1, 970, 911, 80, 922]
M_CODES = [0, -1, 5, -1, 9, -1, 48, -1, -1, -1]


def machine_status() -> emc.EMC_STAT:
    status = emc.EMC_STAT(status=RCS_STATUS.DONE)
    task = status.task
    task.state, task.mode = STATE_ESTOP, MODE_MANUAL
    task.execState, task.interpState = EXEC_DONE, INTERP_IDLE
    task.g5x_index, task.g5x_offset.tran.x = 1, 10.0
    task.activeGCodes[:], task.activeMCodes[:] = G_CODES, M_CODES
    task.activeSettings[:] = [0.0, 500.0, 1000.0, 0.0, 0.0]
    traj = status.motion.traj
    traj.linearUnits, traj.angularUnits, traj.joints, traj.spindles = 1.0, 1.0, 3, 1
    traj.axis_mask, traj.mode, traj.inpos = 0b111, TRAJ_MODE_FREE, True
    traj.scale, traj.rapid_scale = 1.0, 1.0
    traj.position.tran.x, traj.position.tran.y, traj.position.tran.z = 12.5, -3.25, 40.0
    traj.actualPosition.tran.x = 12.5
    for number, value in enumerate((12.5, -3.25, 40.0)):
        joint = status.motion.joint[number]
        joint.output = joint.input = value
        joint.homed, joint.enabled, joint.jointType = number < 2, 1, 1
    status.motion.joint[2].minSoftLimit = 1
    spindle = status.motion.spindle[0]
    spindle.speed, spindle.direction, spindle.enabled, spindle.spindle_scale = 1000.0, 1, 1, 1.0
    status.io.tool.toolInSpindle = 3
    status.io.aux.estop = 1
    return status


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("nml")
    parser.add_argument("--fail", default="")
    parser.add_argument("--hang", default="")
    parser.add_argument("--machine", action="store_true")
    args = parser.parse_args()
    with Nml(load_config(args.nml), "emc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
        commands, status_buffer, errors = nml[EMC_COMMAND], nml[EMC_STATUS], nml[EMC_ERROR]
        status = machine_status() if args.machine else emc.EMC_STAT()
        if args.machine:
            status_buffer.write(status)
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
            if isinstance(command, emc.EMC_TASK_PLAN_OPEN):
                status.task.file = command.file
            if args.machine and isinstance(command, emc.EMC_TASK_SET_STATE):
                status.task.state = command.state
                status.io.aux.estop = command.state == STATE_ESTOP
                status.motion.traj.enabled = command.state == STATE_ON
            if text is not None and text == args.fail:
                errors.write(emc.EMC_OPERATOR_ERROR(error=f"failed: {text}"))
                status.status = RCS_STATUS.ERROR
            else:
                status.status = RCS_STATUS.DONE
            status_buffer.write(status)


if __name__ == "__main__":
    sys.exit(main())
