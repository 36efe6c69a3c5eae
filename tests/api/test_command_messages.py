"""Every command() method sends the EMC message LinuxCNC's sends, and checks its arguments."""

from __future__ import annotations

from typing import Any

import pytest

import cnc

Z_AND_X = {"offset": {"tran": {"x": 0.5, "y": 0.0, "z": 12.0}}}

# (call, message type, fields the message must have)
CASES: list[tuple[Any, str, dict[str, Any]]] = [
    (lambda c: c.state(cnc.STATE_ESTOP_RESET), "EMC_TASK_SET_STATE", {"state": 2}),
    (lambda c: c.mode(cnc.MODE_MANUAL), "EMC_TASK_SET_MODE", {"mode": 1}),
    (lambda c: c.mdi("G0 X1"), "EMC_TASK_PLAN_EXECUTE", {"command": "G0 X1"}),
    (lambda c: c.auto(cnc.AUTO_RUN, 7), "EMC_TASK_PLAN_RUN", {"line": 7}),
    (lambda c: c.auto(cnc.AUTO_PAUSE), "EMC_TASK_PLAN_PAUSE", {}),
    (lambda c: c.auto(cnc.AUTO_RESUME), "EMC_TASK_PLAN_RESUME", {}),
    (lambda c: c.auto(cnc.AUTO_STEP), "EMC_TASK_PLAN_STEP", {}),
    (lambda c: c.auto(cnc.AUTO_REVERSE), "EMC_TASK_PLAN_REVERSE", {}),
    (lambda c: c.auto(cnc.AUTO_FORWARD), "EMC_TASK_PLAN_FORWARD", {}),
    (lambda c: c.abort(), "EMC_TASK_ABORT", {}),
    (lambda c: c.reset_interpreter(), "EMC_TASK_PLAN_INIT", {}),
    (lambda c: c.task_plan_synch(), "EMC_TASK_PLAN_SYNCH", {}),
    (lambda c: c.set_optional_stop(1), "EMC_TASK_PLAN_SET_OPTIONAL_STOP", {"state": True}),
    (lambda c: c.set_block_delete(0), "EMC_TASK_PLAN_SET_BLOCK_DELETE", {"state": False}),
    (lambda c: c.debug(0x100), "EMC_SET_DEBUG", {"debug": 0x100}),
    (lambda c: c.home(-1), "EMC_JOINT_HOME", {"joint": -1}),
    (lambda c: c.unhome(2), "EMC_JOINT_UNHOME", {"joint": 2}),
    (lambda c: c.override_limits(), "EMC_JOINT_OVERRIDE_LIMITS", {"joint": 0}),
    (
        lambda c: c.set_min_limit(1, -10.5),
        "EMC_JOINT_SET_MIN_POSITION_LIMIT",
        {"joint": 1, "limit": -10.5},
    ),
    (
        lambda c: c.set_max_limit(2, 99),
        "EMC_JOINT_SET_MAX_POSITION_LIMIT",
        {"joint": 2, "limit": 99.0},
    ),
    (
        lambda c: c.jog(cnc.JOG_STOP, True, 3),
        "EMC_JOG_STOP",
        {"joint_or_axis": 3, "jjogmode": 1},
    ),
    (
        lambda c: c.jog(cnc.JOG_CONTINUOUS, False, 2, -5.0),
        "EMC_JOG_CONT",
        {"joint_or_axis": 2, "jjogmode": 0, "vel": -5.0},
    ),
    (
        lambda c: c.jog(cnc.JOG_INCREMENT, 1, 0, 10, 0.1),
        "EMC_JOG_INCR",
        {"joint_or_axis": 0, "jjogmode": 1, "vel": 10.0, "incr": 0.1},
    ),
    (lambda c: c.teleop_enable(1), "EMC_TRAJ_SET_TELEOP_ENABLE", {"enable": 1}),
    (
        lambda c: c.teleop_vector(1, -2, 3.5, 0, 0, 4),
        "EMC_TRAJ_SET_TELEOP_VECTOR",
        {"vector": {"tran": {"x": 1.0, "y": -2.0, "z": 3.5}, "a": 0.0, "b": 0.0, "c": 4.0}},
    ),
    (lambda c: c.traj_mode(cnc.TRAJ_MODE_FREE), "EMC_TRAJ_SET_MODE", {"mode": 1}),
    (lambda c: c.feedrate(1.5), "EMC_TRAJ_SET_SCALE", {"scale": 1.5}),
    (lambda c: c.rapidrate(0.25), "EMC_TRAJ_SET_RAPID_SCALE", {"scale": 0.25}),
    (lambda c: c.maxvel(20), "EMC_TRAJ_SET_MAX_VELOCITY", {"velocity": 20.0}),
    (
        lambda c: c.spindleoverride(0.8, 1),
        "EMC_TRAJ_SET_SPINDLE_SCALE",
        {"scale": 0.8, "spindle": 1},
    ),
    (lambda c: c.set_feed_override(1), "EMC_TRAJ_SET_FO_ENABLE", {"mode": 1}),
    (
        lambda c: c.set_spindle_override(0, 2),
        "EMC_TRAJ_SET_SO_ENABLE",
        {"mode": 0, "spindle": 2},
    ),
    (lambda c: c.set_feed_hold(1), "EMC_TRAJ_SET_FH_ENABLE", {"mode": 1}),
    (lambda c: c.set_adaptive_feed(1), "EMC_MOTION_ADAPTIVE", {"status": 1}),
    (
        lambda c: c.set_digital_output(3, 1),
        "EMC_MOTION_SET_DOUT",
        {"index": 3, "start": 1, "now": 1},
    ),
    (
        lambda c: c.set_analog_output(2, 4.5),
        "EMC_MOTION_SET_AOUT",
        {"index": 2, "start": 4.5, "now": 1},
    ),
    (
        lambda c: c.spindle(cnc.SPINDLE_FORWARD, 1000),
        "EMC_SPINDLE_ON",
        {"speed": 1000.0, "spindle": 0, "wait_for_spindle_at_speed": 0},
    ),
    (
        lambda c: c.spindle(cnc.SPINDLE_REVERSE, 666, 1, 1),
        "EMC_SPINDLE_ON",
        {"speed": -666.0, "spindle": 1, "wait_for_spindle_at_speed": 1},
    ),
    (lambda c: c.spindle(cnc.SPINDLE_OFF), "EMC_SPINDLE_OFF", {"spindle": 0}),
    (lambda c: c.spindle(cnc.SPINDLE_INCREASE, 2), "EMC_SPINDLE_INCREASE", {"spindle": 2}),
    (lambda c: c.spindle(cnc.SPINDLE_DECREASE), "EMC_SPINDLE_DECREASE", {"spindle": 0}),
    (lambda c: c.spindle(cnc.SPINDLE_CONSTANT, 1), "EMC_SPINDLE_CONSTANT", {"spindle": 1}),
    (lambda c: c.brake(cnc.BRAKE_ENGAGE), "EMC_SPINDLE_BRAKE_ENGAGE", {"spindle": 0}),
    (lambda c: c.brake(cnc.BRAKE_RELEASE, 1), "EMC_SPINDLE_BRAKE_RELEASE", {"spindle": 1}),
    (lambda c: c.flood(cnc.FLOOD_ON), "EMC_COOLANT_FLOOD_ON", {}),
    (lambda c: c.flood(cnc.FLOOD_OFF), "EMC_COOLANT_FLOOD_OFF", {}),
    (lambda c: c.mist(cnc.MIST_ON), "EMC_COOLANT_MIST_ON", {}),
    (lambda c: c.mist(cnc.MIST_OFF), "EMC_COOLANT_MIST_OFF", {}),
    (
        lambda c: c.tool_offset(5, 12.0, 0.5, 6.0, 10.0, 20.0, 3),
        "EMC_TOOL_SET_OFFSET",
        {"toolno": 5, "diameter": 6.0, "frontangle": 10.0, "backangle": 20.0, "orientation": 3}
        | Z_AND_X,
    ),
    (lambda c: c.load_tool_table(), "EMC_TOOL_LOAD_TOOL_TABLE", {"file": ""}),
    (lambda c: c.error_msg("oops"), "EMC_OPERATOR_ERROR", {"id": 0, "error": "oops"}),
    (lambda c: c.text_msg("note"), "EMC_OPERATOR_TEXT", {"id": 0, "text": "note"}),
    (lambda c: c.display_msg("look"), "EMC_OPERATOR_DISPLAY", {"id": 0, "display": "look"}),
]


def is_subset(expected: dict[str, Any], actual: dict[str, Any]) -> bool:
    for key, value in expected.items():
        if isinstance(value, dict):
            if not is_subset(value, actual[key]):
                return False
        elif actual[key] != pytest.approx(value):
            return False
    return True


def test_each_method_sends_linuxcncs_message(fake_task) -> None:
    task = fake_task()
    c = cnc.command()
    for call, name, fields in CASES:
        call(c)
        received = task.next_command()
        assert received["type"] == name, name
        assert is_subset(fields, received["fields"]), (name, received["fields"])
        assert received["fields"]["serial_number"] == c.serial


def test_program_open_closes_the_open_program_first(fake_task) -> None:
    task = fake_task()
    cnc.command().program_open("/tmp/part.ngc")
    assert task.next_command()["type"] == "EMC_TASK_PLAN_CLOSE"
    opened = task.next_command()
    assert (opened["type"], opened["fields"]["file"]) == ("EMC_TASK_PLAN_OPEN", "/tmp/part.ngc")


def test_operator_messages_are_cut_to_254_bytes(fake_task) -> None:
    task = fake_task()
    cnc.command().error_msg("x" * 300)
    assert task.next_command()["fields"]["error"] == "x" * 254


BAD_CALLS = [
    (lambda c: c.state(9), ValueError, "Machine state should be"),
    (lambda c: c.mode(0), ValueError, "Mode should be"),
    (lambda c: c.mode(1.0), TypeError, None),
    (lambda c: c.mdi("G1" * 128), ValueError, "MDI commands limited to 254"),
    (lambda c: c.mdi(5), TypeError, None),
    (lambda c: c.program_open("a" * 255), ValueError, "File name limited to 254"),
    (lambda c: c.auto(cnc.AUTO_RUN), cnc.error, "Unexpected argument '0'"),
    (lambda c: c.auto(9), cnc.error, "Unexpected argument '9'"),
    (lambda c: c.auto(cnc.AUTO_PAUSE, 3), TypeError, None),
    (lambda c: c.jog(cnc.JOG_STOP, 0, 1, 5.0), TypeError, r"takes 3 arguments \(4 given\)"),
    (lambda c: c.jog(cnc.JOG_CONTINUOUS, 0, 1), TypeError, r"takes 4 arguments \(3 given\)"),
    (lambda c: c.jog(cnc.JOG_INCREMENT, 0, 1, 5.0), TypeError, r"takes 5 arguments"),
    (lambda c: c.jog(7, 0, 1), TypeError, "first argument must be JOG_xxx"),
    (lambda c: c.spindle(5), ValueError, "Spindle direction should be"),
    (lambda c: c.flood(2), ValueError, "FLOOD should be"),
    (lambda c: c.mist(-1), ValueError, "Mist should be"),
    (lambda c: c.brake(3), ValueError, "BRAKE should be"),
    (lambda c: c.feedrate("fast"), TypeError, None),
    (lambda c: c.set_digital_output(256, 1), OverflowError, None),
    (lambda c: c.set_feed_hold(-1), OverflowError, None),
    (lambda c: c.wait_complete("soon"), TypeError, None),
]


@pytest.mark.parametrize(("call", "exception", "match"), BAD_CALLS)
def test_bad_arguments_are_refused_before_sending(call, exception, match) -> None:
    # No controller at all: a refused call must fail on its arguments, not on the connection.
    with pytest.raises(exception, match=match):
        call(cnc.command())
