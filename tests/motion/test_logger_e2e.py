"""motion-logger in a whole machine, as LinuxCNC's tests/motion-logger use it: ``cnc run``
of tests/motion/logger_machine (its HAL file loads ``motion-logger out.motion-logger`` in
place of motmod), driven through ``import cnc``; the log holds what task told motion, in
LinuxCNC's emcmot words, and task went on as if motion had done it all."""

from __future__ import annotations

import shutil
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import cnc
from hal.core import Hal
from tests.task.test_machine import Machine, launched

MACHINE = Path(__file__).with_name("logger_machine")
LOG = "out.motion-logger"
JOG_ABORTS = [f"JOG_ABORT joint={n}" for n in range(16)]
MOTION_ABORT = [*JOG_ABORTS, "ABORT"]  # LinuxCNC's emcMotionAbort


def joint_lines(joint: int, low: float, high: float, vel: float, acc: float, volatile: int):
    return [
        f"SET_JOINT_BACKLASH joint={joint}, backlash=0",
        f"SET_JOINT_POSITION_LIMITS joint={joint}, min={low:g}, max=0",
        f"SET_JOINT_POSITION_LIMITS joint={joint}, min={low:g}, max={high:g}",
        f"SET_JOINT_MAX_FERROR joint={joint}, maxFerror=1",
        f"SET_JOINT_MIN_FERROR joint={joint}, minFerror=0.5",
        f"SET_JOINT_HOMING_PARAMS joint={joint}, offset=0 home=0, final_vel=-1, search_vel=0, "
        f"latch_vel=0, flags=0x00000000, sequence={0 if joint == 2 else 999}, "
        f"volatile={volatile}",
        f"SET_JOINT_VEL_LIMIT joint={joint}, vel={vel:g}",
        f"SET_JOINT_ACC_LIMIT joint={joint}, acc={acc:g}",
        f"JOINT_ACTIVATE joint={joint}",
    ]


def axis_lines(axis: int, low: float, high: float, vel: float, acc: float) -> list[str]:
    # (a limit of 0 set second leaves the line as it was: LinuxCNC's task sends it all the same)
    return [
        f"SET_AXIS_POSITION_LIMITS axis={axis}, min={low:g}, max=0",
        f"SET_AXIS_POSITION_LIMITS axis={axis}, min={low:g}, max={high:g}",
        f"SET_AXIS_VEL_LIMIT axis={axis} vel={vel:g}",
        f"SET_AXIS_ACC_LIMIT axis={axis}, acc={acc:g}",
        f"SET_AXIS_LOCKING_JOINT axis={axis}, locking_joint=-1",
    ]


# What LinuxCNC's task sends its motion for this machine from start-up to Auto mode.
START_UP = [
    "SET_NUM_JOINTS 3",
    "SET_NUM_SPINDLES 1",
    "SET_VEL vel=0, ini_maxvel=20",
    "SET_VEL_LIMIT vel=50",
    "SET_ACC acc=1e+99",
    "SETUP_ARC_BLENDS",
    "SET_MAX_FEED_OVERRIDE 1",
    "SETUP_SET_PROBE_ERR_INHIBIT 0 0",
    "SET_WORLD_HOME x=0, y=0, z=0, a=0, b=0, c=0, u=0, v=0, w=0",
    *joint_lines(0, -100, 100, 50, 1000, volatile=1),
    *joint_lines(1, -100, 100, 50, 1000, volatile=0),
    *joint_lines(2, -50, 0, 25, 500, volatile=0),
    *axis_lines(0, -100, 100, 50, 1000),
    *axis_lines(1, -100, 100, 50, 1000),
    *axis_lines(2, -50, 0, 25, 500),
    "SET_SPINDLE_PARAMS, 1.00e+99, 0.00e+00, -1.00e+99, 0.00e+00",
    # task starts in E-stop
    *MOTION_ABORT,
    "SPINDLE_OFF",
    *["DISABLE_AMPLIFIER"] * 3,
    "DISABLE",
    "JOINT_UNHOME joint=-2",
    "FREE",
    # E-stop reset
    *MOTION_ABORT,
    "SPINDLE_OFF",
    # machine on
    "ENABLE",
    *["ENABLE_AMPLIFIER"] * 3,
    # Auto mode: coordinated, and what ran in the other mode aborted
    "COORD",
    *MOTION_ABORT,
]


@pytest.fixture
def machine(procs, tmp_path: Path) -> Iterator[Machine]:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    with launched(procs, folder) as machine:
        yield machine


def logged_lines(machine: Machine) -> list[str]:
    """The log so far, then a fresh one (as LinuxCNC's tests rotate it: the reopen-log
    pin set, cleared by the logger once it closed the file, the file renamed)."""
    hal = Hal(is_creating=False)  # (this machine's: each test has its own instance)
    try:
        found = hal.find_pin("motion-logger.reopen-log")
        assert found is not None
        pin = found[1]
        hal.write_slot(pin["type"], pin["slot"], 1)
        deadline = time.monotonic() + 10
        while hal.pin_value(pin):
            assert time.monotonic() < deadline, "motion-logger did not close its log"
            time.sleep(0.01)
    finally:
        hal.close()
    log = machine.folder / LOG
    taken = log.with_suffix(".taken")
    log.rename(taken)
    return taken.read_text().splitlines()


def test_the_log_says_what_task_told_motion_as_linuxcncs_motion_logger(
    machine: Machine,
) -> None:
    c = machine.command
    for state in (cnc.STATE_ESTOP_RESET, cnc.STATE_ON):
        c.state(state)
        assert c.wait_complete() == cnc.RCS_DONE
    c.mode(cnc.MODE_AUTO)
    assert c.wait_complete() == cnc.RCS_DONE
    assert logged_lines(machine) == START_UP

    c.program_open(str(machine.folder / "part.ngc"))
    c.auto(cnc.AUTO_RUN, 0)
    assert c.wait_complete() == cnc.RCS_DONE  # the program has ended: motion did it all
    machine.stat.poll()
    assert machine.stat.interp_state == cnc.INTERP_IDLE and machine.stat.inpos
    assert logged_lines(machine) == [
        "SET_LINE x=1, y=0, z=0, a=0, b=0, c=0, u=0, v=0, w=0, id=2, motion_type=1, "
        "vel=50, ini_maxvel=50, acc=1000, turn=-1",
        "SET_LINE x=3, y=0, z=0, a=0, b=0, c=0, u=0, v=0, w=0, id=3, motion_type=2, "
        "vel=10, ini_maxvel=50, acc=1000, turn=-1",
        # M2
        "SET_SPINDLESYNC sync=0.000000, flags=0x00000000",
        "SPINDLE_OFF",
    ]

    c.state(cnc.STATE_ESTOP)
    assert c.wait_complete() == cnc.RCS_DONE
    machine.stop()  # what task sends while the machine shuts down is not logged
    assert (machine.folder / LOG).read_text().splitlines() == [
        *MOTION_ABORT,
        "SPINDLE_OFF",
        *["DISABLE_AMPLIFIER"] * 3,
        "DISABLE",
        "JOINT_UNHOME joint=-2",  # joint 0 is VOLATILE_HOME
    ]
