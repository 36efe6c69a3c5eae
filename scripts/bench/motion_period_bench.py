#!/usr/bin/env python3
"""Motion's servo-period cost, in one process: motmod loaded into a realtime host object
(no thread), its two functions called period after period on the limits of LinuxCNC's sim
``axis_mm.ini``, commands through the real NML motion command buffer.

Prints JSON: motion's CPU time per period (this thread's, µs) idle in coordinated mode,
then per program while moves stream in the way task sends them (as many commands in flight
as task allows, none while motion reports its queue full): the whole period, the command
handler (move intake) and the controller, the most commands one period took, and the mean
period (what a program costs on average: moves arrive in bursts, so most periods take none
and the median is mostly the controller's).

Unlike ``motion_bench.py`` (the whole machine, servo thread lateness), nothing else runs:
the figures are motion's own work, steady enough to compare two versions of it.

    .venv/bin/python scripts/bench/motion_period_bench.py [--programs bigprog_50k ...]
                     [--moves N] [--idle-periods N]
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import tp_bench  # (the programs' reader and the axis_mm limits)

from hal.core import Hal
from hal.rtapi_app import Host
from motion.controller import QUEUE_FULL_MARGIN
from nml import emc
from nml.channels import EMC_ERROR, MOTION_COMMAND, MOTION_STATUS, Nml, load_config
from task.controller import MAX_MOTION_IN_FLIGHT

PERIOD_NS = 1_000_000
COORD = emc.EMC_TRAJ_MODE_ENUM.COORD


def percentiles(values: list[float]) -> dict[str, float]:
    ordered = sorted(values)

    def at(fraction: float) -> float:
        return round(ordered[min(len(ordered) - 1, int(fraction * len(ordered)))], 1)

    return {"p50": at(0.5), "p99": at(0.99), "p999": at(0.999), "max": round(ordered[-1], 1)}


class Bench:
    def __init__(self) -> None:
        config = load_config()
        self.master = Nml(config, "cnc", [MOTION_COMMAND, MOTION_STATUS, EMC_ERROR])
        self.task = Nml(config, "emc", [MOTION_COMMAND, MOTION_STATUS])
        self.hal = Hal()
        self.host = Host(self.hal, is_rt=False)
        self.host.loadrt("trivkins", ["coordinates=XYZ"])
        self.host.loadrt("motmod", [f"servo_period_nsec={PERIOD_NS}", "num_joints=3"])
        self.motmod = self.host.motmod
        # motmod creates servo-thread, as LinuxCNC's does; here this process calls motion's
        # functions itself, and an idle thread waking every period would take the GIL from
        # it (whenever numpy or a semaphore releases it) and count in its figures
        self.host.stop_thread("servo-thread")
        self.commands = self.task[MOTION_COMMAND]

    def close(self) -> None:
        self.host.unload_all()
        self.task.close()
        self.master.close()
        self.hal.destroy()

    def period(self) -> None:
        self.motmod.command_handler(PERIOD_NS)
        self.motmod.controller_period(PERIOD_NS)

    def send(self, cmd: emc.NMLmsg) -> None:
        self.commands.write(cmd)
        self.period()
        if self.motmod.pending_errors:
            raise RuntimeError(f"{cmd.NAME}: {self.motmod.pending_errors}")

    def machine_ready(self) -> None:
        """axis_mm's limits, motion on, homed, coordinated mode."""
        for index in range(3):
            for cmd in (
                emc.EMC_JOINT_SET_MAX_VELOCITY(joint=index, vel=tp_bench.AXIS_VEL),
                emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=index, acc=tp_bench.AXIS_ACC),
                emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=index, limit=-1000.0),
                emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=index, limit=1000.0),
                emc.EMC_AXIS_SET_MAX_VELOCITY(axis=index, vel=tp_bench.AXIS_VEL),
                emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=index, acc=tp_bench.AXIS_ACC),
                emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=index, limit=-1000.0),
                emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=index, limit=1000.0),
            ):
                self.send(cmd)
        self.send(emc.EMC_TRAJ_SET_MAX_VELOCITY(velocity=tp_bench.TRAJ_VEL))
        self.send(emc.EMC_TRAJ_ENABLE())
        controller = self.motmod.controller
        for index, joint in enumerate(controller.joints):
            while not joint.is_homed:  # (each at once: no home switch, search velocity 0)
                self.send(emc.EMC_JOINT_HOME(joint=index))
                for _ in range(50):
                    self.period()
        self.send(emc.EMC_TRAJ_SET_MODE(mode=COORD))
        start = emc.EMC_TRAJ_LINEAR_MOVE(type=emc.EMC_MOTION_TYPE.TRAVERSE, id=1)
        start.vel, start.ini_maxvel, start.acc = tp_bench.TRAJ_VEL, tp_bench.TRAJ_VEL, 500.0
        start.end.tran.x, start.end.tran.y, start.end.tran.z = tp_bench.START
        self.send(start)
        while not controller.tp.is_done:
            self.period()

    def idle(self, periods: int) -> dict[str, float]:
        clock = time.thread_time_ns
        spent = []
        for _ in range(periods):
            before = clock()
            self.period()
            spent.append((clock() - before) / 1e3)
        return percentiles(spent)

    def program(self, name: str, limit: int) -> dict:
        moves = tp_bench.read_program(tp_bench.PROGRAMS / f"{name}.ngc")[:limit]
        messages = [_message(move, line) for line, move in enumerate(moves, start=2)]
        clock = time.thread_time_ns
        motmod, controller = self.motmod, self.motmod.controller
        whole, intake, most = [], [], 0
        sent = written = 0
        while sent < len(messages) or not controller.tp.is_done:
            answered = motmod.status.echo_serial_number
            in_flight = written - answered if sent else 0
            if controller.tp.free_slots >= QUEUE_FULL_MARGIN:  # task's view: not full
                while sent < len(messages) and in_flight < MAX_MOTION_IN_FLIGHT:
                    written = self.commands.write(messages[sent])
                    sent += 1
                    in_flight += 1
            start = clock()
            motmod.command_handler(PERIOD_NS)
            taken = clock()
            motmod.controller_period(PERIOD_NS)
            end = clock()
            whole.append((end - start) / 1e3)
            intake.append((taken - start) / 1e3)
            most = max(most, motmod.status.echo_serial_number - answered)
        if motmod.pending_errors:
            raise RuntimeError(f"{name}: {motmod.pending_errors[:3]}")
        return {
            "moves": len(messages),
            "periods": len(whole),
            "period_us": percentiles(whole),
            "mean_period_us": round(sum(whole) / len(whole), 1),
            "intake_us": percentiles(intake),
            "controller_us": percentiles([w - i for w, i in zip(whole, intake, strict=True)]),
            "most_commands_in_a_period": most,
        }


def _message(move: dict, line: int) -> emc.NMLmsg:
    vel, maxvel, acc = move["vel"], tp_bench.TRAJ_VEL, tp_bench.AXIS_ACC
    if "centre" in move:
        msg = emc.EMC_TRAJ_CIRCULAR_MOVE(type=emc.EMC_MOTION_TYPE.ARC, turn=move["turns"])
        msg.center.x, msg.center.y, msg.center.z = move["centre"]
        msg.normal.x, msg.normal.y, msg.normal.z = move["normal"]
    else:
        kind = emc.EMC_MOTION_TYPE.TRAVERSE if move["rapid"] else emc.EMC_MOTION_TYPE.FEED
        msg = emc.EMC_TRAJ_LINEAR_MOVE(type=kind)
    msg.vel, msg.ini_maxvel, msg.acc, msg.id = vel, maxvel, acc, line
    msg.end.tran.x, msg.end.tran.y, msg.end.tran.z = move["end"]
    return msg


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--programs", nargs="+", default=["bigprog_50k", "circle_g64"])
    parser.add_argument("--moves", type=int, default=10_000, help="first N moves of each")
    parser.add_argument("--idle-periods", type=int, default=5000)
    args = parser.parse_args()
    os.environ.setdefault("CNC_INSTANCE", f"motion-period-bench-{os.getpid()}")
    bench = Bench()
    gc.disable()  # as in the realtime host
    try:
        bench.machine_ready()
        report = {
            "idle_coord_us": bench.idle(args.idle_periods),
            "programs": {name: bench.program(name, args.moves) for name in args.programs},
        }
    finally:
        bench.close()
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
