"""Kinematics loaded by ``loadrt`` into the realtime host and used by motmod (issue 17):
a 5-axis table-rotary-tilting machine (xyzac-trt-kins) keeps the tool on the programmed
point while its tables turn (tool-centre-point), switches kinematics through
``motion.switchkins-type``, and a bare ``loadrt trivkins`` makes an XYZ machine of
``motmod num_joints=3``. The test plays task (NML commands) and the drives (the joints'
commands looped back as feedback), running motion's functions period by period.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from hal.core import Hal
from hal.rtapi_app import Host
from nml import emc
from nml.channels import MOTION_COMMAND
from tests.motion.test_motmod import Task

PERIOD_NS = 1_000_000
Y_OFFSET, Z_OFFSET, TOOL = 20.0, 10.0, 35.0


class Machine:
    def __init__(self, hal: Hal, host: Host, task: Task) -> None:
        self.hal, self.host, self.task = hal, host, task
        self.motmod = host.motmod

    def command(self, cmd: emc.NMLmsg) -> None:
        self.task.task[MOTION_COMMAND].write(cmd)
        self.motmod.command_handler(PERIOD_NS)
        self.period()

    def period(self) -> None:
        for joint in self.motmod.joints:  # perfect drives
            joint.motor_pos_fb = joint.motor_pos_cmd
        self.motmod.controller_period(PERIOD_NS)

    def joints(self) -> list[float]:
        return [joint.motor_pos_cmd for joint in self.motmod.joints]

    def pin(self, name: str) -> Any:
        return self.hal.pin_value(self.hal.find_pin(name)[1])


@pytest.fixture
def machine(request) -> Iterator[Machine]:
    kins, num_joints = request.param
    task = Task()  # (the NML buffers' master)
    hal = Hal()
    host = Host(hal, is_rt=False)
    try:
        host.loadrt(kins[0], kins[1:])
        host.loadrt("motmod", [f"servo_period_nsec={PERIOD_NS}", f"num_joints={num_joints}"])
        host.stop_thread("servo-thread")  # the test runs motion's functions itself
        yield Machine(hal, host, task)
    finally:
        host.unload_all()
        hal.destroy()
        task.close()


def home_and_coordinate(m: Machine, joints: int, limits: dict[int, float]) -> None:
    for joint in range(joints):
        limit = limits.get(joint, 500.0)
        for cmd in (
            emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=joint, limit=-limit),
            emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=joint, limit=limit),
            emc.EMC_JOINT_SET_MAX_VELOCITY(joint=joint, vel=100.0),
            emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=joint, acc=1000.0),
            emc.EMC_JOINT_SET_HOMING_PARAMS(joint=joint, home_sequence=0),
        ):
            m.command(cmd)
    for axis in range(9):
        for cmd in (
            emc.EMC_AXIS_SET_MAX_VELOCITY(axis=axis, vel=100.0),
            emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=axis, acc=1000.0),
            emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=axis, limit=-500.0),
            emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=axis, limit=500.0),
        ):
            m.command(cmd)
    m.command(emc.EMC_TRAJ_ENABLE())
    m.command(emc.EMC_JOINT_HOME(joint=-1))
    for _ in range(10_000):
        m.period()
        if all(j.is_homed for j in m.motmod.controller.joints):
            break
    else:
        raise AssertionError("the joints did not home")
    m.command(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD))
    assert m.pin("motion.coord-mode") == 1


def move(m: Machine, **end: float) -> list[list[float]]:
    """A feed move to ``end`` (axis letters); the joint commands of every period."""
    cmd = emc.EMC_TRAJ_LINEAR_MOVE(
        type=emc.EMC_MOTION_TYPE.FEED, vel=50.0, ini_maxvel=100.0, acc=1000.0
    )
    pose = m.motmod.controller.carte_pos_cmd
    cmd.end.tran.x, cmd.end.tran.y, cmd.end.tran.z = pose.x, pose.y, pose.z
    cmd.end.a, cmd.end.b, cmd.end.c = pose.a, pose.b, pose.c
    for letter, value in end.items():
        if letter in "xyz":
            setattr(cmd.end.tran, letter, value)
        else:
            setattr(cmd.end, letter, value)
    m.command(cmd)
    path = []
    for _ in range(20_000):
        m.period()
        path.append(m.joints())
        if m.motmod.controller.tp.is_done and len(path) > 2:
            break
    else:
        raise AssertionError("the move did not end")
    return path


def table_joints(x: float, y: float, z: float, a: float, c: float) -> np.ndarray:
    """Where an A-tilting table carrying a C rotary table puts work point (x, y, z) (the
    rotation point at the origin; tilt axis Y_OFFSET, Z_OFFSET + tool length from it)."""
    ca, sa = math.cos(math.radians(a)), math.sin(math.radians(a))
    cc, sc = math.cos(math.radians(c)), math.sin(math.radians(c))
    turned = np.array([cc * x - sc * y, sc * x + cc * y, z])
    d = np.array([0.0, Y_OFFSET, Z_OFFSET + TOOL])
    tilt = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    return tilt @ (turned - d) + d


@pytest.mark.parametrize("machine", [(["xyzac-trt-kins"], 5)], indirect=True)
def test_five_axis_table_machine_keeps_the_tool_on_the_point(machine: Machine) -> None:
    m = machine
    trt = m.host.kinematics.types[0].pins  # the pins loadrt made: xyzac-trt-kins.*
    assert m.hal.find_pin("xyzac-trt-kins.y-offset") is not None
    trt.y_offset, trt.z_offset, trt.tool_offset = Y_OFFSET, Z_OFFSET, TOOL
    assert m.pin("xyzac-trt-kins.tool-offset") == TOOL
    home_and_coordinate(m, 5, {3: 90.0, 4: 3600.0})
    move(m, x=10.0, y=5.0, z=-20.0)
    path = move(m, c=90.0)  # turn the rotary table a quarter: the joints must follow
    kins = m.motmod.controller.kins
    for joints in path[:: len(path) // 20]:
        tip = kins.forward(joints)
        assert (tip.x, tip.y, tip.z) == pytest.approx((10.0, 5.0, -20.0), abs=1e-6)
    assert path[-1] == pytest.approx([*table_joints(10, 5, -20, 0, 90), 0, 90], abs=1e-6)
    path = move(m, a=-30.0)  # tilt
    assert path[-1] == pytest.approx([*table_joints(10, 5, -20, -30, 90), -30, 90], abs=1e-6)
    assert m.motmod.controller.carte_pos_cmd.a == pytest.approx(-30.0)


@pytest.mark.parametrize("machine", [(["xyzac-trt-kins"], 5)], indirect=True)
def test_switchkins_type_pin_switches_to_identity(machine: Machine) -> None:
    m = machine
    trt = m.host.kinematics.types[0].pins
    trt.y_offset, trt.z_offset, trt.tool_offset = Y_OFFSET, Z_OFFSET, TOOL
    home_and_coordinate(m, 5, {3: 90.0, 4: 3600.0})
    move(m, x=10.0, a=-30.0)
    joints = m.joints()
    assert m.pin("kinstype.is-0") and not m.pin("kinstype.is-1")
    m.motmod.switch_pins.switchkins_type = 1.0  # as M429 does through motion.analog-out
    m.period()
    assert m.pin("kinstype.is-1") and not m.pin("kinstype.is-0")
    assert m.joints() == pytest.approx(joints)  # switching moves nothing...
    pose = m.motmod.controller.carte_pos_cmd  # ...the world position is the joints' now
    assert pose.as_tuple()[:6] == pytest.approx([*joints[:4], 0.0, joints[4]])
    move(m, x=pose.x + 5.0)
    assert m.joints()[0] == pytest.approx(joints[0] + 5.0)  # identity: X moves joint 0 only
    assert m.joints()[1:] == pytest.approx(joints[1:])


@pytest.mark.parametrize("machine", [(["trivkins"], 3)], indirect=True)
def test_bare_trivkins_makes_an_xyz_machine_of_three_joints(machine: Machine) -> None:
    m = machine
    assert m.host.kinematics.num_joints == 9  # all of XYZABCUVW, as LinuxCNC's default
    assert m.hal.find_pin("joint.2.motor-pos-cmd") is not None
    assert m.hal.find_pin("joint.3.motor-pos-cmd") is None
    assert m.hal.find_pin("axis.z.pos-cmd") is not None
    assert m.hal.find_pin("axis.a.pos-cmd") is not None  # all nine, idle (as LinuxCNC 2.9)
    home_and_coordinate(m, 3, {})
    move(m, x=3.0, y=-4.0, z=5.0)
    assert m.joints() == pytest.approx([3.0, -4.0, 5.0])
