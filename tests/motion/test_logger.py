"""motion-logger (motion/logger.py): each EMC_* message task sends motion, written as the
emcmot command lines LinuxCNC's task makes of it, in LinuxCNC's motion-logger's words.

The expected lines are those of LinuxCNC 2.9's own regression tests
(tests/motion-logger/*/expected.*), which its motion-logger wrote."""

from __future__ import annotations

from pathlib import Path

import pytest

from motion.logger import CommandLog, LogFile, MotionSettings, MotionState, homing_flags
from nml import emc
from nml.message import RCS_CMD_MSG, Receiver
from nml.registry import REGISTRY


def lines_of(*messages: emc.NMLmsg, settings: MotionSettings | None = None) -> list[str]:
    """What the log says of ``messages`` after a first command (whose start-up lines are
    left out)."""
    log = CommandLog(settings or MotionSettings(num_joints=3))
    log.lines(emc.EMC_TRAJ_ABORT())
    return [line for msg in messages for line in log.lines(msg)]


def test_every_message_task_sends_motion_has_its_lines() -> None:
    log = CommandLog(MotionSettings())
    motion_commands = [
        cls
        for cls in REGISTRY.all()
        if issubclass(cls, RCS_CMD_MSG) and cls.RECEIVER is Receiver.MOTION
    ]
    assert motion_commands
    assert [cls.NAME for cls in motion_commands if cls not in log.handlers] == []


def test_the_first_command_comes_after_the_joint_and_spindle_counts() -> None:
    log = CommandLog(MotionSettings(num_joints=9, num_spindles=2))
    assert log.lines(emc.EMC_TRAJ_SET_VELOCITY(velocity=0.0, ini_maxvel=1.2)) == [
        "SET_NUM_JOINTS 9",
        "SET_NUM_SPINDLES 2",
        "SET_VEL vel=0, ini_maxvel=1.2",
    ]
    assert log.lines(emc.EMC_TRAJ_SET_MAX_VELOCITY(velocity=4.0)) == ["SET_VEL_LIMIT vel=4"]


def test_the_first_acceleration_brings_the_settings_with_no_message() -> None:
    settings = MotionSettings(
        max_feed_override=1.2, probe_jog_err_inhibit=1, world_home=(1, 2, 3, 0, 0, 0, 0, 0, 0)
    )
    assert lines_of(emc.EMC_TRAJ_SET_ACCELERATION(acceleration=1e99), settings=settings) == [
        "SET_ACC acc=1e+99",
        "SETUP_ARC_BLENDS",
        "SET_MAX_FEED_OVERRIDE 1.2",
        "SETUP_SET_PROBE_ERR_INHIBIT 1 0",
        "SET_WORLD_HOME x=1, y=2, z=3, a=0, b=0, c=0, u=0, v=0, w=0",
    ]
    assert (
        lines_of(
            emc.EMC_TRAJ_SET_ACCELERATION(acceleration=1e99),
            emc.EMC_TRAJ_SET_ACCELERATION(acceleration=50.0),
        )[-1]
        == "SET_ACC acc=50"
    )


def test_a_joint_is_configured_in_linuxcncs_words() -> None:
    homing = emc.EMC_JOINT_SET_HOMING_PARAMS(
        joint=0, home=0.0, offset=0.0, home_final_vel=-1.0, home_sequence=999
    )
    assert lines_of(
        emc.EMC_JOINT_SET_BACKLASH(joint=0, backlash=0.0),
        emc.EMC_JOINT_SET_MIN_POSITION_LIMIT(joint=0, limit=-40.0),
        emc.EMC_JOINT_SET_MAX_POSITION_LIMIT(joint=0, limit=40.0),
        emc.EMC_JOINT_SET_FERROR(joint=0, ferror=0.05),
        emc.EMC_JOINT_SET_MIN_FERROR(joint=0, ferror=0.01),
        homing,
        emc.EMC_JOINT_SET_MAX_VELOCITY(joint=0, vel=4.0),
        emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=0, acc=1000.0),
        emc.EMC_JOINT_SET_MAX_ACCELERATION(joint=0, acc=500.0),  # later: no second activation
    ) == [
        "SET_JOINT_BACKLASH joint=0, backlash=0",
        # LinuxCNC's task sends both limits each time, the other one 0 until set
        "SET_JOINT_POSITION_LIMITS joint=0, min=-40, max=0",
        "SET_JOINT_POSITION_LIMITS joint=0, min=-40, max=40",
        "SET_JOINT_MAX_FERROR joint=0, maxFerror=0.05",
        "SET_JOINT_MIN_FERROR joint=0, minFerror=0.01",
        "SET_JOINT_HOMING_PARAMS joint=0, offset=0 home=0, final_vel=-1, search_vel=0, "
        "latch_vel=0, flags=0x00000000, sequence=999, volatile=0",
        "SET_JOINT_VEL_LIMIT joint=0, vel=4",
        "SET_JOINT_ACC_LIMIT joint=0, acc=1000",
        "JOINT_ACTIVATE joint=0",
        "SET_JOINT_ACC_LIMIT joint=0, acc=500",
    ]


def test_an_axis_is_configured_with_its_locking_joint_once() -> None:
    settings = MotionSettings(locking_joints={2: 3})
    assert lines_of(
        emc.EMC_AXIS_SET_MIN_POSITION_LIMIT(axis=2, limit=-4.0),
        emc.EMC_AXIS_SET_MAX_POSITION_LIMIT(axis=2, limit=4.0),
        emc.EMC_AXIS_SET_MAX_VELOCITY(axis=2, vel=4.0),
        emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=2, acc=1000.0),
        emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=0, acc=1000.0),
        emc.EMC_AXIS_SET_MAX_ACCELERATION(axis=2, acc=20.0),
        settings=settings,
    ) == [
        "SET_AXIS_POSITION_LIMITS axis=2, min=-4, max=0",
        "SET_AXIS_POSITION_LIMITS axis=2, min=-4, max=4",
        "SET_AXIS_VEL_LIMIT axis=2 vel=4",
        "SET_AXIS_ACC_LIMIT axis=2, acc=1000",
        "SET_AXIS_LOCKING_JOINT axis=2, locking_joint=3",
        "SET_AXIS_ACC_LIMIT axis=0, acc=1000",
        "SET_AXIS_LOCKING_JOINT axis=0, locking_joint=-1",
        "SET_AXIS_ACC_LIMIT axis=2, acc=20",
    ]


@pytest.mark.parametrize(
    ("fields", "flags"),
    [
        ({}, 0x00),
        ({"ignore_limits": 1, "use_index": 1, "is_shared": 1}, 0x07),
        ({"locking_indexer": 1, "encoder_does_not_reset": 1}, 0x88),
        ({"absolute_encoder": 1}, 0x30),
        ({"absolute_encoder": 2}, 0x70),
    ],
)
def test_homing_flags_are_linuxcncs(fields: dict[str, int], flags: int) -> None:
    assert homing_flags(emc.EMC_JOINT_SET_HOMING_PARAMS(joint=1, **fields)) == flags


def test_spindle_limits_print_the_reverse_speeds_negative() -> None:
    params = emc.EMC_SPINDLE_SET_PARAMS(
        spindle=0, max_forward=1e99, min_forward=0.0, max_reverse=1e99, min_reverse=0.0
    )
    assert lines_of(params) == ["SET_SPINDLE_PARAMS, 1.00e+99, 0.00e+00, -1.00e+99, 0.00e+00"]


def test_abort_enable_and_disable_expand_as_linuxcncs_task_sends_them() -> None:
    lines = lines_of(emc.EMC_MOTION_ABORT(), emc.EMC_TRAJ_ENABLE(), emc.EMC_TRAJ_DISABLE())
    jogs = [f"JOG_ABORT joint={n}" for n in range(16)]  # every joint motion could have
    amps = 3  # the machine's
    assert lines == [
        *jogs,
        "ABORT",
        "ENABLE",
        *["ENABLE_AMPLIFIER"] * amps,
        *["DISABLE_AMPLIFIER"] * amps,
        "DISABLE",
    ]
    assert lines_of(emc.EMC_TRAJ_ABORT()) == ["ABORT"]


def test_moves_spindle_and_offsets_as_in_linuxcncs_expected_logs() -> None:
    line = emc.EMC_TRAJ_LINEAR_MOVE(
        type=1, vel=1.66296, ini_maxvel=1.66296, acc=415.74, indexer_jnum=-1, id=2
    )
    line.end.set([1, 2, 3, 4, 5, 6, 7, 8, 9])
    assert lines_of(
        line,
        emc.EMC_SPINDLE_SPEED(spindle=0, speed=0.0),
        emc.EMC_SPINDLE_ON(spindle=0, speed=234.0),
        emc.EMC_TRAJ_SET_OFFSET(),
        emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.0),
        emc.EMC_SPINDLE_OFF(spindle=0),
        emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD),
        emc.EMC_JOINT_UNHOME(joint=-2),
    ) == [
        "SET_LINE x=1, y=2, z=3, a=4, b=5, c=6, u=7, v=8, w=9, id=2, motion_type=1, "
        "vel=1.66296, ini_maxvel=1.66296, acc=415.74, turn=-1",
        "SPINDLE_ON speed=0.000000, css_factor=0.000000, xoffset=0.000000",
        "SPINDLE_ON speed=234.000000, css_factor=0.000000, xoffset=0.000000",
        "SET_OFFSET x=0, y=0, z=0, a=0, b=0, c=0 u=0, v=0, w=0",
        "SET_SPINDLESYNC sync=0.000000, flags=0x00000000",
        "SPINDLE_OFF",
        "COORD",
        "JOINT_UNHOME joint=-2",
    ]


def test_an_arc_takes_five_lines() -> None:
    arc = emc.EMC_TRAJ_CIRCULAR_MOVE(turn=0, type=3, vel=0.5, ini_maxvel=4.0, acc=100.0, id=7)
    arc.end.set([1, 1, 0, 0, 0, 0, 0, 0, 0])
    arc.center.x, arc.normal.z = 1.0, 1.0
    assert lines_of(arc) == [
        "SET_CIRCLE:",
        "    pos: x=1, y=1, z=0, a=0, b=0, c=0, u=0, v=0, w=0",
        "    center: x=1, y=0, z=0",
        "    normal: x=0, y=0, z=1",
        "    id=7, motion_type=3, vel=0.5, ini_maxvel=4, acc=100, turn=0",
    ]


def test_what_linuxcncs_task_keeps_to_itself_is_not_logged() -> None:
    assert lines_of(emc.EMC_TRAJ_SET_MOTION_ID(id=5), emc.EMC_TRAJ_SET_MAX_ACCELERATION()) == []


def test_a_message_it_does_not_know_is_said_so() -> None:
    assert lines_of(emc.EMC_TASK_PLAN_RUN()) == ["ERROR: unknown command EMC_TASK_PLAN_RUN"]


def test_the_settings_come_from_the_ini_file(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[KINS]\nKINEMATICS = trivkins\nJOINTS = 4\n"
        "[TRAJ]\nCOORDINATES = X Y Z A\nLINEAR_UNITS = mm\nANGULAR_UNITS = degree\n"
        "SPINDLES = 2\nHOME = 1 2 3 4\nNO_PROBE_HOME_ERROR = 1\n"
        "[DISPLAY]\nMAX_FEED_OVERRIDE = 1.5\n"
        "[AXIS_A]\nLOCKING_INDEXER_JOINT = 3\n"
        + "".join(f"[JOINT_{n}]\nTYPE = LINEAR\n" for n in range(4))
    )
    settings = MotionSettings.read(str(ini))
    assert (settings.num_joints, settings.num_spindles) == (4, 2)
    assert settings.max_feed_override == 1.5
    assert (settings.probe_jog_err_inhibit, settings.probe_home_err_inhibit) == (0, 1)
    assert settings.world_home == (1, 2, 3, 0, 0, 0, 0, 0, 0)  # LinuxCNC reads X Y Z only
    assert settings.locking_joints == {0: -1, 1: -1, 2: -1, 3: 3}


def test_the_status_follows_what_task_reads_back() -> None:
    state = MotionState(num_joints=3, num_spindles=1)
    homing = [emc.EMC_JOINT_SET_HOMING_PARAMS(joint=n, volatile_home=int(n == 1)) for n in range(3)]
    for msg in [
        *homing,
        emc.EMC_TRAJ_ENABLE(),
        emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.COORD),
        emc.EMC_JOINT_HOME(joint=-1),
        emc.EMC_JOINT_UNHOME(joint=-2),  # the VOLATILE_HOME joint only
        emc.EMC_SPINDLE_ON(spindle=0, speed=-300.0),
    ]:
        state.take(msg)
    stat = emc.EMC_MOTION_STAT()
    state.fill(stat)
    assert stat.traj.enabled and stat.traj.mode == emc.EMC_TRAJ_MODE_ENUM.COORD
    assert stat.traj.inpos and stat.traj.queue == 0 and stat.traj.joints == 3
    assert [stat.joint[n].homed for n in range(3)] == [1, 0, 1]
    assert stat.spindle[0].speed == -300.0 and stat.spindle[0].direction == -1
    state.take(emc.EMC_TRAJ_DISABLE())
    state.take(emc.EMC_SPINDLE_OFF(spindle=0))
    state.fill(stat)
    assert not stat.traj.enabled and stat.spindle[0].speed == 0.0


def test_a_reopened_log_starts_afresh(tmp_path: Path) -> None:
    path = tmp_path / "out.motion-logger"
    log = LogFile(str(path))
    log.write(["ABORT", "SPINDLE_OFF"])
    assert path.read_text() == "ABORT\nSPINDLE_OFF\n"  # each line flushed at once
    log.close()
    path.rename(tmp_path / "result.first")
    log.write([])
    assert not path.exists()  # opened with the next line, not before
    log.write(["ENABLE"])
    assert path.read_text() == "ENABLE\n"
    assert (tmp_path / "result.first").read_text() == "ABORT\nSPINDLE_OFF\n"
    log.close()
