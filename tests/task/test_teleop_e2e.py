"""The teleop vector through the whole machine (MOT-016, MOT-055): a UI's
``command.teleop_vector`` goes through task to motion, which moves the test mill along it
in teleop mode and stops on a zero vector; outside teleop mode it is refused."""

from __future__ import annotations

import math

import pytest

import cnc
from tests.task.test_machine import Machine


def teleop(machine: Machine) -> None:
    c = machine.command
    c.mode(cnc.MODE_MANUAL)
    assert c.wait_complete() == cnc.RCS_DONE
    c.teleop_enable(1)
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.motion_mode == cnc.TRAJ_MODE_TELEOP)


def test_teleop_vector_moves_the_machine_along_it_and_zero_stops(start_machine) -> None:
    machine = start_machine()
    teleop(machine)
    c = machine.command
    start = machine.stat.position[:3]
    c.teleop_vector(10.0, -5.0, 2.0)
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.position[0] - start[0] > 3.0)
    assert machine.stat.current_vel > 0.0
    c.teleop_vector(0.0, 0.0, 0.0)
    assert c.wait_complete() == cnc.RCS_DONE
    machine.until(lambda s: s.inpos and s.current_vel == 0.0)
    stopped = machine.stat.position[:3]
    moved = [b - a for a, b in zip(start, stopped, strict=True)]
    length = math.hypot(*moved)
    # along the vector from where it started, and still once stopped
    assert [m / length for m in moved] == pytest.approx(
        [v / math.hypot(10.0, -5.0, 2.0) for v in (10.0, -5.0, 2.0)], abs=1e-6
    )
    machine.stat.poll()
    assert machine.stat.position[:3] == stopped
    assert machine.stat.motion_mode == cnc.TRAJ_MODE_TELEOP


def test_teleop_vector_is_refused_outside_teleop_mode(start_machine) -> None:
    machine = start_machine()  # in MDI mode: task refuses manual motion
    c = machine.command
    machine.messages(0.05)
    c.teleop_vector(5.0, 0.0, 0.0)
    assert c.wait_complete() == cnc.RCS_ERROR
    assert any("must be in MANUAL mode" in text for _, text in machine.messages())
    c.mode(cnc.MODE_MANUAL)
    assert c.wait_complete() == cnc.RCS_DONE
    c.teleop_enable(0)  # free (joint) mode: motion refuses it (MOT-012)
    assert c.wait_complete() == cnc.RCS_DONE
    c.teleop_vector(5.0, 0.0, 0.0)
    assert c.wait_complete() == cnc.RCS_ERROR
    assert any("teleop vector needs teleop mode" in text for _, text in machine.messages())
    machine.stat.poll()
    assert machine.stat.inpos and machine.stat.position[0] == pytest.approx(0.0, abs=1e-9)
