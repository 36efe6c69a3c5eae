"""External offsets, extra joints and locking indexers in the motion controller, without
HAL or processes (motion/eoffsets.py, motion/extrajoints.py, motion/indexer.py).

One machine: trivkins XYZC (joints 0..3), joint 3 a locking indexer of axis C, joint 4
an extra joint, Z with OFFSET_AV_RATIO 0.2 (as configs/sim/features.ini)."""

from __future__ import annotations

import pytest

from motion.controller import COORD, FREE, Inputs, MotionController
from motion.eoffsets import EoffsetInputs
from motion.kinematics import load_kinematics
from nml import emc

PERIOD = 0.001
Z, C = 2, 5
EXTRA, LOCKING = 4, 3


def make() -> MotionController:
    motion = MotionController(
        load_kinematics("trivkins", coordinates="XYZC"),
        5,
        PERIOD,
        num_extrajoints=1,
        unlock_joints_mask=1 << LOCKING,
    )
    motion.eoffsets.set_ratio(Z, 0.2)
    assert motion.indexers.set_axis_joint(C, LOCKING) is None
    for joint in range(5):
        for cmd in (
            emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=joint, limit=-100.0),
            emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=joint, limit=100.0),
            emc.EMC_JOINT_SET_MAX_VELOCITY(joint=joint, vel=50.0),
            emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=joint, acc=500.0),
            emc.EMC_JOINT_SET_HOMING_PARAMS(
                joint=joint, home_sequence=0, locking_indexer=joint == LOCKING
            ),
        ):
            assert motion.handle(cmd) is None
    for axis in (0, 1, Z, C):
        for cmd in (
            emc.EMC_AXIS_SET_MAX_VELOCITY(axis=axis, vel=50.0),
            emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=axis, acc=500.0),
            emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=axis, limit=-100.0),
            emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=axis, limit=100.0),
        ):
            assert motion.handle(cmd) is None
    return motion


class Hal:
    """The HAL side: a perfect servo loop, the lock of joint 3 (opens one period after
    unlock), joint 4's posthome-cmd and Z's eoffset pins."""

    def __init__(self, motion: MotionController) -> None:
        self.motion = motion
        self.posthome_cmd = 0.0
        self.z = EoffsetInputs(scale=0.01)
        self.unlock_log: list[tuple[bool, bool, float]] = []  # (unlock, unlocked, C joint)

    def run(self, periods: int) -> None:
        motion = self.motion
        lock = motion.joints[LOCKING]
        for _ in range(periods):
            fb = [j.pos_cmd + j.motor_offset for j in motion.joints]
            n = len(fb)
            lock.is_unlocked = lock.is_unlock_requested  # (a lock one period slow)
            motion.update(
                Inputs(
                    fb,
                    [False] * n,
                    [False] * n,
                    [False] * n,
                    eoffsets={Z: self.z},
                    posthome_cmd=[self.posthome_cmd],
                )
            )
            self.unlock_log.append((lock.is_unlock_requested, lock.is_unlocked, lock.pos_cmd))
            assert not motion.errors, motion.errors


@pytest.fixture
def hal() -> Hal:
    motion = make()
    hal = Hal(motion)
    assert motion.handle(emc.EMC_TRAJ_ENABLE()) is None
    assert motion.handle(emc.EMC_JOINT_HOME(joint=-1)) is None
    hal.run(2000)
    assert all(j.is_homed for j in motion.joints)
    return hal


def coord(motion: MotionController) -> None:
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=COORD)) is None


def rapid(**end: float) -> emc.EMC_TRAJ_LINEAR_MOVE:
    cmd = emc.EMC_TRAJ_LINEAR_MOVE(vel=50.0, ini_maxvel=50.0, acc=500.0, indexer_jnum=-1)
    cmd.type = emc.EMC_MOTION_TYPE.TRAVERSE
    for letter, value in end.items():
        if letter in "xyz":
            setattr(cmd.end.tran, letter, value)
        else:
            setattr(cmd.end, letter, value)
    return cmd


# ------------------------------------------------------------------ external offsets
def test_an_offset_moves_z_by_counts_times_scale_within_its_share(hal: Hal) -> None:
    motion = hal.motion
    coord(motion)
    assert motion.axis_max_vel[Z] == pytest.approx(40.0)  # the planners keep 1 - 0.2
    hal.z.is_enabled, hal.z.counts = True, 500  # 500 * 0.01 = 5 mm
    hal.run(1)
    assert motion.eoffsets.request[Z] == pytest.approx(5.0)
    speeds = []
    for _ in range(2000):
        before = motion.joints[Z].pos_cmd
        hal.run(1)
        speeds.append(abs(motion.joints[Z].pos_cmd - before) / PERIOD)
    assert motion.joints[Z].pos_cmd == pytest.approx(5.0)
    assert max(speeds) <= 10.0 + 1e-9  # 0.2 of MAX_VELOCITY 50
    assert motion.eoffsets.is_active and motion.eoffsets.offset(Z) == pytest.approx(5.0)
    # a program moves on top of it; the planner's own Z stays without the offset
    assert motion.handle(rapid(z=10.0)) is None
    hal.run(2000)
    assert motion.joints[Z].pos_cmd == pytest.approx(15.0)
    assert motion.tp.pos[Z] == pytest.approx(10.0)


def test_an_offset_is_held_at_the_soft_limit_and_flags_it(hal: Hal) -> None:
    motion = hal.motion
    coord(motion)
    assert motion.handle(rapid(z=95.0)) is None
    hal.run(2000)
    hal.z.is_enabled, hal.z.counts = True, 1000  # +10 mm: 105 > MAX_LIMIT 100
    hal.run(3000)
    assert motion.joints[Z].pos_cmd == pytest.approx(100.0)
    assert motion.eoffsets.is_limited
    assert motion.eoffsets.request[Z] == pytest.approx(10.0)  # the request stays
    hal.z.counts = 0  # back to zero offset: inside again
    hal.run(3000)
    assert motion.joints[Z].pos_cmd == pytest.approx(95.0)
    assert not motion.eoffsets.is_limited


def test_disable_holds_clear_zeroes_machine_on_keeps_the_position(hal: Hal) -> None:
    motion = hal.motion
    coord(motion)
    hal.z.is_enabled, hal.z.counts = True, 300
    hal.run(2000)
    hal.z.is_enabled = False
    hal.z.counts = 600  # ignored while disabled
    hal.run(1000)
    assert motion.joints[Z].pos_cmd == pytest.approx(3.0)
    hal.z.is_enabled, hal.z.is_clear = True, True
    hal.run(2000)
    assert motion.joints[Z].pos_cmd == pytest.approx(0.0) and not motion.eoffsets.is_active
    hal.z.is_clear = False
    hal.z.counts = 1000  # +4 mm
    hal.run(2000)
    assert motion.joints[Z].pos_cmd == pytest.approx(4.0)
    # machine off and on: nothing moves, the offset is zero again and Z stays where it is
    assert motion.handle(emc.EMC_TRAJ_DISABLE()) is None
    assert motion.handle(emc.EMC_TRAJ_ENABLE()) is None
    hal.run(100)
    assert motion.eoffsets.offset(Z) == 0.0 and motion.eoffsets.request[Z] == 0.0
    assert motion.joints[Z].pos_cmd == pytest.approx(4.0)
    assert motion.tp.pos[Z] == pytest.approx(4.0)


def test_no_offset_before_homing() -> None:
    motion = make()
    hal = Hal(motion)
    motion.handle(emc.EMC_TRAJ_ENABLE())
    hal.z.is_enabled, hal.z.counts = True, 100
    hal.run(10)
    assert motion.eoffsets.request[Z] == 0.0


# ------------------------------------------------------------------ extra joints
def test_a_homed_extra_joint_follows_posthome_cmd_within_its_limits(hal: Hal) -> None:
    motion = hal.motion
    joint = motion.joints[EXTRA]
    hal.posthome_cmd = 30.0  # a jump: followed at MAX_VELOCITY 50, never a step
    hal.run(1)
    assert 0.0 < joint.pos_cmd < 0.01
    hal.run(2000)
    assert joint.pos_cmd == pytest.approx(30.0)
    hal.posthome_cmd = 500.0  # beyond MAX_LIMIT 100: held at the limit
    hal.run(3000)
    assert joint.pos_cmd == pytest.approx(100.0)
    # coordinated moves never move it; it keeps following its pin there too
    coord(motion)
    assert motion.handle(rapid(x=10.0)) is None
    hal.posthome_cmd = 20.0
    hal.run(3000)
    assert (motion.joints[0].pos_cmd, joint.pos_cmd) == pytest.approx((10.0, 20.0))


def test_a_homed_extra_joint_cannot_be_jogged_nor_unhomed_with_motion_on(hal: Hal) -> None:
    motion = hal.motion
    # homing left motion in teleop mode (as LinuxCNC's): joint jogs need free mode
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=FREE)) is None
    jog = emc.EMC_JOG_INCR(joint_or_axis=EXTRA, incr=1.0, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert "posthome-cmd" in motion.handle(jog)
    assert motion.handle(emc.EMC_JOINT_UNHOME(joint=EXTRA)) == (
        "cannot unhome extra joint 4 with motion enabled"
    )
    motion.handle(emc.EMC_TRAJ_DISABLE())
    assert motion.handle(emc.EMC_JOINT_UNHOME(joint=EXTRA)) is None


def test_kinematics_map_the_joints_without_the_extra_one() -> None:
    with pytest.raises(ValueError, match="kinematics maps 4 joints, motmod has 5"):
        MotionController(load_kinematics("trivkins", coordinates="XYZC"), 5, PERIOD)


# ------------------------------------------------------------------ locking indexer
def test_an_indexing_move_waits_for_the_unlock_and_relocks_before_the_next(hal: Hal) -> None:
    motion = hal.motion
    assert not any(unlock for unlock, _, _ in hal.unlock_log[-100:])  # homing relocked it
    coord(motion)
    hal.unlock_log.clear()
    assert motion.handle(rapid(c=90.0)) is None
    assert motion.handle(rapid(x=5.0, c=90.0)) is None
    hal.run(4000)
    log = hal.unlock_log
    assert motion.joints[LOCKING].pos_cmd == pytest.approx(90.0)
    assert motion.joints[0].pos_cmd == pytest.approx(5.0)
    # C never moved while locked, and the lock was asked for, then dropped
    assert all(unlocked for _, unlocked, c in log if 0.0 < c < 90.0)
    first_move = next(k for k, (_, _, c) in enumerate(log) if c > 0.0)
    # asked for while still locked, it waited; it started in the period the lock was open
    assert log[first_move - 1][:2] == (True, False) and log[first_move][1]
    assert not log[-1][0] and not log[-1][1]  # locked again at the end


def test_a_locking_indexer_cannot_be_jogged(hal: Hal) -> None:
    motion = hal.motion
    # homing left motion in teleop mode (as LinuxCNC's): joint jogs need free mode
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=FREE)) is None
    jog = emc.EMC_JOG_INCR(joint_or_axis=LOCKING, incr=1.0, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(jog) == "cannot jog locking indexer joint 3"
    assert motion.mode == FREE


def test_an_indexer_without_unlock_pins_is_refused() -> None:
    motion = MotionController(load_kinematics("trivkins", coordinates="XYZC"), 4, PERIOD)
    motion.indexers.set_axis_joint(C, LOCKING)
    assert "unlock_joints_mask=0x8" in motion.indexers.check_move(LOCKING)
