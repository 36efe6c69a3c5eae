"""Task canon's spindle-synchronised moves (G33, G33.1, G76, G95, G96)
as motion receives and runs them."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from nml import emc
from nml.channels import is_motion_type
from task.interp import canon as C  # noqa: N812  (C.UNITS_INCHES reads like CANON_UNITS_INCHES)
from tests.motion.test_controller import enabled_homed
from tests.motion.test_spindle import SpindleModel, run_until_done
from tests.task.test_canon import Machine, make_canon, messages

# what task keeps for itself instead of sending it on to motion (task/controller.py)
TASKS_OWN = (
    emc.EMC_TRAJ_SET_G5X,
    emc.EMC_TRAJ_SET_G92,
    emc.EMC_TRAJ_SET_ROTATION,
    emc.EMC_TRAJ_DELAY,
)


def send_to_motion(motion, out) -> int:
    """Hand canon's messages to motion as task would; returns how many were looked at."""
    out = list(out)
    for msg in out:
        if is_motion_type(msg.TYPE) and not isinstance(msg, TASKS_OWN):
            assert motion.handle(msg) is None, msg.NAME
    return len(out)


def test_g33_move_asks_for_the_axis_limit_without_a_feed_rate() -> None:
    canon = make_canon()
    canon.START_SPEED_FEED_SYNCH(0, 1.5, False)
    canon.STRAIGHT_FEED(3, 0, 0, -10, 0, 0, 0)  # no F word: motion follows the spindle
    canon.STOP_SPEED_FEED_SYNCH()
    sync_on, move, sync_off = messages(
        canon, emc.EMC_TRAJ_SET_SPINDLESYNC | emc.EMC_TRAJ_LINEAR_MOVE
    )
    assert (sync_on.feed_per_revolution, sync_on.velocity_mode) == (1.5, False)
    assert move.vel == move.ini_maxvel == pytest.approx(20.0)  # Z's limit
    assert move.end.tran.z == -10 and sync_off.feed_per_revolution == 0.0


def test_g95_sends_the_feed_per_revolution_in_machine_units() -> None:
    canon = make_canon("mm")
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)  # G20 program on a millimetre machine
    canon.SET_FEED_MODE(0, 1)
    canon.SET_FEED_RATE(0.01)  # inch per revolution
    canon.STRAIGHT_FEED(4, 1, 0, 0, 0, 0, 0)
    sync = messages(canon, emc.EMC_TRAJ_SET_SPINDLESYNC)[-1]
    assert sync.velocity_mode and sync.feed_per_revolution == pytest.approx(0.254)
    move = messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1]
    assert move.vel == move.ini_maxvel and move.feed_mode == 1


def test_rigid_tap_goes_to_the_hole_bottom_and_keeps_the_end_point() -> None:
    canon = make_canon()
    canon.START_SPEED_FEED_SYNCH(0, 1.0, False)
    canon.RIGID_TAP(5, 0, 0, -8, 1.0)
    canon.STOP_SPEED_FEED_SYNCH()
    (tap,) = messages(canon, emc.EMC_TRAJ_RIGID_TAP)
    assert tap.pos.tran.z == -8 and tap.ini_maxvel > 0 and tap.scale == 1.0
    assert canon.end_point[2] == 0.0


def test_g76_thread_cycle_from_the_interpreter_runs_on_motion(tmp_path: Path) -> None:
    """The interpreter's G76 through task canon into motion: every pass a G33 chain that
    starts at the index, the cycle ending where the canon says."""
    machine = Machine(tmp_path)
    machine.mdi("G18 G21 G90 G64", "M3 S600", "G0 X5 Z2", "G76 P1.5 Z-6 I-0.5 J0.3 K0.9")
    motion, spindle = enabled_homed(), SpindleModel()
    send_to_motion(motion, machine.canon.out)
    syncs = [
        msg
        for msg in messages(machine.canon, emc.EMC_TRAJ_SET_SPINDLESYNC)
        if msg.feed_per_revolution
    ]
    assert all((m.feed_per_revolution, m.velocity_mode) == (1.5, False) for m in syncs)
    passes = len(syncs)
    run_until_done(motion, spindle)
    assert passes >= 3 and spindle.index_pulses == passes
    end = machine.canon.end_point
    assert (motion.carte_pos_cmd.x, motion.carte_pos_cmd.z) == pytest.approx((end[0], end[2]))
    assert motion.errors == []


def test_g96_spindle_speed_follows_x_through_canon_and_motion(tmp_path: Path) -> None:
    machine = Machine(tmp_path)
    machine.mdi("G21 G90 G10 L2 P1 X5", "G96 D2000 S100 M3", "G0 X20")  # 100 m/min
    motion, spindle = enabled_homed(), SpindleModel()
    sent = send_to_motion(motion, machine.canon.out)
    run_until_done(motion, spindle)
    # the radius is X in the work coordinates: machine X 25 minus the G54 offset 5
    assert motion.carte_pos_cmd.x == pytest.approx(25.0)
    assert motion.spindles[0].speed_out == pytest.approx(100_000 / (2 * math.pi * 20.0))
    machine.mdi("G0 X5.5")  # near the centre: held at D, the maximum
    send_to_motion(motion, list(machine.canon.out)[sent:])
    run_until_done(motion, spindle)
    assert motion.spindles[0].speed_out == 2000.0
