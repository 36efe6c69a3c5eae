"""halui's logic on fakes: buttons act on rising edges, inputs on change, outputs mirror the
status every cycle, MDI buttons keep task's mode rules (``man 1 halui``, LinuxCNC 2.9)."""

from __future__ import annotations

from collections import namedtuple

import pytest

from cnc.api import constants as c
from cnc.api import error
from cnc.halui.config import HaluiConfig
from tests.halui.fakes import Rig, joint_status

Tool = namedtuple("Tool", "id diameter")


@pytest.fixture
def rig() -> Rig:
    return Rig()


# ------------------------------------------------------------------ edges
def test_a_held_button_acts_once_and_again_after_release(rig: Rig) -> None:
    main = rig.pins.main
    main.estop_reset = True
    assert rig.cycle() == [("state", c.STATE_ESTOP_RESET)]
    assert rig.cycle() == []  # still held: nothing more
    main.estop_reset = False
    assert rig.cycle() == []  # the falling edge does nothing
    main.estop_reset = True
    assert rig.cycle() == [("state", c.STATE_ESTOP_RESET)]


def test_a_button_high_at_start_acts_at_the_first_cycle(rig: Rig) -> None:
    rig.pins.main.machine_on = True  # e.g. netted to a switch already on
    assert rig.cycle() == [("state", c.STATE_ON)]


def test_nothing_is_sent_or_mirrored_while_the_controller_is_down(rig: Rig) -> None:
    def poll() -> None:
        raise error("the controller is not running")

    rig.stat.poll = poll
    rig.pins.main.machine_on = True
    with pytest.raises(error):
        rig.halui.step()
    assert rig.command.take() == []
    del rig.stat.poll  # the controller is back: the held button acts now
    assert rig.cycle() == [("state", c.STATE_ON)]


@pytest.mark.parametrize(
    ("attr", "command"),
    [
        ("machine_off", ("state", c.STATE_OFF)),
        ("estop_activate", ("state", c.STATE_ESTOP)),
        ("mode_mdi", ("mode", c.MODE_MDI)),
        ("mode_auto", ("mode", c.MODE_AUTO)),
        ("mode_teleop", ("teleop_enable", 1)),
        ("mode_joint", ("teleop_enable", 0)),
        ("mist_on", ("mist", c.MIST_ON)),
        ("flood_off", ("flood", c.FLOOD_OFF)),
        ("lube_on", ("lube", True)),
        ("lube_off", ("lube", False)),
        ("program_pause", ("auto", c.AUTO_PAUSE)),
        ("program_resume", ("auto", c.AUTO_RESUME)),
        ("program_step", ("auto", c.AUTO_STEP)),
        ("program_stop", ("abort",)),
        ("abort", ("abort",)),
        ("optional_stop_on", ("set_optional_stop", 1)),
        ("block_delete_off", ("set_block_delete", 0)),
    ],
)
def test_each_button_sends_its_command(rig: Rig, attr: str, command: tuple) -> None:
    assert rig.press(rig.pins.main, attr) == [command]


def test_a_mode_button_for_the_mode_task_is_in_sends_nothing(rig: Rig) -> None:
    assert rig.press(rig.pins.main, "mode_manual") == []


def test_program_run_needs_an_open_program_and_switches_to_auto_first(rig: Rig) -> None:
    assert rig.press(rig.pins.main, "program_run") == []
    rig.stat.file = "/tmp/part.ngc"
    assert rig.press(rig.pins.main, "program_run") == [
        ("mode", c.MODE_AUTO),
        ("auto", c.AUTO_RUN, 0),
    ]


def test_homing_all_one_and_the_selected_joint(rig: Rig) -> None:
    assert rig.press(rig.pins.home_all, "home_all") == [("home", -1)]
    assert rig.press(rig.pins.joints[2], "home") == [("home", 2)]
    assert rig.press(rig.pins.joints[1], "unhome") == [("unhome", 1)]
    rig.press(rig.pins.joints[1], "select")
    assert rig.pins.main.joint_selected == 1
    assert [j.is_selected for j in rig.pins.joints] == [False, True, False]
    assert rig.press(rig.pins.selected_joint, "home") == [("home", 1)]


def test_home_all_exists_only_with_a_homing_sequence() -> None:
    rig = Rig(HaluiConfig(ini_path="test.ini", has_home_all=False))
    assert rig.pins.home_all is None


# ------------------------------------------------------------------ overrides
def test_feed_override_counts_are_relative_to_the_current_value(rig: Rig) -> None:
    fo = rig.pins.feed_override
    rig.cycle()  # mirrors the status: value 1.0
    rig.stat.feedrate = 0.5  # task took another override meanwhile
    rig.cycle()
    fo.counts = 3  # scale 0.1 by default
    assert rig.cycle() == [("feedrate", pytest.approx(0.8))]
    assert rig.cycle() == []  # counts unchanged


def test_feed_override_direct_value_is_counts_times_scale(rig: Rig) -> None:
    fo = rig.pins.feed_override
    fo.direct_value, fo.scale = True, 0.01
    fo.counts = 75
    assert rig.cycle() == [("feedrate", pytest.approx(0.75))]


def test_counts_change_nothing_while_counting_is_disabled(rig: Rig) -> None:
    fo = rig.pins.feed_override
    rig.stat.feedrate = 0.5
    fo.count_enable = False
    fo.counts = 4
    assert rig.cycle() == []
    fo.count_enable = True  # the counts moved while disabled are not caught up on
    assert rig.cycle() == []
    fo.counts = 5
    assert rig.cycle() == [("feedrate", pytest.approx(0.6))]


def test_overrides_stay_within_their_limits() -> None:
    rig = Rig(HaluiConfig(ini_path="t.ini", max_feed_override=1.2, max_spindle_override=1.5))
    rig.cycle()
    rig.pins.feed_override.counts = 50
    rig.pins.rapid_override.counts = 50
    rig.pins.spindle_overrides[0].counts = 50
    rig.pins.max_velocity.counts, rig.pins.max_velocity.scale = -100, 1.0
    assert sorted(rig.cycle()) == [
        ("feedrate", 1.2),
        ("maxvel", 0.0),
        ("rapidrate", 1.0),
        ("spindleoverride", 1.5, 0),
    ]


def test_increase_decrease_and_reset_buttons(rig: Rig) -> None:
    rig.cycle()
    fo = rig.pins.feed_override
    assert rig.press(fo, "decrease") == [("feedrate", pytest.approx(0.9))]
    rig.stat.feedrate = 0.9
    rig.cycle()
    assert rig.press(fo, "decrease") == [("feedrate", pytest.approx(0.8))]
    assert rig.press(fo, "reset") == [("feedrate", 1.0)]
    assert rig.press(rig.pins.max_velocity, "increase") == [("maxvel", 1.0)]  # clamped


def test_a_non_finite_override_is_not_sent(rig: Rig) -> None:
    rig.pins.feed_override.direct_value = True
    rig.pins.feed_override.scale = float("nan")
    rig.pins.feed_override.counts = 1
    assert rig.cycle() == []


# ------------------------------------------------------------------ spindle
def test_spindle_start_reverse_and_stop_use_the_programmed_speed(rig: Rig) -> None:
    spindle = rig.pins.spindles[0]
    assert rig.press(spindle, "start") == [("spindle", c.SPINDLE_FORWARD, 1.0, 0)]
    rig.stat.settings = (0.0, 100.0, -1200.0)
    assert rig.press(spindle, "reverse") == [("spindle", c.SPINDLE_REVERSE, 1200.0, 0)]
    assert rig.press(spindle, "stop") == [("spindle", c.SPINDLE_OFF, 0)]
    assert rig.press(spindle, "brake_off") == [("brake", c.BRAKE_RELEASE, 0)]


def test_spindle_increase_acts_while_held(rig: Rig) -> None:
    assert rig.press(rig.pins.spindles[0], "increase") == [
        ("spindle", c.SPINDLE_INCREASE, 0),
        ("spindle", c.SPINDLE_CONSTANT, 0),
    ]


# ------------------------------------------------------------------ jogging
def machine_on(rig: Rig) -> None:
    rig.stat.task_state = c.STATE_ON
    rig.pins.main.joint_jog_speed = 600.0  # units per minute
    rig.pins.main.axis_jog_speed = 300.0
    rig.cycle()


def test_a_held_jog_button_jogs_until_released(rig: Rig) -> None:
    machine_on(rig)
    joint = rig.pins.joints[1]
    joint.minus = True
    assert rig.cycle() == [("jog", c.JOG_CONTINUOUS, 1, 1, -10.0)]
    assert rig.cycle() == []
    joint.minus = False
    assert rig.cycle() == [("jog", c.JOG_STOP, 1, 1)]


def test_a_new_jog_speed_restarts_running_jogs(rig: Rig) -> None:
    machine_on(rig)
    rig.pins.joints[0].plus = True
    rig.cycle()
    rig.pins.main.joint_jog_speed = 1200.0
    assert rig.cycle() == [("jog", c.JOG_CONTINUOUS, 1, 0, 20.0)]


def test_analog_jogging_has_a_deadband(rig: Rig) -> None:
    machine_on(rig)
    joint = rig.pins.joints[2]
    joint.analog = 0.1  # inside the 0.2 deadband
    assert rig.cycle() == [("jog", c.JOG_STOP, 1, 2)]
    joint.analog = -0.5
    assert rig.cycle() == [("jog", c.JOG_CONTINUOUS, 1, 2, -5.0)]


def test_increment_jogs(rig: Rig) -> None:
    machine_on(rig)
    joint = rig.pins.joints[0]
    joint.increment = 0.25
    assert rig.press(joint, "increment_minus") == [("jog", c.JOG_INCREMENT, 1, 0, 10.0, -0.25)]


def test_jogs_need_the_machine_on(rig: Rig) -> None:
    rig.pins.main.joint_jog_speed = 600.0
    assert rig.press(rig.pins.joints[0], "increment_plus") == []
    rig.pins.joints[0].plus = True
    assert rig.cycle() == []


def test_joints_jog_in_joint_mode_and_axes_in_teleop_mode(rig: Rig) -> None:
    machine_on(rig)
    assert rig.press(rig.pins.axes["y"], "increment_plus") == []
    rig.stat.motion_mode = c.TRAJ_MODE_TELEOP
    rig.pins.axes["y"].increment = 1.0
    assert rig.press(rig.pins.axes["y"], "increment_plus") == [
        ("jog", c.JOG_INCREMENT, 0, 1, 5.0, 1.0)
    ]
    assert rig.press(rig.pins.joints[0], "increment_plus") == []


def test_a_jog_on_the_selected_joint_follows_the_selection(rig: Rig) -> None:
    machine_on(rig)
    rig.pins.selected_joint.plus = True
    assert rig.cycle() == [("jog", c.JOG_CONTINUOUS, 1, 0, 10.0)]  # joint 0 at start
    rig.pins.joints[2].select = True
    assert rig.cycle() == [
        ("jog", c.JOG_STOP, 1, 0),
        ("jog", c.JOG_STOP, 1, 1),
        ("jog", c.JOG_CONTINUOUS, 1, 2, 10.0),
    ]
    rig.pins.selected_joint.plus = False
    assert rig.cycle() == [("jog", c.JOG_STOP, 1, 2)]


def test_the_first_axis_is_selected_at_start_and_selection_moves() -> None:
    rig = Rig(HaluiConfig(ini_path="t.ini", axes="xz"))
    assert rig.pins.axes["x"].is_selected and not rig.pins.axes["z"].is_selected
    rig.press(rig.pins.axes["z"], "select")
    assert rig.pins.main.axis_selected == 2  # the index in XYZABCUVW
    assert not rig.pins.axes["x"].is_selected and rig.pins.axes["z"].is_selected


# ------------------------------------------------------------------ MDI buttons
def mdi_rig() -> Rig:
    rig = Rig(HaluiConfig(ini_path="t.ini", mdi_commands=("G0 X10", "M7")))
    rig.stat.task_state = c.STATE_ON
    return rig


def test_an_mdi_button_switches_to_mdi_runs_the_line_then_switches_back() -> None:
    rig = mdi_rig()
    rig.pins.main.mdi_command[0] = True
    assert rig.cycle() == [("mode", c.MODE_MDI), ("mdi", "G0 X10")]
    assert rig.cycle() == []  # the line runs: task stays in MDI mode
    rig.stat.state = c.RCS_DONE
    assert rig.cycle() == [("mode", c.MODE_MANUAL)]
    assert rig.cycle() == []


def test_mdi_buttons_in_a_row_go_back_to_the_first_mode_after_the_last_line() -> None:
    rig = mdi_rig()
    rig.stat.task_mode = c.MODE_AUTO
    rig.pins.main.mdi_command[0] = True
    assert rig.cycle() == [("mode", c.MODE_MDI), ("mdi", "G0 X10")]
    rig.pins.main.mdi_command[1] = True  # while the first still runs
    assert rig.cycle() == [("mdi", "M7")]
    rig.stat.state = c.RCS_DONE
    assert rig.cycle() == [("mode", c.MODE_AUTO)]


def test_after_a_failed_mdi_line_the_mode_comes_back_too() -> None:
    rig = mdi_rig()
    rig.pins.main.mdi_command[1] = True
    rig.cycle()
    rig.stat.state = c.RCS_ERROR
    assert rig.cycle() == [("mode", c.MODE_MANUAL)]


def test_an_mdi_button_in_mdi_mode_leaves_the_mode_alone() -> None:
    rig = mdi_rig()
    rig.stat.task_mode = c.MODE_MDI
    rig.pins.main.mdi_command[1] = True
    assert rig.cycle() == [("mdi", "M7")]
    rig.stat.state = c.RCS_DONE
    assert rig.cycle() == []


def test_an_mdi_line_is_not_sent_when_task_refuses_mdi_mode(
    capsys: pytest.CaptureFixture[str],
) -> None:
    rig = mdi_rig()
    rig.command.is_mode_refused = True  # e.g. a program runs
    rig.pins.main.mdi_command[0] = True
    assert rig.cycle() == [("mode", c.MODE_MDI)]
    assert "mdi-command-00 not sent" in capsys.readouterr().err


# ------------------------------------------------------------------ status -> pins
def test_state_mode_and_program_pins_mirror_the_status(rig: Rig) -> None:
    main = rig.pins.main
    rig.cycle()
    assert main.is_estop_activated and not main.is_machine_on
    assert main.is_mode_manual and main.is_mode_joint and main.is_program_idle
    rig.stat.task_state = c.STATE_ON
    rig.stat.task_mode = c.MODE_AUTO
    rig.stat.motion_mode = c.TRAJ_MODE_COORD
    rig.stat.interp_state = c.INTERP_WAITING
    rig.stat.mist, rig.stat.lube, rig.stat.optional_stop = True, True, True
    rig.cycle()
    assert main.is_machine_on and not main.is_estop_activated
    assert main.is_mode_auto and not (main.is_mode_manual or main.is_mode_mdi)
    assert not (main.is_mode_joint or main.is_mode_teleop)
    assert main.is_program_running and not (main.is_program_idle or main.is_program_paused)
    assert main.is_mist_on and main.is_lube_on and not main.is_flood_on
    assert main.is_optional_stop_on and not main.is_block_delete_on
    rig.stat.interp_state = c.INTERP_PAUSED
    rig.cycle()
    assert main.is_program_paused and not main.is_program_running


def test_joint_and_selected_joint_pins_mirror_the_joints(rig: Rig) -> None:
    rig.stat.joint[1] = joint_status(homed=1, max_soft_limit=1, fault=1)
    rig.cycle()
    joint = rig.pins.joints[1]
    assert joint.is_homed and joint.on_soft_max_limit and joint.has_fault
    assert not (joint.on_soft_min_limit or joint.on_hard_max_limit or joint.override_limits)
    assert not rig.pins.selected_joint.is_homed  # joint 0 is selected
    rig.press(joint, "select")
    assert rig.pins.selected_joint.is_homed and rig.pins.selected_joint.has_fault


def test_values_spindle_and_tool_pins(rig: Rig) -> None:
    rig.stat.feedrate, rig.stat.rapidrate, rig.stat.max_velocity = 0.7, 0.3, 25.0
    rig.stat.spindle[0] = {"enabled": 1, "direction": -1, "brake": 0, "override": 0.9}
    rig.stat.tool_in_spindle = 4
    rig.stat.tool_table = (Tool(4, 6.0), Tool(3, 2.0), Tool(4, 6.0))
    rig.stat.tool_offset = (0.0, 0.0, 12.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    rig.cycle()
    pins = rig.pins
    assert (pins.feed_override.value, pins.rapid_override.value) == (0.7, 0.3)
    assert pins.max_velocity.value == 25.0
    spindle = pins.spindles[0]
    assert spindle.is_on and spindle.runs_backward and not spindle.runs_forward
    assert not spindle.brake_is_on and pins.spindle_overrides[0].value == 0.9
    assert pins.main.tool_number == 4 and pins.main.tool_diameter == 6.0
    assert (pins.tool_offset.z, pins.tool_offset.w, pins.tool_offset.x) == (12.5, 1.0, 0.0)
    rig.stat.tool_in_spindle = 9  # not in the table
    rig.cycle()
    assert pins.main.tool_diameter == 0.0


def test_units_per_mm_is_set_once_task_has_set_it(rig: Rig) -> None:
    rig.stat.linear_units = 0.0
    rig.cycle()
    assert rig.pins.main.units_per_mm == 0
    rig.stat.linear_units = 1 / 25.4
    rig.cycle()
    rig.stat.linear_units = 1.0
    rig.cycle()
    assert rig.pins.main.units_per_mm == pytest.approx(1 / 25.4)


def test_axis_positions_machine_and_relative(rig: Rig) -> None:
    rig.stat.position = (10.0, 20.0, 30.0, 0, 0, 0, 0, 0, 0)
    rig.stat.actual_position = (11.0, 21.0, 31.0, 0, 0, 0, 0, 0, 0)
    rig.stat.g5x_offset = (1.0, 1.0, 1.0, 0, 0, 0, 0, 0, 0)
    rig.stat.g92_offset = (0.5, 0.0, 2.0, 0, 0, 0, 0, 0, 0)
    rig.stat.tool_offset = (0.0, 0.0, 5.0, 0, 0, 0, 0, 0, 0)
    rig.stat.rotation_xy = 90.0  # the work offset turned a quarter turn
    rig.cycle()
    x, y, z = (rig.pins.axes[letter] for letter in "xyz")
    assert (x.pos_commanded, y.pos_commanded, z.pos_commanded) == (10.0, 20.0, 30.0)
    assert (x.pos_feedback, z.pos_feedback) == (11.0, 31.0)
    # (10, 20) away from the G5x origin, seen in a frame turned by 90 degrees: (20, -10)
    assert x.pos_relative == pytest.approx(20.0 - 0.5)
    assert y.pos_relative == pytest.approx(-10.0)
    assert z.pos_relative == pytest.approx(31.0 - 1.0 - 2.0 - 5.0)


def test_a_command_that_fails_unexpectedly_is_said_and_halui_goes_on(rig: Rig, capsys) -> None:
    def mist(value: int) -> None:
        raise ZeroDivisionError("a bug")

    rig.command.mist = mist
    main = rig.pins.main
    main.mist_on = main.flood_on = True  # mist acts first, then flood
    assert rig.cycle() == [("flood", c.FLOOD_ON)]
    said = capsys.readouterr().err
    assert "halui: internal error in mist_on: ZeroDivisionError: a bug" in said


def test_every_main_button_has_one_handler(rig: Rig) -> None:
    from cnc.halui.core import MAIN_BUTTONS

    assert sorted(rig.halui.handlers) == sorted(MAIN_BUTTONS)
