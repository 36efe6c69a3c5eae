"""Motion's spindle: at-speed waits, M19 orient, G33 / G95 / G96 / G33.1 (MOT-062, MOT-065).

The controller runs against a small spindle model standing in for sim_spindle.hal: the
speed ramps toward ``speed_out``, the revolutions integrate it, the index pulse clears
index-enable and restarts the count, at-speed compares the two speeds.
"""

from __future__ import annotations

import math

import pytest

from motion.controller import Inputs, MotionController, OrientState, SpindleInputs
from nml import emc
from tests.motion.test_controller import PERIOD, enabled_homed, move


class SpindleModel:
    """Spindle 0 with 3000 rpm/s of acceleration and an index pulse."""

    def __init__(self, revs: float = 0.3, rpm_per_s: float = 3000.0) -> None:
        self.rpm = 0.0
        self.revs = revs
        self.rpm_per_s = rpm_per_s
        self.inputs = SpindleInputs(revs=revs)
        self.is_at_speed_forced: bool | None = None
        self.index_pulses = 0

    def step(self, motion: MotionController) -> None:
        spindle = motion.spindles[0]
        target = spindle.speed_out
        step = self.rpm_per_s * PERIOD
        self.rpm = min(max(target, self.rpm - step), self.rpm + step)
        old = self.revs
        self.revs += self.rpm / 60.0 * PERIOD
        pins = self.inputs
        pins.index_enable = spindle.is_index_enabled
        if pins.index_enable and math.floor(old) != math.floor(self.revs):
            pins.index_enable = False
            self.revs -= math.ceil(self.revs) if self.rpm < 0 else math.floor(self.revs)
            self.index_pulses += 1
        pins.revs = self.revs
        pins.speed_in = self.rpm / 60.0
        is_at_speed = abs(self.rpm - target) <= max(10.0, 0.02 * abs(target))
        if self.is_at_speed_forced is not None:
            is_at_speed = self.is_at_speed_forced
        pins.is_at_speed = is_at_speed


def run(motion: MotionController, spindle: SpindleModel, periods: int, watch=None) -> None:
    n = len(motion.joints)
    for _ in range(periods):
        spindle.step(motion)
        fb = [j.pos_cmd + j.motor_offset for j in motion.joints]
        motion.update(Inputs(fb, [False] * n, [False] * n, [False] * n, spindles=[spindle.inputs]))
        if watch is not None:
            watch(motion, spindle)


def run_until_done(motion, spindle, limit: int = 60_000, watch=None) -> None:
    for _ in range(limit):
        run(motion, spindle, 1, watch)
        if motion.is_in_position:
            return
    raise AssertionError("motion did not finish")


def ok(motion: MotionController, cmd: emc.NMLmsg) -> None:
    assert motion.handle(cmd) is None, cmd.NAME


def test_feed_after_spindle_on_waits_for_at_speed_and_rapids_do_not() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    spindle.is_at_speed_forced = False
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=1000.0, wait_for_spindle_at_speed=1))
    ok(motion, move(1.0, rapid=True))
    ok(motion, move(2.0))
    run(motion, spindle, 2000)
    assert motion.carte_pos_cmd.x == pytest.approx(1.0)  # the rapid ran, the feed waits
    assert motion.tp.is_waiting_for_at_speed and not motion.is_in_position
    spindle.is_at_speed_forced = None
    run_until_done(motion, spindle)
    assert motion.carte_pos_cmd.x == pytest.approx(2.0)
    assert not motion.tp.is_waiting_for_at_speed
    ok(motion, move(3.0))  # no new spindle command: no wait
    spindle.is_at_speed_forced = False
    run_until_done(motion, spindle)
    assert motion.carte_pos_cmd.x == pytest.approx(3.0)


def test_spindle_pins_follow_direction_override_and_inhibit() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=-1200.0))
    ok(motion, emc.EMC_TRAJ_SET_SPINDLE_SCALE(spindle=0, scale=0.5))
    run(motion, spindle, 1)
    state = motion.spindles[0]
    assert state.speed_out == -600.0 and not state.is_brake_on
    spindle.inputs.is_inhibited = True
    run(motion, spindle, 1)
    assert state.speed_out == 0.0 and state.speed == -1200.0


def test_spindle_amplifier_fault_disables_motion() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    spindle.inputs.is_amp_fault = True
    run(motion, spindle, 1)
    assert not motion.is_enabled and motion.errors == ["spindle 0 amplifier fault"]


def test_m19_orients_then_locks_and_the_next_move_waits_for_it() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=500.0))
    run(motion, spindle, 10)
    ok(motion, emc.EMC_SPINDLE_ORIENT(spindle=0, orientation=90.0, mode=1))
    ok(motion, emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE(spindle=0, timeout=5.0))
    ok(motion, move(1.0))
    run(motion, spindle, 50)
    state = motion.spindles[0]
    assert state.speed_out == 0.0 and state.is_orienting and state.orient_angle == 90.0
    assert state.orient_state == OrientState.IN_PROGRESS and not motion.is_in_position
    assert motion.carte_pos_cmd.x == 0.0  # held until oriented
    spindle.inputs.is_oriented = True
    run_until_done(motion, spindle)
    assert state.orient_state == OrientState.COMPLETE and state.is_locked and state.is_brake_on
    assert not state.is_orienting and motion.carte_pos_cmd.x == pytest.approx(1.0)
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=500.0))  # M3 unlocks
    assert not state.is_locked and state.orient_state == OrientState.NONE


def test_orient_fault_is_an_error_and_drops_the_waiting_moves() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    ok(motion, emc.EMC_SPINDLE_ORIENT(spindle=0, orientation=0.0, mode=0))
    ok(motion, emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE(spindle=0, timeout=5.0))
    ok(motion, move(1.0))
    spindle.inputs.orient_fault = 7
    run(motion, spindle, 5)
    state = motion.spindles[0]
    assert state.orient_state == OrientState.FAULTED and state.orient_fault == 7
    assert "spindle 0 orient fault 7" in motion.errors
    assert motion.is_in_position and motion.carte_pos_cmd.x == 0.0
    refused = motion.handle(emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE(spindle=0, timeout=1.0))
    assert refused == "spindle 0 orient fault 7"


def test_orient_wait_times_out() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    ok(motion, emc.EMC_SPINDLE_ORIENT(spindle=0, orientation=0.0, mode=0))
    ok(motion, emc.EMC_SPINDLE_WAIT_ORIENT_COMPLETE(spindle=0, timeout=0.05))
    run(motion, spindle, 100)
    assert motion.errors == ["spindle 0 orient timed out"] and motion.is_in_position


def _thread_setup(speed: float) -> tuple[MotionController, SpindleModel]:
    motion, spindle = enabled_homed(), SpindleModel()
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=speed, wait_for_spindle_at_speed=1))
    return motion, spindle


@pytest.mark.parametrize("speed", [600.0, -600.0])
def test_g33_follows_the_revolutions_from_the_index(speed: float) -> None:
    motion, spindle = _thread_setup(speed)
    pitch = 1.5
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=pitch))
    ok(motion, move(0.0, 0.0, -30.0, vel=50.0))
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.0))
    errors = []

    def watch(motion: MotionController, spindle: SpindleModel) -> None:
        z = motion.carte_pos_cmd.z
        if spindle.index_pulses and -28.0 < z < -2.0:  # past the catch-up, before the end
            errors.append(abs(z + abs(spindle.revs) * pitch))

    run_until_done(motion, spindle, watch=watch)
    assert spindle.index_pulses == 1  # one index pulse started the thread
    assert errors and max(errors) < 0.01 * pitch  # Z followed the spindle
    assert motion.carte_pos_cmd.z == pytest.approx(-30.0)
    assert motion.errors == []


def test_g33_chain_keeps_the_phase_across_moves() -> None:
    motion, spindle = _thread_setup(600.0)
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=1.0))
    ok(motion, move(0.0, 0.0, -10.0, vel=50.0))
    ok(motion, move(0.0, 0.0, -20.0, vel=50.0))
    errors = []

    def watch(motion: MotionController, spindle: SpindleModel) -> None:
        z = motion.carte_pos_cmd.z
        if -18.0 < z < -2.0:
            errors.append(abs(z + spindle.revs))

    run_until_done(motion, spindle, watch=watch)
    assert spindle.index_pulses == 1 and max(errors) < 0.01
    assert motion.carte_pos_cmd.z == pytest.approx(-20.0)


def test_g95_feed_per_revolution_from_the_measured_speed() -> None:
    motion, spindle = _thread_setup(300.0)  # 5 rev/s
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.2, velocity_mode=1))
    ok(motion, move(10.0, vel=50.0))
    speeds = []
    run_until_done(motion, spindle, watch=lambda m, s: speeds.append(m.tp.vel))
    assert max(speeds) == pytest.approx(1.0)  # 0.2 mm/rev * 5 rev/s
    assert motion.carte_pos_cmd.x == pytest.approx(10.0)


def test_g96_speed_follows_the_radius_within_the_maximum() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    # 100 m/min at radius r (mm): 100000 / (2 pi r) rpm; at most 2000 rpm
    factor = 100_000 / (2 * math.pi)
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=2000.0, factor=factor, xoffset=0.0))
    ok(motion, move(20.0, rapid=True))
    run_until_done(motion, spindle)
    assert motion.spindles[0].speed_out == pytest.approx(factor / 20.0)
    ok(motion, move(1.0, rapid=True))
    run_until_done(motion, spindle)
    assert motion.spindles[0].speed_out == 2000.0


def test_g33_1_rigid_tap_goes_in_reverses_and_comes_back() -> None:
    motion, spindle = _thread_setup(600.0)
    ok(motion, move(5.0, 5.0, 0.0, rapid=True))
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=1.0))
    tap = emc.EMC_TRAJ_RIGID_TAP(vel=50.0, ini_maxvel=50.0, acc=500.0, scale=1.0)
    tap.pos.tran.x, tap.pos.tran.y, tap.pos.tran.z = 5.0, 5.0, -10.0
    ok(motion, tap)
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.0))
    ok(motion, move(6.0, 5.0, 0.0))
    seen = {"deepest": 0.0, "reversed": False}

    def watch(motion: MotionController, spindle: SpindleModel) -> None:
        seen["deepest"] = min(seen["deepest"], motion.carte_pos_cmd.z)
        seen["reversed"] |= motion.spindles[0].speed_out < 0

    run_until_done(motion, spindle, watch=watch)
    assert seen["reversed"] and motion.spindles[0].speed_out == 600.0
    # the tool follows the spindle while it reverses: 10 rev/s braked at 50 rev/s^2 is
    # one more revolution (1 mm) past the programmed depth, as on a real machine
    assert seen["deepest"] == pytest.approx(-11.0, abs=0.02)
    assert (motion.carte_pos_cmd.x, motion.carte_pos_cmd.z) == pytest.approx((6.0, 0.0))
    assert motion.errors == []


def test_rigid_tap_needs_position_synchronisation() -> None:
    motion = enabled_homed()
    tap = emc.EMC_TRAJ_RIGID_TAP(vel=50.0, ini_maxvel=50.0, acc=500.0, scale=1.0)
    tap.pos.tran.z = -10.0
    refused = motion.handle(tap)
    assert refused.endswith("rigid tapping needs spindle position synchronisation (G33.1)")


def test_feed_hold_waits_for_the_end_of_a_thread() -> None:
    motion, spindle = _thread_setup(600.0)
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=1.0))
    ok(motion, move(0.0, 0.0, -10.0, vel=50.0))
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=0.0))
    ok(motion, move(5.0, 0.0, -10.0))
    while motion.carte_pos_cmd.z > -2.0:
        run(motion, spindle, 1)
    ok(motion, emc.EMC_TRAJ_PAUSE())
    run(motion, spindle, 3000)
    assert motion.tp.is_paused
    assert (motion.carte_pos_cmd.x, motion.carte_pos_cmd.z) == pytest.approx((0.0, -10.0))
    ok(motion, emc.EMC_TRAJ_RESUME())
    run_until_done(motion, spindle)
    assert motion.carte_pos_cmd.x == pytest.approx(5.0)


def test_g33_waits_at_rest_for_the_index_and_abort_ends_the_wait() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    spindle.is_at_speed_forced = True  # a spindle that does not turn: no index pulse
    ok(motion, emc.EMC_TRAJ_SET_SPINDLESYNC(spindle=0, feed_per_revolution=1.0))
    ok(motion, move(0.0, 0.0, -10.0, vel=50.0))
    run(motion, spindle, 100)
    assert motion.tp.is_waiting_for_index and motion.spindles[0].is_index_enabled
    assert motion.carte_pos_cmd.z == 0.0 and not motion.is_in_position
    ok(motion, emc.EMC_TRAJ_ABORT())
    run(motion, spindle, 2)
    assert motion.is_in_position and not motion.spindles[0].is_index_enabled


def test_in_css_mode_a_feed_after_a_rapid_waits_for_at_speed() -> None:
    motion, spindle = enabled_homed(), SpindleModel()
    on = emc.EMC_SPINDLE_ON(spindle=0, speed=2000.0, factor=5000.0, wait_for_spindle_at_speed=0)
    ok(motion, on)
    ok(motion, move(20.0, rapid=True))
    ok(motion, move(10.0))
    spindle.is_at_speed_forced = False
    run(motion, spindle, 3000)
    assert motion.carte_pos_cmd.x == pytest.approx(20.0) and motion.tp.is_waiting_for_at_speed
    spindle.is_at_speed_forced = True
    run_until_done(motion, spindle)
    assert motion.carte_pos_cmd.x == pytest.approx(10.0)


@pytest.mark.parametrize(
    ("command", "expected"),
    [
        (emc.EMC_SPINDLE_ON(spindle=0, speed=10.0), 100.0),  # up to MIN_FORWARD
        (emc.EMC_SPINDLE_ON(spindle=0, speed=10_000.0), 1000.0),  # down to MAX_FORWARD
        (emc.EMC_SPINDLE_ON(spindle=0, speed=-10.0), -500.0),  # MIN_REVERSE
        (emc.EMC_SPINDLE_ON(spindle=0, speed=-10_000.0), -1500.0),  # MAX_REVERSE
        (emc.EMC_SPINDLE_ON(spindle=0, speed=700.0), 700.0),
        (emc.EMC_SPINDLE_ON(spindle=0, speed=0.0), 0.0),  # stopped is never clamped
    ],
)
def test_a_commanded_speed_is_clamped_to_the_spindle_limits(
    command: emc.EMC_SPINDLE_ON, expected: float
) -> None:
    """[SPINDLE_0] of LinuxCNC's tests/spindle_limits: 100..1000 forward, 500..1500 reverse."""
    motion = enabled_homed()
    limits = emc.EMC_SPINDLE_SET_PARAMS(
        spindle=0, max_forward=1000.0, min_forward=100.0, max_reverse=1500.0, min_reverse=500.0
    )
    ok(motion, limits)
    ok(motion, command)
    assert motion.spindles[0].speed == expected


def test_s_word_and_increase_stay_within_the_spindle_limits() -> None:
    motion = enabled_homed()
    limits = emc.EMC_SPINDLE_SET_PARAMS(
        spindle=0, max_forward=1000.0, min_forward=100.0, max_reverse=1500.0, min_reverse=500.0
    )
    ok(motion, limits)
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=-600.0))
    ok(motion, emc.EMC_SPINDLE_SPEED(spindle=0, speed=20.0))
    assert motion.spindles[0].speed == -500.0
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=950.0))
    ok(motion, emc.EMC_SPINDLE_INCREASE(spindle=0, speed=100.0))
    assert motion.spindles[0].speed == 1000.0


def test_negative_spindle_limits_are_refused() -> None:
    motion = enabled_homed()
    bad = emc.EMC_SPINDLE_SET_PARAMS(
        spindle=0, max_forward=1000.0, min_forward=-1.0, max_reverse=1.0, min_reverse=0.0
    )
    assert "speed limits must be >= 0" in str(motion.handle(bad))
    ok(motion, emc.EMC_SPINDLE_ON(spindle=0, speed=-5.0))
    assert motion.spindles[0].speed == -5.0  # the defaults still apply: no limits
