"""MPG wheels on joint.N.jog-* (free mode) and axis.L.jog-* (teleop mode), and the
motion.jog-inhibit / jog-stop / jog-stop-immediate / jog-is-active pins, motion(9)."""

from __future__ import annotations

import pytest

from motion.controller import FREE, Inputs, MotionController, WheelInputs
from nml import emc
from tests.motion.test_controller import enabled_homed


def turn(motion: MotionController, periods: int, joint=None, axis=None, **pins) -> None:
    """Run with ``joint`` as joint 0's wheel and ``axis`` as axis Y's, and ``pins`` as
    the motion.jog-* inputs (``is_jog_stop=True`` ...)."""
    n = len(motion.joints)
    joint_wheels = [joint, *(WheelInputs() for _ in range(n - 1))] if joint else []
    axis_wheels = {1: axis} if axis else {}
    for _ in range(periods):
        fb = [j.pos_cmd + j.motor_offset for j in motion.joints]
        inputs = Inputs(fb, [False] * n, [False] * n, [False] * n, **pins)
        inputs.joint_wheels, inputs.axis_wheels = joint_wheels, axis_wheels
        motion.update(inputs)


def test_wheel_moves_the_joint_by_counts_times_scale_once_enabled() -> None:
    motion = enabled_homed(mode=FREE)
    wheel = WheelInputs(counts=5, scale=0.1)
    turn(motion, 10, joint=wheel)
    wheel.counts = 40  # not enabled: these counts are dropped
    turn(motion, 10, joint=wheel)
    assert motion.joints[0].pos_cmd == 0.0
    wheel.is_enabled = True
    wheel.counts = 65
    turn(motion, 2000, joint=wheel)
    assert motion.joints[0].pos_cmd == pytest.approx(2.5)
    wheel.counts = 55  # back 10 counts
    turn(motion, 2000, joint=wheel)
    assert motion.joints[0].pos_cmd == pytest.approx(1.5)


def test_wheel_stops_at_the_soft_limit_and_uses_the_acceleration_fraction() -> None:
    motion = enabled_homed(mode=FREE)
    wheel = WheelInputs(is_enabled=True, scale=1.0, accel_fraction=0.1)
    turn(motion, 1, joint=wheel)
    wheel.counts = 500  # far beyond the +100 limit
    speeds = []
    for _ in range(20):
        turn(motion, 1, joint=wheel)
        speeds.append(motion.joints[0].planner.vel)
    assert speeds[-1] == pytest.approx(20 * 0.1 * 500.0 * 0.001)  # 10 % of 500 /s^2
    turn(motion, 8000, joint=wheel)
    assert motion.joints[0].pos_cmd == pytest.approx(100.0)


def test_velocity_mode_drops_what_cannot_be_stopped_for() -> None:
    motion = enabled_homed(mode=FREE)
    wheel = WheelInputs(is_enabled=True, scale=1.0, is_vel_mode=True)
    turn(motion, 1, joint=wheel)
    wheel.counts = 60  # 60 mm at once; braking from 50 mm/s at 500 /s^2 takes 2.5 mm
    turn(motion, 4000, joint=wheel)
    assert motion.joints[0].pos_cmd == pytest.approx(2.5)


def test_axis_wheel_jogs_in_teleop_mode_only() -> None:
    motion = enabled_homed(mode=FREE)
    wheel = WheelInputs(is_enabled=True, scale=0.5)
    turn(motion, 1, axis=wheel)
    wheel.counts = 4
    turn(motion, 100, axis=wheel)
    assert motion.carte_pos_cmd.y == 0.0  # free mode: axis wheels do nothing
    assert motion.handle(emc.EMC_TRAJ_SET_MODE(mode=emc.EMC_TRAJ_MODE_ENUM.TELEOP)) is None
    wheel.counts = 10
    turn(motion, 2000, axis=wheel)
    assert motion.carte_pos_cmd.y == pytest.approx(3.0)


def jog_cont(motion: MotionController) -> str | None:
    return motion.handle(emc.EMC_JOG_CONT(joint_or_axis=0, vel=20.0, jjogmode=emc.JOG_MODE.JOINT))


def test_jog_inhibit_refuses_jogs_and_ignores_the_wheel() -> None:
    motion = enabled_homed(mode=FREE)
    wheel = WheelInputs(is_enabled=True, scale=1.0)
    turn(motion, 1, joint=wheel, is_jog_inhibited=True)
    assert jog_cont(motion) == "jogging is inhibited (motion.jog-inhibit)"
    wheel.counts = 3
    turn(motion, 500, joint=wheel, is_jog_inhibited=True)
    assert motion.joints[0].pos_cmd == 0.0 and not motion.is_jogging


def test_jog_stop_brakes_and_jog_stop_immediate_stops_at_once() -> None:
    motion = enabled_homed(mode=FREE)
    assert jog_cont(motion) is None
    turn(motion, 200)
    assert motion.is_jogging and motion.joints[0].planner.vel == pytest.approx(20.0)
    turn(motion, 1, is_jog_stop=True)
    assert 0.0 < motion.joints[0].planner.vel < 20.0  # braking at the acceleration limit
    turn(motion, 100, is_jog_stop=True)
    assert not motion.is_jogging
    assert jog_cont(motion) is None  # the pin held TRUE stops only on its rising edge
    turn(motion, 200, is_jog_stop=True)
    assert motion.is_jogging
    turn(motion, 1, is_jog_stop_immediate=True)
    assert motion.joints[0].planner.vel == 0.0 and not motion.is_jogging
