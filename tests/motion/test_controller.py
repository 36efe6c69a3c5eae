"""The motion controller: commands and servo periods, without HAL or processes (MOT-*)."""

from __future__ import annotations

import math

import pytest

from motion.controller import COORD, FREE, Inputs, MotionController
from motion.kinematics import load_kinematics
from nml import emc

PERIOD = 0.001


def make(num_joints: int = 3) -> MotionController:
    motion = MotionController(
        load_kinematics("trivkins", coordinates="XYZ"), num_joints, PERIOD, num_dio=4, num_aio=2
    )
    for joint in range(num_joints):
        for cmd in (
            emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=joint, limit=-100.0),
            emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=joint, limit=100.0),
            emc.EMC_JOINT_SET_MAX_VELOCITY(joint=joint, vel=50.0),
        ):
            assert motion.handle(cmd) is None
        for cmd in (
            emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=joint, acc=500.0),
            emc.EMC_AXIS_SET_MAX_VELOCITY(axis=joint, vel=50.0),
            emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=joint, acc=500.0),
            emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=joint, limit=-100.0),
            emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=joint, limit=100.0),
            emc.EMC_JOINT_SET_HOMING_PARAMS(joint=joint, home_sequence=0),
        ):
            assert motion.handle(cmd) is None
    return motion


def run(motion: MotionController, periods: int, **inputs) -> None:
    n = len(motion.joints)
    for _ in range(periods):
        fb = [j.pos_cmd + j.motor_offset for j in motion.joints]  # a perfect servo loop
        motion.update(Inputs(fb, [False] * n, [False] * n, [False] * n, **inputs))


def enabled_homed(mode=COORD) -> MotionController:
    motion = make()
    assert motion.handle(emc.EMC_TRAJ_ENABLE()) is None
    assert motion.handle(emc.EMC_JOINT_HOME(joint=-1)) is None
    for _ in range(10_000):  # homing moves the joints to HOME, then it is done
        run(motion, 1)
        if not motion.homing.is_homing and motion.is_in_position:
            break
    assert all(j.is_homed for j in motion.joints)
    # (homing goes into teleop mode by itself, as LinuxCNC's: asked for here as the others)
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=mode)) is None
    return motion


def move(x: float, y: float = 0.0, z: float = 0.0, vel: float = 20.0, rapid: bool = False):
    cmd = emc.EMC_TRAJ_LINEAR_MOVE(vel=vel, ini_maxvel=50.0, acc=500.0)
    cmd.type = emc.EMC_MOTION_TYPE.TRAVERSE if rapid else emc.EMC_MOTION_TYPE.FEED
    cmd.end.tran.x, cmd.end.tran.y, cmd.end.tran.z = x, y, z
    return cmd


def test_unknown_command_is_refused_with_its_name() -> None:
    assert make().handle(emc.EMC_TASK_ABORT()) == "motion does not handle EMC_TASK_ABORT"


def test_jog_needs_motion_enabled_then_incremental_jogs_add_up() -> None:
    motion = make()
    jog = emc.EMC_JOG_INCR(joint_or_axis=0, incr=1.0, vel=10.0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(jog) == "cannot jog with motion disabled"
    motion.handle(emc.EMC_TRAJ_ENABLE())
    assert motion.handle(jog) is None
    run(motion, 20)
    assert motion.handle(jog) is None  # MOT-048: cumulative while the first runs
    run(motion, 1000)
    assert motion.joints[0].pos_cmd == pytest.approx(2.0)
    assert motion.carte_pos_cmd.x == pytest.approx(2.0)


def test_continuous_jog_stops_at_the_soft_limit_once_homed() -> None:
    motion = enabled_homed(mode=FREE)
    assert motion.handle(emc.EMC_JOG_CONT(joint_or_axis=1, vel=50.0, jjogmode=1)) is None
    run(motion, 3000)
    assert motion.joints[1].pos_cmd == pytest.approx(100.0)
    refused = motion.handle(emc.EMC_JOG_CONT(joint_or_axis=1, vel=5.0, jjogmode=1))
    assert refused == "joint 1: at or beyond the positive soft limit 100: cannot jog further"


def test_coordinated_mode_needs_all_joints_homed_unless_kinematics_are_identity() -> None:
    motion = MotionController(
        load_kinematics("trivkins", coordinates="XYZ", kinstype="both"), 3, PERIOD
    )
    motion.handle(emc.EMC_TRAJ_ENABLE())
    refused = motion.handle(emc.EMC_TRAJ_SET_MODE(mode=COORD))
    assert refused == "all joints must be homed before going into coordinated mode"
    identity = make()  # LinuxCNC's motion lets identity kinematics coordinate unhomed
    identity.handle(emc.EMC_TRAJ_ENABLE())
    assert identity.handle(emc.EMC_TRAJ_SET_MODE(mode=COORD)) is None


def test_homing_without_switches_sets_home_offset_then_moves_home() -> None:
    motion = make()
    motion.handle(emc.EMC_TRAJ_ENABLE())
    motion.joints[0].shift(7.0)  # wherever the machine happens to stand
    motion.joints[0].motor_offset = 0.0
    params = emc.EMC_JOINT_SET_HOMING_PARAMS(joint=0, home=1.0, offset=0.5, home_sequence=0)
    assert motion.handle(params) is None
    assert motion.handle(emc.EMC_JOINT_HOME(joint=0)) is None
    run(motion, 500)
    joint = motion.joints[0]
    assert joint.is_homed and joint.pos_cmd == pytest.approx(1.0)
    assert joint.pos_cmd + joint.motor_offset == pytest.approx(7.5)  # the motor moved 0.5


def test_linear_moves_reach_their_end_and_report_in_position() -> None:
    motion = enabled_homed()
    motion.handle(emc.EMC_TRAJ_SET_MOTION_ID(id=42))
    assert motion.handle(move(10.0, 5.0)) is None
    run(motion, 5)
    assert not motion.is_in_position and motion.tp.motion_id == 42
    run(motion, 2000)
    assert motion.is_in_position
    assert [j.pos_cmd for j in motion.joints] == pytest.approx([10.0, 5.0, 0.0])


def test_a_move_carries_its_own_motion_id_or_keeps_the_last_one() -> None:
    """Task stamps the line into the move (one command per move, as LinuxCNC's
    emcmotCommand.id); a move without one (id 0) runs under the last SET_MOTION_ID's."""
    motion = enabled_homed()
    stamped = move(150.0)
    stamped.id = 7
    assert motion.handle(stamped).startswith("Linear move on line 7 ")
    assert motion.handle(emc.EMC_TRAJ_ABORT()) is None  # (as task does after a refusal)
    motion.handle(emc.EMC_TRAJ_SET_MOTION_ID(id=3))
    assert motion.handle(move(5.0)) is None
    second = move(10.0)
    second.id = 4
    assert motion.handle(second) is None
    seen = set()
    for _ in range(2000):
        run(motion, 1)
        seen.add(motion.tp.motion_id)
    assert seen >= {3, 4} and motion.tp.motion_id == 4


def test_move_beyond_a_soft_limit_is_refused_before_it_starts() -> None:
    motion = enabled_homed()
    motion.handle(emc.EMC_TRAJ_SET_MOTION_ID(id=12))
    assert motion.handle(move(150.0)).splitlines() == [  # LinuxCNC's two messages
        "Linear move on line 12 would exceed X's positive limit",
        "Linear move on line 12 would exceed joint 0's positive limit",
    ]
    assert motion.tp.queue_depth == 0


def test_after_a_refused_move_everything_is_refused_quietly_until_an_abort() -> None:
    """What task queued after a refused move must not run (it would start from the wrong
    place): refused without a new message until task's ABORT (or motion off, on, or in
    another mode)."""
    motion = enabled_homed()
    assert motion.handle(move(150.0))  # beyond X's limit
    assert motion.handle(move(10.0)) == ""
    assert motion.handle(emc.EMC_SPINDLE_ON(speed=1000.0)) == ""
    assert motion.tp.queue_depth == 0 and motion.spindles[0].speed == 0.0
    assert motion.handle(emc.EMC_TRAJ_ABORT()) is None
    assert motion.handle(move(10.0)) is None
    assert motion.handle(move(150.0))
    assert motion.handle(emc.EMC_TRAJ_DISABLE()) is None
    assert motion.handle(emc.EMC_TRAJ_ENABLE()) is None
    assert motion.handle(emc.EMC_TRAJ_SET_MOTION_ID(id=5)) is None


def test_circular_move_follows_the_radius() -> None:
    motion = enabled_homed()
    motion.handle(move(10.0))
    arc = emc.EMC_TRAJ_CIRCULAR_MOVE(turn=0, vel=10.0, ini_maxvel=50.0, acc=500.0)
    arc.end.tran.x = -10.0
    arc.normal.z = 1.0
    assert motion.handle(arc) is None
    run(motion, 200)  # on the way to the arc start
    radii = []
    while not motion.is_in_position:
        run(motion, 1)
        if motion.tp.queue_depth == 1:
            radii.append(math.hypot(motion.carte_pos_cmd.x, motion.carte_pos_cmd.y))
    assert radii and max(abs(r - 10.0) for r in radii) < 1e-6
    assert motion.carte_pos_cmd.x == pytest.approx(-10.0)


def test_abort_is_always_accepted_and_stops_the_queue() -> None:
    motion = enabled_homed()
    for x in (20.0, 40.0, 60.0):
        motion.handle(move(x))
    run(motion, 300)
    for _ in range(1000):  # thousands of aborts in a row create no fault
        assert motion.handle(emc.EMC_TRAJ_ABORT()) is None
    run(motion, 1000)
    assert motion.is_in_position and motion.tp.queue_depth == 0
    assert motion.carte_pos_cmd.x < 20.0  # stopped along the first move, never reached 60
    assert motion.errors == []


def test_following_error_disables_motion_and_says_so() -> None:
    motion = enabled_homed()
    motion.handle(emc.EMC_JOINT_SET_FERROR(joint=2, ferror=0.5))
    motion.handle(emc.EMC_JOINT_SET_MIN_FERROR(joint=2, ferror=0.1))
    n = 3
    motion.update(Inputs([0.0, 0.0, 3.0], [False] * n, [False] * n, [False] * n))
    assert motion.errors == ["joint 2 following error"]
    assert not motion.is_enabled


def test_feedback_that_is_not_a_number_stops_motion_and_the_command_holds() -> None:
    """A drive or encoder component gone wrong (NaN on motor-pos-fb) is a fault, like a
    following error, and never reaches the motor command: NaN compares false with any
    following-error limit, so it would otherwise go unnoticed."""
    motion = enabled_homed()
    assert motion.handle(move(5.0)) is None
    run(motion, 50)
    before = [j.motor_pos_cmd for j in motion.joints]
    assert before[0] > 0
    n = 3
    for _ in range(20):  # the broken feedback stays broken
        fb = [math.nan] + [j.pos_cmd + j.motor_offset for j in motion.joints[1:]]
        motion.update(Inputs(fb, [False] * n, [False] * n, [False] * n))
    assert motion.errors == ["joint 0 position feedback is nan (joint.0.motor-pos-fb)"]
    assert not motion.is_enabled
    after = [j.motor_pos_cmd for j in motion.joints]
    assert after == pytest.approx(before, abs=0.1)  # held near where it was, all finite
    assert all(math.isfinite(v) for v in after)
    assert all(math.isfinite(v) for v in motion.carte_pos_cmd)


def test_hard_limit_switch_disables_motion_unless_overridden() -> None:
    motion = enabled_homed()
    n = 3
    fb = [0.0] * n
    motion.update(Inputs(fb, [False, True, False], [False] * n, [False] * n))
    assert motion.errors == ["joint 1 on limit switch error"]  # LinuxCNC's words
    assert not motion.is_enabled


def test_synchronised_digital_output_waits_for_the_next_move() -> None:
    motion = enabled_homed()
    motion.handle(emc.EMC_MOTION_SET_DOUT(index=1, start=1, now=0))
    assert motion.digital_out == [False] * 4
    motion.handle(move(1.0))
    assert motion.digital_out == [False, True, False, False]
    assert motion.handle(emc.EMC_MOTION_SET_DOUT(index=9, start=1, now=1)) == (
        "digital output 9 does not exist (num_dio 4)"
    )


def test_status_reports_positions_joints_and_queue() -> None:
    motion = enabled_homed()
    motion.handle(move(3.0, 2.0, 1.0))
    run(motion, 2000)
    stat = emc.EMC_MOTION_STAT()
    motion.fill_status(stat)
    assert stat.traj.mode == COORD and stat.traj.enabled and stat.traj.inpos
    assert (stat.traj.position.tran.x, stat.traj.position.tran.z) == pytest.approx((3.0, 1.0))
    assert stat.traj.actualPosition.tran.y == pytest.approx(2.0)
    assert [stat.joint[i].homed for i in range(3)] == [1, 1, 1]
    assert stat.joint[0].maxPositionLimit == 100.0 and stat.traj.joints == 3


def test_settings_task_sends_with_every_program_are_accepted() -> None:
    motion = enabled_homed()
    offset = emc.EMC_TRAJ_SET_OFFSET()
    offset.offset.tran.z = 12.5
    for cmd in (
        offset,
        emc.EMC_TRAJ_SET_FO_ENABLE(mode=0),
        emc.EMC_TRAJ_SET_SO_ENABLE(spindle=0, mode=0),
        emc.EMC_TRAJ_SET_FH_ENABLE(mode=1),
        emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.0),
    ):
        assert motion.handle(cmd) is None, cmd.NAME
    assert motion.tool_offset.z == 12.5 and not motion.is_feed_override_enabled
    refused = motion.handle(emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=3, feed_per_revolution=1.5))
    assert refused == "spindle 3 does not exist (num_spindles 1)"


def test_spindle_speed_changes_keep_the_direction() -> None:
    motion = enabled_homed()
    motion.handle(emc.EMC_SPINDLE_ON(spindle=0, speed=-1000.0))
    motion.handle(emc.EMC_SPINDLE_SPEED(spindle=0, speed=1500.0))
    assert motion.spindles[0].speed == -1500.0
    motion.handle(emc.EMC_SPINDLE_DECREASE(spindle=0, speed=500.0))
    assert motion.spindles[0].speed == -1000.0


def test_teleop_jogs_world_axes_through_the_kinematics() -> None:
    motion = enabled_homed(mode=FREE)
    axis_jog = emc.EMC_JOG_INCR(joint_or_axis=0, incr=5.0, vel=20.0, jjogmode=emc.JOG_MODE.TELEOP)
    assert motion.handle(axis_jog) == (
        "jogging an axis needs teleop mode (teleop_enable(1) once homed)"
    )
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.TELEOP)) is None
    assert motion.handle(axis_jog) is None
    assert motion.handle(axis_jog) is None  # cumulative, as joint jogs (MOT-048)
    run(motion, 2000)
    assert motion.carte_pos_cmd.x == pytest.approx(10.0)
    assert motion.joints[0].pos_cmd == pytest.approx(10.0)  # trivkins: joint 0 is X
    joint_jog = emc.EMC_JOG_INCR(joint_or_axis=0, incr=1.0, vel=5.0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(joint_jog) == "jogging a joint needs free (joint) mode"
    unused = emc.EMC_JOG_CONT(joint_or_axis=4, vel=5.0, jjogmode=emc.JOG_MODE.TELEOP)
    assert motion.handle(unused) == "axis 4 is not used by this machine"


def test_a_jog_stop_is_never_refused_and_stops_what_its_index_does_now() -> None:
    """LinuxCNC's jog abort 'can happen at any time': a UI that sends a joint stop while
    motion went teleop (homing completes) must still stop the axis jog."""
    motion = enabled_homed(mode=FREE)
    motion.handle(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.TELEOP))
    assert motion.handle(emc.EMC_JOG_CONT(joint_or_axis=0, vel=20.0, jjogmode=0)) is None
    run(motion, 200)
    joint_stop = emc.EMC_JOG_STOP(joint_or_axis=0, jjogmode=emc.JOG_MODE.JOINT)
    assert motion.handle(joint_stop) is None
    run(motion, 1000)
    stopped_at = motion.carte_pos_cmd.x
    run(motion, 200)
    assert motion.carte_pos_cmd.x == stopped_at and 0.0 < stopped_at < 20.0
    assert motion.jog_leases == {}
    motion.handle(emc.EMC_TRAJ_DISABLE())
    assert motion.handle(joint_stop) is None
    assert motion.handle(emc.EMC_JOG_STOP(joint_or_axis=8, jjogmode=0)) is None


def test_teleop_jog_stops_at_the_axis_soft_limit() -> None:
    motion = enabled_homed(mode=FREE)
    motion.handle(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.TELEOP))
    assert motion.handle(emc.EMC_JOG_CONT(joint_or_axis=1, vel=-50.0, jjogmode=0)) is None
    run(motion, 4000)
    assert motion.carte_pos_cmd.y == pytest.approx(-100.0)
    assert motion.is_in_position


def test_status_tells_which_kind_of_move_runs() -> None:
    motion = enabled_homed()
    motion.handle(move(20.0, rapid=True))
    run(motion, 5)
    stat = emc.EMC_MOTION_STAT()
    motion.fill_status(stat)
    assert stat.traj.motion_type == emc.EMC_MOTION_TYPE.TRAVERSE and not stat.traj.probing
    run(motion, 3000)
    motion.fill_status(stat)
    assert stat.traj.motion_type == 0  # nothing left to do


@pytest.mark.parametrize(("turn", "passes_y"), [(0, 10.0), (-1, -10.0)])
def test_arc_direction_follows_linuxcncs_turn_convention(turn: int, passes_y: float) -> None:
    """turn 0 is one counter-clockwise arc about the normal, -1 one clockwise arc (G2)."""
    motion = enabled_homed()
    motion.handle(move(10.0))
    run(motion, 1000)
    arc = emc.EMC_TRAJ_CIRCULAR_MOVE(turn=turn, vel=20.0, ini_maxvel=50.0, acc=500.0)
    arc.end.tran.x = -10.0
    arc.normal.z = 1.0  # the plane's normal, whichever the direction, as emccanon sends it
    assert motion.handle(arc) is None
    extreme = 0.0
    while not motion.is_in_position:
        run(motion, 1)
        y = motion.carte_pos_cmd.y
        extreme = y if abs(y) > abs(extreme) else extreme
    assert extreme == pytest.approx(passes_y, abs=1e-3)  # sampled each period
    assert motion.carte_pos_cmd.x == pytest.approx(-10.0)
