"""stat(): LinuxCNC's attributes, read from an EMC_STAT written to emcStatus."""

from __future__ import annotations

import pytest

import cnc
from iocontrol.tooldata import ToolDataWriter
from iocontrol.tooltable import ToolEntry, ToolTable
from nml import emc
from nml.channels import EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from nml.message import RCS_STATUS


def sample_status() -> emc.EMC_STAT:
    status = emc.EMC_STAT(echo_serial_number=41, status=RCS_STATUS.EXEC, debug=0x100)
    task = status.task
    task.mode, task.state = cnc.MODE_AUTO, cnc.STATE_ON
    task.execState, task.interpState = cnc.EXEC_WAITING_FOR_MOTION, cnc.INTERP_READING
    task.callLevel, task.motionLine, task.currentLine, task.readLine = 2, 10, 11, 12
    task.file, task.command, task.ini_filename = "/tmp/part.ngc", "G0 X1", "/tmp/mill.ini"
    task.optional_stop_state, task.block_delete_state = True, False
    task.g5x_index, task.rotation_xy = 2, 30.0
    task.g5x_offset.tran.x, task.g5x_offset.w = 1.5, -2.0
    task.g92_offset.tran.y = 3.0
    task.toolOffset.tran.z = 12.5
    task.activeGCodes[:3] = [10, 170, 400]
    task.activeMCodes[:2] = [0, 5]
    task.activeSettings[:] = [11.0, 500.0, 1200.0, 0.01, 0.0]
    task.programUnits, task.delayLeft, task.queuedMDIcommands = 2, 0.5, 3
    traj = status.motion.traj
    traj.linearUnits, traj.angularUnits, traj.cycleTime = 1.0, 1.0, 0.001
    traj.joints, traj.spindles, traj.axis_mask = 3, 1, 0b111
    traj.mode, traj.enabled, traj.inpos, traj.queue = cnc.TRAJ_MODE_COORD, True, False, 4
    traj.scale, traj.rapid_scale, traj.maxVelocity = 0.5, 0.25, 100.0
    traj.position.tran.x, traj.position.tran.y, traj.position.tran.z = 1.0, 2.0, 3.0
    traj.position.c = 90.0
    traj.actualPosition.tran.x = 0.999
    traj.probe_tripped, traj.probeval = True, 1
    traj.probedPosition.tran.z = -4.0
    traj.kinematics_type, traj.motion_type = cnc.KINEMATICS_IDENTITY, cnc.MOTION_TYPE_FEED
    traj.distance_to_go, traj.dtg.tran.x, traj.current_vel = 7.0, 6.0, 10.0
    traj.feed_override_enabled = True
    for number, joint in enumerate(status.motion.joint[:3]):
        joint.output, joint.input = 10.0 * number, 10.0 * number - 0.001
        joint.homed, joint.enabled, joint.jointType = 1, 1, 1
        joint.minPositionLimit, joint.maxPositionLimit = -100.0, 100.0 + number
    status.motion.joint[1].maxHardLimit = 1
    status.motion.joint[2].minSoftLimit = 1
    status.motion.axis[2].maxPositionLimit = 0.0
    status.motion.axis[2].minPositionLimit = -50.0
    spindle = status.motion.spindle[0]
    spindle.speed, spindle.direction, spindle.enabled, spindle.spindle_scale = 1000.0, 1, 1, 1.1
    spindle.spindle_override_enabled = True
    status.motion.synch_di[3] = 1
    status.motion.analog_output[1] = 2.5
    status.io.tool.toolInSpindle, status.io.tool.pocketPrepped = 5, 2
    status.io.tool.toolFromPocket = 3
    status.io.coolant.flood, status.io.lube.on, status.io.lube.level = 1, 1, 1
    status.io.aux.estop = 0
    return status


@pytest.fixture
def polled(controller: Nml) -> cnc.stat:
    controller[EMC_STATUS].write(sample_status())
    s = cnc.stat()
    s.poll()
    return s


def test_poll_before_the_controller_is_up_raises_cnc_error() -> None:
    s = cnc.stat()
    with pytest.raises(cnc.error, match="not running"):
        s.poll()
    assert s.task_state == 0  # attributes are zero until a poll succeeds, as in LinuxCNC


def test_a_stat_made_before_the_controller_starts_attaches_at_the_next_poll() -> None:
    s = cnc.stat()
    with pytest.raises(cnc.error):
        s.poll()
    with Nml(load_config(), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
        nml[EMC_STATUS].write(sample_status())
        s.poll()
        assert s.echo_serial_number == 41
        s.close()


def test_plain_attributes(polled: cnc.stat) -> None:
    s = polled
    assert (s.echo_serial_number, s.state, s.debug) == (41, cnc.RCS_EXEC, 0x100)
    assert (s.task_mode, s.task_state) == (cnc.MODE_AUTO, cnc.STATE_ON)
    assert (s.exec_state, s.interp_state) == (cnc.EXEC_WAITING_FOR_MOTION, cnc.INTERP_READING)
    assert (s.call_level, s.motion_line, s.current_line, s.read_line) == (2, 10, 11, 12)
    assert (s.file, s.command, s.ini_filename) == ("/tmp/part.ngc", "G0 X1", "/tmp/mill.ini")
    assert s.optional_stop is True and s.block_delete is False
    assert (s.program_units, s.delay_left, s.queued_mdi_commands) == (2, 0.5, 3)
    assert (s.joints, s.spindles, s.axis_mask, s.cycle_time) == (3, 1, 7, 0.001)
    assert (s.motion_mode, s.enabled, s.inpos, s.queue) == (cnc.TRAJ_MODE_COORD, True, False, 4)
    assert (s.feedrate, s.rapidrate, s.max_velocity) == (0.5, 0.25, 100.0)
    assert (s.probe_tripped, s.probe_val) == (True, 1)
    assert (s.kinematics_type, s.motion_type) == (cnc.KINEMATICS_IDENTITY, cnc.MOTION_TYPE_FEED)
    assert (s.distance_to_go, s.current_vel, s.feed_override_enabled) == (7.0, 10.0, True)
    assert (s.tool_in_spindle, s.pocket_prepped, s.tool_from_pocket) == (5, 2, 3)
    assert (s.flood, s.mist, s.lube, s.lube_level, s.estop) == (1, 0, 1, 1, 0)
    assert (s.g5x_index, s.rotation_xy) == (2, 30.0)


def test_poses_and_arrays(polled: cnc.stat) -> None:
    s = polled
    assert s.position == (1.0, 2.0, 3.0, 0.0, 0.0, 90.0, 0.0, 0.0, 0.0)
    assert s.actual_position[0] == 0.999 and len(s.actual_position) == 9
    assert s.g5x_offset == (1.5, 0, 0, 0, 0, 0, 0, 0, -2.0)
    assert s.g92_offset[1] == 3.0 and s.tool_offset[2] == 12.5
    assert s.probed_position[2] == -4.0 and s.dtg[0] == 6.0
    assert s.joint_position[:3] == (0.0, 10.0, 20.0) and len(s.joint_position) == 16
    assert s.joint_actual_position[1] == pytest.approx(9.999)
    assert s.homed == (1, 1, 1) + (0,) * 13
    assert s.limit[:3] == (0, 2, 4)
    assert s.gcodes[:3] == (10, 170, 400) and len(s.gcodes) == 17
    assert s.mcodes[:2] == (0, 5) and len(s.mcodes) == 10
    assert s.settings == (11.0, 500.0, 1200.0, 0.01, 0.0)
    assert s.din[3] == 1 and len(s.din) == 64 and len(s.dout) == 64
    assert s.aout[1] == 2.5 and len(s.ain) == 64


def test_joint_axis_and_spindle_dicts(polled: cnc.stat) -> None:
    s = polled
    assert len(s.joint) == 16 and len(s.axis) == 9 and len(s.spindle) == 8
    joint = s.joint[1]
    assert set(joint) == {
        "jointType", "units", "backlash", "min_position_limit", "max_position_limit",
        "max_ferror", "min_ferror", "ferror_current", "ferror_highmark", "output", "input",
        "velocity", "inpos", "homing", "homed", "fault", "enabled", "min_soft_limit",
        "max_soft_limit", "min_hard_limit", "max_hard_limit", "override_limits",
    }  # fmt: skip
    assert (joint["output"], joint["homed"], joint["max_position_limit"]) == (10.0, 1, 101.0)
    assert (joint["max_hard_limit"], joint["jointType"]) == (1, cnc.LINEAR)
    assert s.axis[2] == {"velocity": 0.0, "min_position_limit": -50.0, "max_position_limit": 0.0}
    assert s.spindle[0] == {
        "brake": 0, "direction": 1, "enabled": 1, "override_enabled": True, "speed": 1000.0,
        "override": 1.1, "homed": False, "orient_state": 0, "orient_fault": 0,
    }  # fmt: skip


def test_attributes_change_only_with_poll(controller: Nml) -> None:
    status = sample_status()
    controller[EMC_STATUS].write(status)
    s = cnc.stat()
    s.poll()
    assert s.position[0] == 1.0
    status.motion.traj.position.tran.x = 5.0
    controller[EMC_STATUS].write(status)
    assert s.position[0] == 1.0
    s.poll()
    assert s.position[0] == 5.0


def test_tool_table_comes_from_iocontrols_tool_data(polled: cnc.stat) -> None:
    assert polled.tool_table == ()  # iocontrol not running: LinuxCNC's empty table
    table = ToolTable()
    table.put(0, ToolEntry(toolno=5, pocketno=0, offset=[0, 0, 12.5] + [0] * 6, diameter=6))
    table.put(1, ToolEntry(toolno=5, pocketno=1, offset=[0, 0, 12.5] + [0] * 6, diameter=6))
    table.put(2, ToolEntry(toolno=7, pocketno=2, offset=[1, 0, 3] + [0] * 6, orientation=2))
    writer = ToolDataWriter()
    try:
        writer.publish(table)
        polled.poll()
        tools = polled.tool_table
        assert [t.id for t in tools] == [5, 5, 7]
        assert (tools[0].zoffset, tools[0].diameter) == (12.5, 6.0)
        assert tools[2] == cnc.tool(7, 1.0, 0.0, 3.0, 0, 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 2)
        assert tools[2].orientation == 2 and isinstance(tools[2].id, int)
    finally:
        polled.close()
        writer.close()


def test_dir_lists_linuxcnc_attributes(polled: cnc.stat) -> None:
    names = dir(polled)
    for name in ("poll", "task_state", "joint", "tool_table", "spindle", "homed", "settings"):
        assert name in names
    with pytest.raises(AttributeError):
        polled.no_such_attribute  # noqa: B018
