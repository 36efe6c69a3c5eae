"""``cnc demo``: two OS processes talking NML, the RCS way, over configs/common/cnc.nml.

The launcher-like parent is master of the buffers. A motion-like child reads EMC_TRAJ_*
commands from ``motCommand`` and publishes EMC_MOTION_STAT on ``motStatus``, echoing each
command's serial number with EXEC, then DONE once the move has "finished". A task-like child
sends moves and waits for each DONE. The parent prints what happened and removes every
buffer at the end.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

from nml import emc
from nml.channels import MOTION_COMMAND, MOTION_STATUS, Nml, load_config
from nml.ipcnames import INSTANCE_ENV
from nml.message import RCS_STATUS


def motion_child(moves: int) -> int:
    """Answer ``moves`` commands, each taking two status updates to complete."""
    with Nml(load_config(), "motion", [MOTION_COMMAND, MOTION_STATUS]) as nml:
        commands, status = nml[MOTION_COMMAND], nml[MOTION_STATUS]
        stat = emc.EMC_MOTION_STAT()
        for _ in range(moves):
            cmd = commands.blocking_read(10)
            if cmd is None:
                return 1
            stat.command_type, stat.echo_serial_number = cmd.TYPE, cmd.serial_number
            stat.status = RCS_STATUS.EXEC
            status.write(stat, timeout=1.0)  # motion's P lines never wait; the demo may
            if isinstance(cmd, emc.EMC_TRAJ_LINEAR_MOVE):
                stat.traj.position = cmd.end
            stat.status = RCS_STATUS.DONE
            status.write(stat, timeout=1.0)
    return 0


def task_child(moves: int) -> int:
    """Send moves; for each, wait until status echoes its serial number with DONE."""
    with Nml(load_config(), "emc", [MOTION_COMMAND, MOTION_STATUS]) as nml:
        commands, status = nml[MOTION_COMMAND], nml[MOTION_STATUS]
        round_trips = []
        for index in range(moves):
            move = emc.EMC_TRAJ_LINEAR_MOVE(type=emc.EMC_MOTION_TYPE.FEED, vel=10.0)
            move.end.tran.x = float(index)
            start = time.perf_counter()
            serial = commands.write(move, timeout=1.0)
            while True:
                stat = status.blocking_read(5)
                if stat is None:
                    print(f"task: no status for command {serial}", file=sys.stderr)
                    return 1
                if stat.echo_serial_number == serial and stat.status == RCS_STATUS.DONE:
                    break
            round_trips.append((time.perf_counter() - start) * 1e6)
            if index < 3 or index == moves - 1:
                print(
                    f"task: move {index} serial {serial} DONE, "
                    f"motion now at X{stat.traj.position.tran.x:g}"
                )
        print(
            f"task: {moves} commands acknowledged; round trip median "
            f"{statistics.median(round_trips):.0f} us, max {max(round_trips):.0f} us"
        )
    return 0


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="cnc demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--moves", type=int, default=1000)
    parser.add_argument("--role", choices=["motion", "task"], help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role == "motion":
        return motion_child(args.moves)
    if args.role == "task":
        return task_child(args.moves)
    os.environ.setdefault(INSTANCE_ENV, f"demo{os.getpid()}")
    config = load_config()
    with Nml(config, "cnc", [MOTION_COMMAND, MOTION_STATUS]):
        print(f"demo: buffers {MOTION_COMMAND} and {MOTION_STATUS} created from {config.path}")
        child = [sys.executable, "-m", "cnc", "demo", "--moves", str(args.moves), "--role"]
        motion = subprocess.Popen([*child, "motion"])
        task = subprocess.Popen([*child, "task"])
        status = task.wait(60) or motion.wait(10)
        for proc in (task, motion):
            if proc.poll() is None:
                proc.kill()
    print("demo: buffers removed")
    return status
