"""EMC_MOTION_STAT fields with LinuxCNC's meanings (MOT-001, MOT-066..071): dtg,
distance_to_go, current_vel, activeQueue, motion_type and the spindle status."""

from __future__ import annotations

import math

import pytest

from motion.controller import FREE, OrientState
from motion.status import FieldRun
from nml import emc
from tests.motion.test_controller import enabled_homed, move, run


def status(motion) -> emc.EMC_MOTION_STAT:
    stat = emc.EMC_MOTION_STAT()
    motion.fill_status(stat)
    return stat


def xyz(pose: emc.EmcPose) -> tuple[float, float, float]:
    return pose.tran.x, pose.tran.y, pose.tran.z


def test_dtg_is_what_is_left_of_the_current_move_per_axis() -> None:
    motion = enabled_homed()
    assert motion.handle(move(10.0, 5.0)) is None
    run(motion, 100)
    traj = status(motion).traj
    here = motion.carte_pos_cmd
    assert xyz(traj.dtg) == pytest.approx((10.0 - here.x, 5.0 - here.y, 0.0))
    assert traj.distance_to_go == pytest.approx(math.hypot(*xyz(traj.dtg)))
    assert traj.current_vel == pytest.approx(motion.tp.vel) and traj.current_vel > 0
    assert traj.motion_type == emc.EMC_MOTION_TYPE.FEED and traj.activeQueue == 1
    run(motion, 3000)
    traj = status(motion).traj
    assert xyz(traj.dtg) == (0.0, 0.0, 0.0) and traj.distance_to_go == 0.0
    assert traj.activeQueue == 0 and traj.current_vel == 0.0 and traj.queue == 0


def test_active_queue_is_two_while_blending_into_the_next_move() -> None:
    motion = enabled_homed()
    assert motion.handle(move(10.0)) is None
    assert motion.handle(move(10.0, 10.0)) is None  # G64 corner: blended
    seen = set()
    for _ in range(3000):
        run(motion, 1)
        seen.add(status(motion).traj.activeQueue)
    assert seen == {0, 1, 2}


def test_current_vel_in_teleop_is_the_jog_speed_and_zero_in_free_mode() -> None:
    motion = enabled_homed(mode=FREE)
    jog = emc.EMC_JOG_CONT(joint_or_axis=0, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(jog) is None
    run(motion, 500)
    assert status(motion).traj.current_vel == 0.0  # free mode: no path speed
    assert motion.handle(emc.EMC_JOG_STOP(joint_or_axis=0, jjogmode=emc.JOG_MODE.JOINT)) is None
    run(motion, 500)
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.TELEOP)) is None
    for axis in (0, 1):
        axis_jog = emc.EMC_JOG_CONT(joint_or_axis=axis, vel=3.0, jjogmode=emc.JOG_MODE.TELEOP)
        assert motion.handle(axis_jog) is None
    run(motion, 500)
    assert status(motion).traj.current_vel == pytest.approx(math.hypot(3.0, 3.0))


def test_spindle_status_orient_css_and_override() -> None:
    motion = enabled_homed()
    on = emc.EMC_SPINDLE_ON(spindle=0, speed=-1500.0, factor=-2000.0, xoffset=1.0)
    assert motion.handle(on) is None
    assert motion.handle(emc.EMC_SPINDLE_INCREASE(spindle=0, speed=100.0)) is None
    spindle = status(motion).spindle[0]
    assert (spindle.speed, spindle.direction, spindle.enabled) == (-1600.0, -1, 1)
    assert (spindle.css_maximum, spindle.css_factor) == (1600.0, -2000.0)
    assert spindle.increasing == 1 and not spindle.brake and not spindle.homed
    assert motion.handle(emc.EMC_SPINDLE_ORIENT(spindle=0, orientation=45.0, mode=0)) is None
    spindle = status(motion).spindle[0]
    assert spindle.orient_state == OrientState.IN_PROGRESS and spindle.orient_fault == 0
    assert (spindle.speed, spindle.enabled, spindle.css_maximum) == (0.0, 0, 0.0)


def test_status_filled_every_period_into_one_record_follows_the_controller() -> None:
    """motmod fills the same record every period (motion/status.py keeps its field runs):
    each fill shows the state of that period, not of the first one."""
    motion = enabled_homed()
    stat = emc.EMC_MOTION_STAT()
    motion.fill_status(stat)
    assert stat.traj.inpos and stat.traj.queue == 0 and stat.traj.position.tran.x == 0.0
    assert motion.handle(move(10.0)) is None
    run(motion, 100)
    motion.fill_status(stat)
    traj = stat.traj
    assert not traj.inpos and traj.queue == 1 and traj.activeQueue == 1
    assert 0 < traj.position.tran.x == pytest.approx(motion.carte_pos_cmd.x)
    assert traj.actualPosition.tran.x == pytest.approx(motion.carte_pos_fb.x)
    assert stat.joint[0].output == pytest.approx(motion.joints[0].pos_cmd)
    assert 0 < stat.joint[0].velocity == pytest.approx(motion.joints[0].vel_cmd)
    assert list(stat.synch_do[:4]) == [0, 0, 0, 0]
    assert motion.handle(emc.EMC_MOTION_SET_DOUT(index=2, start=1, now=1)) is None
    assert motion.handle(emc.EMC_MOTION_SET_AOUT(index=0, start=2.5, now=1)) is None
    motion.fill_status(stat)
    assert list(stat.synch_do[:4]) == [0, 0, 1, 0] and stat.analog_output[0] == 2.5
    assert motion.handle(emc.EMC_MOTION_SET_DOUT(index=2, start=0, now=1)) is None
    motion.fill_status(stat)
    assert list(stat.synch_do[:4]) == [0, 0, 0, 0] and stat.analog_output[0] == 2.5


def test_fill_status_leaves_the_fields_motion_does_not_own() -> None:
    """The command handler's echo, task's units and the soft-limit flags are not motion's
    per-period state: filling the status keeps them."""
    motion = enabled_homed()
    stat = emc.EMC_MOTION_STAT()
    stat.echo_serial_number, stat.status = 41, 1
    stat.traj.linearUnits, stat.traj.probeval = 25.4, 1
    stat.joint[1].minSoftLimit = 1
    motion.fill_status(stat)
    motion.fill_status(stat)
    assert (stat.echo_serial_number, stat.status) == (41, 1)
    assert (stat.traj.linearUnits, stat.traj.probeval) == (25.4, 1)
    assert stat.joint[1].minSoftLimit == 1 and stat.joint[1].homed
    assert stat.traj.joints == 3 and stat.traj.cycleTime == motion.period_s


def test_a_field_run_is_consecutive_fields_only() -> None:
    with pytest.raises(ValueError, match="not consecutive"):
        FieldRun(emc.EMC_MOTION_STAT().byte_view(), 0, emc.EMC_TRAJ_STAT.dtype, ("mode", "id"))


def test_unset_traj_limits_read_as_linuxcnc_unlimited() -> None:
    """[TRAJ]MAX_LINEAR_VELOCITY/ACCELERATION absent: LinuxCNC reports 1e99 (its test
    helper waits for both to be non-zero before it trusts the status)."""
    motion = enabled_homed()
    motion.max_vel = motion.max_acc = math.inf
    traj = status(motion).traj
    assert (traj.maxVelocity, traj.maxAcceleration) == (1e99, 1e99)
    motion.max_vel, motion.max_acc = 25.0, 300.0
    traj = status(motion).traj
    assert (traj.maxVelocity, traj.maxAcceleration) == (25.0, 300.0)


def test_at_start_the_joints_motion_lacks_and_the_feed_read_as_in_linuxcnc() -> None:
    """LinuxCNC's tests/startup-state: joints beyond the machine's keep EMC_JOINT_STAT's
    start values, and no feed velocity or acceleration is set yet."""
    from tests.motion.test_controller import make

    stat = status(make(num_joints=3))
    for index in range(3, len(stat.joint)):
        joint = stat.joint[index]
        assert (joint.jointType, joint.units) == (emc.EmcJointType.LINEAR, 1.0)
        assert (joint.minPositionLimit, joint.maxPositionLimit) == (-1.0, 1.0)
        assert (joint.minFerror, joint.maxFerror, joint.inpos) == (1.0, 1.0, 1)
    assert stat.joint[2].maxPositionLimit == 100.0  # a joint motion has: its own
    assert (stat.traj.velocity, stat.traj.acceleration) == (0.0, 0.0)
