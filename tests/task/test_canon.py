"""Task's canon (task/canon.py): canonical calls -> NML messages in machine units."""

from __future__ import annotations

import math
from pathlib import Path
from types import UnionType

import pytest

from iocontrol.tooldata import ToolDataWriter
from iocontrol.tooltable import ToolTable
from nml import emc
from task.canon import CanonSetup, TaskCanon
from task.interp import canon as C  # noqa: N812  (C.PLANE_XY reads like CANON_PLANE_XY)
from task.interp.errors import INTERP_ENDFILE, INTERP_EXECUTE_FINISH, INTERP_EXIT
from task.interp.interp import Interpreter

INF = math.inf


def make_setup(
    units: str = "mm", vel: list[float] | None = None, acc: list[float] | None = None, **extra
) -> CanonSetup:
    """An XYZA machine (mask 0b1111); X/Y/Z/A limits 100/50/20/360 per s, ten times that
    per s^2 unless given."""
    vel = vel or [100.0, 50.0, 20.0, 360.0, INF, INF, INF, INF, INF]
    acc = acc or [10 * v for v in vel]
    return CanonSetup(units, 0b1111, vel, acc, 150.0, 1500.0, **extra)


def make_canon(units: str = "mm", **extra) -> TaskCanon:
    canon = TaskCanon(make_setup(units, **extra))
    canon.out.clear()  # the start-up term condition
    return canon


def messages(canon: TaskCanon, kind: type | UnionType | None = None) -> list:
    return [m for m in canon.out if kind is None or isinstance(m, kind)]


def names(canon: TaskCanon) -> list[str]:
    return [type(m).__name__ for m in canon.out]


def pose(p: emc.EmcPose) -> list[float]:
    return [p.tran.x, p.tran.y, p.tran.z, p.a, p.b, p.c, p.u, p.v, p.w]


def xyz(p: emc.PmCartesian) -> list[float]:
    return [p.x, p.y, p.z]


def approx(values, abs_tol: float = 1e-9):
    return pytest.approx(list(values), abs=abs_tol)


def last_move(canon: TaskCanon):
    return messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1]


# ============================================================ straight moves, offsets, units
def test_start_up_blending_tolerance_is_a_thousandth_of_an_inch() -> None:
    msg = TaskCanon(make_setup("mm")).out[0]
    assert isinstance(msg, emc.EMC_TRAJ_SET_TERM_COND)
    assert msg.cond == emc.EMC_TRAJ_TERM_COND.BLEND
    assert msg.tolerance == pytest.approx(0.0254)
    assert TaskCanon(make_setup("inch")).out[0].tolerance == pytest.approx(0.001)


def test_traverse_is_in_machine_coordinates_with_all_offsets_and_rotation() -> None:
    canon = make_canon()
    canon.SET_G5X_OFFSET(2, 10, 20, 30, 0, 0, 0, 0, 0, 0)
    canon.SET_G92_OFFSET(1, 2, 3, 0, 0, 0, 0, 0, 0)
    canon.SET_XY_ROTATION(90)
    canon.USE_TOOL_LENGTH_OFFSET([0, 0, 5, 0, 0, 0, 0, 0, 0])
    canon.STRAIGHT_TRAVERSE(7, 1, 0, 0, 0, 0, 0)
    # (1, 0, 0) + G92 = (2, 2, 3); turned 90 degrees: (-2, 2, 3); + G5x; + tool length
    assert pose(last_move(canon).end) == approx([8, 22, 38, 0, 0, 0, 0, 0, 0])
    assert last_move(canon).type == emc.EMC_MOTION_TYPE.TRAVERSE
    g5x = messages(canon, emc.EMC_TRAJ_SET_G5X)[0]
    assert g5x.g5x_index == 2
    assert pose(g5x.origin)[:3] == approx([10, 20, 30])
    assert pose(messages(canon, emc.EMC_TRAJ_SET_G92)[0].origin)[:3] == approx([1, 2, 3])
    assert messages(canon, emc.EMC_TRAJ_SET_ROTATION)[0].rotation == 90
    assert pose(messages(canon, emc.EMC_TRAJ_SET_OFFSET)[0].offset)[2] == 5


def test_inch_program_on_a_mm_machine() -> None:
    canon = make_canon("mm")
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
    canon.SET_G5X_OFFSET(1, 1, 0, 0, 0, 0, 0, 0, 0, 0)
    canon.STRAIGHT_TRAVERSE(1, 1, 2, 0, 45, 0, 0)
    # lengths scale by 25.4, angles do not
    assert pose(last_move(canon).end) == approx([50.8, 50.8, 0, 45, 0, 0, 0, 0, 0])
    assert pose(messages(canon, emc.EMC_TRAJ_SET_G5X)[0].origin)[0] == pytest.approx(25.4)
    canon.SET_FEED_RATE(10)  # inches per minute
    canon.STRAIGHT_FEED(2, 2, 2, 0, 45, 0, 0)
    canon.FINISH()
    assert last_move(canon).vel == pytest.approx(10 * 25.4 / 60)
    assert canon.GET_EXTERNAL_FEED_RATE() == pytest.approx(10)


def test_mm_program_on_an_inch_machine() -> None:
    canon = make_canon("inch")
    assert canon.GET_EXTERNAL_LENGTH_UNIT_TYPE() == C.UNITS_INCHES
    assert canon.GET_EXTERNAL_LENGTH_UNITS() == pytest.approx(1 / 25.4)
    canon.USE_LENGTH_UNITS(C.UNITS_MM)
    canon.USE_TOOL_LENGTH_OFFSET([0, 0, 25.4, 0, 0, 0, 0, 0, 0])
    canon.STRAIGHT_TRAVERSE(1, 25.4, 0, 0, 0, 0, 0)
    assert pose(last_move(canon).end)[:3] == approx([1, 0, 1])
    assert pose(messages(canon, emc.EMC_TRAJ_SET_OFFSET)[0].offset)[2] == pytest.approx(1)
    assert canon.GET_EXTERNAL_TOOL_LENGTH_OFFSET()[2] == pytest.approx(25.4)


def test_feed_velocity_is_limited_per_axis_along_a_diagonal() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(60000)  # 1000 mm/s: faster than any axis
    canon.STRAIGHT_FEED(1, 10, 10, 0, 0, 0, 0)
    canon.FINISH()
    move = last_move(canon)
    # Y (50/s, 500/s^2) needs the longest: 10 / 50 s; the path is 10 * sqrt(2) long
    assert move.vel == pytest.approx(10 * math.sqrt(2) / (10 / 50))
    assert move.ini_maxvel == pytest.approx(move.vel)
    assert move.acc == pytest.approx(10 * math.sqrt(2) / (10 / 500))
    assert move.type == emc.EMC_MOTION_TYPE.FEED


def test_feed_runs_at_the_feed_rate_below_the_axis_limits() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(600)
    canon.STRAIGHT_FEED(1, 10, 0, 0, 0, 0, 0)
    canon.FINISH()
    assert last_move(canon).vel == pytest.approx(10)
    assert last_move(canon).ini_maxvel == pytest.approx(100)


def test_rapids_run_at_the_axis_limits() -> None:
    canon = make_canon()
    canon.STRAIGHT_TRAVERSE(1, 0, 0, -5, 0, 0, 0)
    assert last_move(canon).vel == pytest.approx(20)  # Z alone
    assert last_move(canon).acc == pytest.approx(200)
    canon.STRAIGHT_TRAVERSE(2, 0, 0, -5, 90, 0, 0)
    assert last_move(canon).vel == pytest.approx(360)  # A alone: degrees per second
    # X with A: the linear path length over the time the slower A needs
    canon.STRAIGHT_TRAVERSE(3, 10, 0, -5, 450, 0, 0)
    assert last_move(canon).vel == pytest.approx(10 / (360 / 360))


def test_unlimited_axes_move_at_the_trajectory_limits() -> None:
    canon = make_canon(vel=[INF] * 9, acc=[INF] * 9)
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    assert (last_move(canon).vel, last_move(canon).acc) == (150.0, 1500.0)


def test_moves_to_nowhere_and_on_absent_axes_are_not_sent() -> None:
    canon = make_canon()
    canon.STRAIGHT_TRAVERSE(1, 0, 0, 0, 0, 0, 0)
    canon.STRAIGHT_TRAVERSE(2, 0, 0, 0, 0, 30, 0)  # B is not in the axis mask
    assert messages(canon, emc.EMC_TRAJ_LINEAR_MOVE) == []


def test_motion_id_is_queued_only_when_the_line_changes() -> None:
    canon = make_canon()
    canon.STRAIGHT_TRAVERSE(5, 1, 0, 0, 0, 0, 0)
    canon.STRAIGHT_TRAVERSE(5, 2, 0, 0, 0, 0, 0)
    canon.STRAIGHT_TRAVERSE(6, 3, 0, 0, 0, 0, 0)
    # (a move's own id stays 0 here: task stamps it when it sends the move)
    ids = [(type(m).__name__, getattr(m, "id", None)) for m in canon.out]
    assert ids == [
        ("EMC_TRAJ_SET_MOTION_ID", 5),
        ("EMC_TRAJ_LINEAR_MOVE", 0),
        ("EMC_TRAJ_LINEAR_MOVE", 0),
        ("EMC_TRAJ_SET_MOTION_ID", 6),
        ("EMC_TRAJ_LINEAR_MOVE", 0),
    ]
    canon.ON_RESET()  # after an abort the line is announced again
    canon.STRAIGHT_TRAVERSE(6, 4, 0, 0, 0, 0, 0)
    assert isinstance(canon.out[-2], emc.EMC_TRAJ_SET_MOTION_ID)


def test_feed_is_queued_at_once_without_naive_cam() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(600)
    canon.STRAIGHT_FEED(1, 10, 0, 0, 0, 0, 0)
    canon.DWELL(1.5)
    assert names(canon) == ["EMC_TRAJ_SET_MOTION_ID", "EMC_TRAJ_LINEAR_MOVE", "EMC_TRAJ_DELAY"]
    assert canon.out[-1].delay == 1.5


def test_naive_cam_holds_feeds_until_the_next_call_in_program_order() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(600)
    canon.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, 0.1)
    canon.SET_NAIVECAM_TOLERANCE(0.01)
    canon.out.clear()
    canon.STRAIGHT_FEED(1, 10, 0, 0, 0, 0, 0)
    assert messages(canon, emc.EMC_TRAJ_LINEAR_MOVE) == []
    canon.DWELL(1.5)
    assert names(canon) == ["EMC_TRAJ_SET_MOTION_ID", "EMC_TRAJ_LINEAR_MOVE", "EMC_TRAJ_DELAY"]
    canon.STRAIGHT_FEED(2, 20, 0, 0, 0, 0, 0)
    canon.FINISH()
    assert len(messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)) == 2


def test_naive_cam_joins_nearly_collinear_feeds() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(600)
    canon.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, 0.1)
    canon.SET_NAIVECAM_TOLERANCE(0.01)
    canon.STRAIGHT_FEED(1, 1, 0.001, 0, 0, 0, 0)
    canon.STRAIGHT_FEED(2, 2, 0.0, 0, 0, 0, 0)
    canon.STRAIGHT_FEED(3, 3, 0.002, 0, 0, 0, 0)
    canon.FINISH()
    moves = messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)
    assert len(moves) == 1
    assert pose(moves[0].end)[:2] == approx([3, 0.002])
    assert messages(canon, emc.EMC_TRAJ_SET_MOTION_ID)[-1].id == 3
    term = messages(canon, emc.EMC_TRAJ_SET_TERM_COND)[0]
    assert (term.cond, term.tolerance) == (emc.EMC_TRAJ_TERM_COND.BLEND, pytest.approx(0.1))


def test_without_naive_cam_every_feed_is_a_move() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(600)
    canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)
    for k in range(1, 4):
        canon.STRAIGHT_FEED(k, k, 0, 0, 0, 0, 0)
    canon.FINISH()
    assert len(messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)) == 3
    assert messages(canon, emc.EMC_TRAJ_SET_TERM_COND)[0].cond == emc.EMC_TRAJ_TERM_COND.EXACT


def test_probe_move() -> None:
    canon = make_canon()
    canon.SET_FEED_RATE(60)
    canon.TURN_PROBE_ON()
    canon.STRAIGHT_PROBE(4, 0, 0, -10, 0, 0, 0, 0, 0, 0, 2)
    canon.TURN_PROBE_OFF()
    assert names(canon) == [
        "EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG",
        "EMC_TRAJ_SET_MOTION_ID",
        "EMC_TRAJ_PROBE",
    ]
    probe = canon.out[-1]
    assert pose(probe.pos)[2] == -10
    assert (probe.vel, probe.ini_maxvel, probe.probe_type) == (1.0, 20.0, 2)
    assert probe.type == emc.EMC_MOTION_TYPE.PROBING


# ============================================================ world model
def status_at(machine: list[float]) -> emc.EMC_STAT:
    stat = emc.EMC_STAT()
    p = stat.motion.traj.position
    p.tran.x, p.tran.y, p.tran.z = machine[:3]
    p.a, p.b, p.c, p.u, p.v, p.w = machine[3:]
    return stat


def test_external_position_round_trips_through_offsets_and_units() -> None:
    canon = make_canon("mm")
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
    canon.SET_G5X_OFFSET(1, 1, 2, 3, 0, 0, 0, 0, 0, 0)
    canon.SET_G92_OFFSET(0.5, 0, 0, 10, 0, 0, 0, 0, 0)
    canon.SET_XY_ROTATION(30)
    canon.USE_TOOL_LENGTH_OFFSET([0, 0, 2, 0, 0, 0, 0, 0, 0])
    target = [1.25, -2.5, 0.75, 20.0, 0, 0, 0, 0, 0]
    canon.STRAIGHT_TRAVERSE(1, *target[:6])
    canon.set_status(status_at(pose(last_move(canon).end)))
    assert canon.GET_EXTERNAL_POSITION() == approx(target)
    # the next move starts where motion is
    canon.STRAIGHT_TRAVERSE(2, *target[:6])
    assert len(messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)) == 1


def test_external_position_starts_the_next_move_from_motion() -> None:
    canon = make_canon()
    canon.set_status(status_at([5, 0, 0, 0, 0, 0, 0, 0, 0]))
    assert canon.GET_EXTERNAL_POSITION()[:3] == approx([5, 0, 0])
    canon.STRAIGHT_TRAVERSE(1, 5, 10, 0, 0, 0, 0)
    assert last_move(canon).vel == pytest.approx(50)  # Y alone: X did not move


def test_external_position_without_external_offsets() -> None:
    canon = make_canon()
    stat = status_at([5, 0, 3, 0, 0, 0, 0, 0, 0])
    stat.motion.external_offsets_applied = 1
    stat.motion.eoffset_pose.tran.z = 1
    canon.set_status(stat)
    assert canon.GET_EXTERNAL_POSITION()[:3] == approx([5, 0, 2])


def test_status_answers() -> None:
    tools = ToolTable()
    tools.load_lines(["T7 P3 Z1.5\n", "T9 P4\n"])
    canon = TaskCanon(make_setup(), tools)
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
    stat = emc.EMC_STAT()
    stat.motion.traj.probedPosition.tran.x = 25.4
    stat.motion.traj.probe_tripped = True
    stat.motion.traj.maxVelocity = 25.4
    stat.io.tool.toolInSpindle = 9
    stat.io.tool.pocketPrepped = 1
    stat.io.coolant.flood = 1
    stat.motion.synch_di[3] = 1
    stat.motion.analog_input[2] = 4.5
    stat.motion.spindle[0].speed = -300
    stat.motion.traj.feed_override_enabled = True
    canon.set_status(stat)
    assert canon.GET_EXTERNAL_PROBE_POSITION()[0] == pytest.approx(1.0)
    assert canon.GET_EXTERNAL_PROBE_TRIPPED_VALUE() == 1
    assert canon.GET_EXTERNAL_TRAVERSE_RATE() == pytest.approx(60)  # inches per minute
    assert canon.GET_EXTERNAL_TOOL_SLOT() == 2
    assert canon.GET_EXTERNAL_SELECTED_TOOL_SLOT() == 1
    assert (canon.GET_EXTERNAL_FLOOD(), canon.GET_EXTERNAL_MIST()) == (1, 0)
    assert canon.GET_EXTERNAL_DIGITAL_INPUT(3, 0) == 1
    assert canon.GET_EXTERNAL_DIGITAL_INPUT(4, 1) == 0
    assert canon.GET_EXTERNAL_DIGITAL_INPUT(64, 0) == -1
    assert canon.GET_EXTERNAL_ANALOG_INPUT(2, 0.0) == 4.5
    assert canon.GET_EXTERNAL_SPINDLE(0) == C.COUNTERCLOCKWISE
    assert canon.GET_EXTERNAL_FEED_OVERRIDE_ENABLE() == 1
    assert canon.GET_EXTERNAL_TOOL_TABLE(1).offset[2] == 1.5  # machine units
    assert canon.GET_EXTERNAL_TOOL_TABLE(5000).toolno == -1
    assert canon.find_tool_index(9) == 2
    stat.task.input_timeout = True
    assert canon.GET_EXTERNAL_DIGITAL_INPUT(3, 0) == -1


def test_world_before_any_status() -> None:
    canon = make_canon()
    assert canon.GET_EXTERNAL_POSITION() == approx([0] * 9)
    assert canon.GET_EXTERNAL_SELECTED_TOOL_SLOT() == -1
    assert canon.GET_EXTERNAL_FEED_OVERRIDE_ENABLE() == 1
    assert canon.GET_EXTERNAL_SPINDLE_OVERRIDE_ENABLE(0) == 1
    assert canon.GET_EXTERNAL_AXIS_MASK() == 0b1111
    assert canon.GET_EXTERNAL_SPINDLE(0) == C.STOPPED


def test_modes_read_back_in_program_units() -> None:
    canon = make_canon("mm")
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
    canon.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, 0.01)
    canon.SET_NAIVECAM_TOLERANCE(0.002)
    canon.SELECT_PLANE(C.PLANE_XZ)
    assert canon.GET_EXTERNAL_MOTION_CONTROL_MODE() == C.CONTINUOUS
    assert canon.GET_EXTERNAL_MOTION_CONTROL_TOLERANCE() == pytest.approx(0.01)
    assert canon.GET_EXTERNAL_MOTION_CONTROL_NAIVECAM_TOLERANCE() == pytest.approx(0.002)
    assert canon.GET_EXTERNAL_PLANE() == C.PLANE_XZ
    assert messages(canon, emc.EMC_TRAJ_SET_TERM_COND)[-1].tolerance == pytest.approx(0.254)


# ============================================================ arcs
def arc_canon(**extra) -> TaskCanon:
    canon = make_canon(
        vel=[100.0, 100.0, 100.0, 360.0, INF, INF, INF, INF, INF],
        acc=[1000.0, 1000.0, 1000.0, 3600.0, INF, INF, INF, INF, INF],
        **extra,
    )
    canon.SET_FEED_RATE(600)
    return canon


def test_arc_in_xy() -> None:
    canon = arc_canon()
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    canon.ARC_FEED(2, 0, 10, 0, 0, 1, 0, 0, 0, 0)
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    assert pose(arc.end) == approx([0, 10, 0, 0, 0, 0, 0, 0, 0])
    assert xyz(arc.center) == approx([0, 0, 0])
    assert xyz(arc.normal) == approx([0, 0, 1])
    assert arc.turn == 0
    assert arc.type == emc.EMC_MOTION_TYPE.ARC
    assert arc.vel == pytest.approx(10)
    # the radius allows sqrt(a * sqrt(3)/2 * r) = 93 per s, below the axes' 100
    assert arc.ini_maxvel == pytest.approx(math.sqrt(1000 * math.sqrt(3) / 2 * 10))
    assert arc.acc == pytest.approx(1000)
    assert messages(canon, emc.EMC_TRAJ_SET_MOTION_ID)[-1].id == 2


def test_helix_with_turns_and_offsets() -> None:
    canon = arc_canon()
    canon.SET_G5X_OFFSET(1, 100, 0, 0, 0, 0, 0, 0, 0, 0)
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    canon.ARC_FEED(2, 10, 0, 0, 0, 3, -6, 0, 0, 0)  # two full turns more, ccw, Z down
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    assert pose(arc.end)[:3] == approx([110, 0, -6])
    assert xyz(arc.center) == approx([100, 0, -6])
    assert arc.turn == 2
    canon.ARC_FEED(3, 10, 0, 0, 0, -2, -6, 0, 0, 0)  # clockwise, one full turn
    assert messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[1].turn == -2


def test_arc_in_xz_and_yz() -> None:
    canon = arc_canon()
    canon.SELECT_PLANE(C.PLANE_XZ)
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    # XZ: first axis Z, second X, the helix along Y
    canon.ARC_FEED(2, 10, 0, 0, 0, 1, 3, 0, 0, 0)
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[-1]
    assert pose(arc.end)[:3] == approx([0, 3, 10])
    assert xyz(arc.center) == approx([0, 3, 0])
    assert xyz(arc.normal) == approx([0, 1, 0])
    canon.SELECT_PLANE(C.PLANE_YZ)
    canon.STRAIGHT_TRAVERSE(3, 0, 10, 0, 0, 0, 0)
    # YZ: first axis Y, second Z, the helix along X
    canon.ARC_FEED(4, 0, 10, 0, 0, -1, 2, 0, 0, 0)
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[-1]
    assert pose(arc.end)[:3] == approx([2, 0, 10])
    assert xyz(arc.center) == approx([2, 0, 0])
    assert xyz(arc.normal) == approx([1, 0, 0])
    assert arc.turn == -1


def test_arc_under_rotation_turns_center_and_end() -> None:
    canon = arc_canon()
    canon.SET_XY_ROTATION(90)
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    canon.ARC_FEED(2, 0, 10, 0, 5, 1, 0, 0, 0, 0)
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    assert pose(arc.end)[:2] == approx([-10, 0])
    assert xyz(arc.center) == approx([-5, 0, 0])


def test_arc_in_inches_on_a_mm_machine() -> None:
    canon = arc_canon()
    canon.USE_LENGTH_UNITS(C.UNITS_INCHES)
    canon.STRAIGHT_TRAVERSE(1, 1, 0, 0, 0, 0, 0)
    canon.ARC_FEED(2, -1, 0, 0, 0, 1, 0, 0, 0, 0)
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    assert pose(arc.end)[:3] == approx([-25.4, 0, 0])


def test_nurbs_is_fed_as_arcs_ending_at_the_last_point() -> None:
    canon = arc_canon()
    canon.SET_MOTION_CONTROL_MODE(C.EXACT_PATH, 0)
    canon.NURBS_FEED(1, [(0, 0, 1), (5, 10, 1), (10, 0, 1)], 3)
    canon.FINISH()
    moves = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE | emc.EMC_TRAJ_LINEAR_MOVE)
    assert len(moves) >= 6
    assert pose(moves[-1].end)[:2] == approx([10, 0], 1e-6)
    assert max(pose(m.end)[1] for m in moves) == pytest.approx(5, abs=1e-3)  # the apex


# ============================================================ spindle, coolant, tools, flow
def test_spindle_messages() -> None:
    canon = make_canon()
    canon.SET_SPINDLE_SPEED(0, 1000)
    canon.START_SPINDLE_COUNTERCLOCKWISE(0)
    canon.SET_SPINDLE_SPEED(0, 1200)
    canon.ORIENT_SPINDLE(0, 90, 1)
    canon.WAIT_SPINDLE_ORIENT_COMPLETE(0, 5)
    canon.STOP_SPINDLE_TURNING(0)
    out = list(canon.out)
    assert names(canon) == [
        "EMC_SPINDLE_SPEED",
        "EMC_SPINDLE_ON",
        "EMC_SPINDLE_SPEED",
        "EMC_SPINDLE_ORIENT",
        "EMC_SPINDLE_WAIT_ORIENT_COMPLETE",
        "EMC_SPINDLE_OFF",
    ]
    assert out[0].speed == 0  # not turning yet
    assert (out[1].speed, out[1].factor) == (-1000, 0)
    assert out[2].speed == -1200
    assert (out[3].orientation, out[3].mode, out[4].timeout) == (90, 1, 5)
    assert canon.GET_EXTERNAL_SPEED(0) == 1200


def test_constant_surface_speed() -> None:
    canon = make_canon()
    canon.SET_G5X_OFFSET(1, 7, 0, 0, 0, 0, 0, 0, 0, 0)
    canon.SET_SPINDLE_MODE(0, 2000)  # G96 D2000
    canon.SET_SPINDLE_SPEED(0, 100)  # S100 m/min
    canon.START_SPINDLE_CLOCKWISE(0)
    on = messages(canon, emc.EMC_SPINDLE_ON)[0]
    assert on.speed == 2000
    assert on.factor == pytest.approx(1000 / (2 * math.pi) * 100)
    assert on.xoffset == 7
    canon.SET_G92_OFFSET(1, 0, 0, 0, 0, 0, 0, 0, 0)  # the X offset changes: speed again
    assert names(canon)[-2:] == ["EMC_SPINDLE_SPEED", "EMC_TRAJ_SET_G92"]
    assert canon.out[-2].xoffset == 8


def test_feed_per_revolution_synchronises_with_the_spindle() -> None:
    canon = make_canon("inch")
    canon.SET_FEED_MODE(0, 1)
    canon.SET_FEED_RATE(0.1)
    sync = messages(canon, emc.EMC_TRAJ_SET_SPINDLESYNC)[-1]
    assert (sync.feed_per_revolution, sync.velocity_mode) == (pytest.approx(0.1), True)
    canon.STRAIGHT_TRAVERSE(1, 1, 0, 0, 0, 0, 0)  # rapids are not synchronised
    assert names(canon)[-4:] == [
        "EMC_TRAJ_SET_SPINDLESYNC",
        "EMC_TRAJ_SET_MOTION_ID",
        "EMC_TRAJ_LINEAR_MOVE",
        "EMC_TRAJ_SET_SPINDLESYNC",
    ]
    assert canon.out[-4].feed_per_revolution == 0
    assert canon.GET_EXTERNAL_FEED_RATE() == 0.1
    canon.SET_FEED_MODE(0, 0)
    assert canon.out[-1].feed_per_revolution == 0


def test_coolant_io_and_override_messages() -> None:
    canon = make_canon()
    canon.FLOOD_ON()
    canon.MIST_ON()
    canon.FLOOD_OFF()
    canon.MIST_OFF()
    canon.DISABLE_FEED_OVERRIDE()
    canon.ENABLE_SPEED_OVERRIDE(1)
    canon.DISABLE_FEED_HOLD()
    canon.ENABLE_ADAPTIVE_FEED()
    canon.SET_MOTION_OUTPUT_BIT(2)
    canon.CLEAR_AUX_OUTPUT_BIT(3)
    canon.SET_AUX_OUTPUT_VALUE(1, 2.5)
    assert canon.WAIT(4, C.DIGITAL_INPUT, 1, 2.0) == 0
    assert canon.WAIT(64, C.DIGITAL_INPUT, 1, 2.0) == -1
    assert names(canon) == [
        "EMC_COOLANT_FLOOD_ON",
        "EMC_COOLANT_MIST_ON",
        "EMC_COOLANT_FLOOD_OFF",
        "EMC_COOLANT_MIST_OFF",
        "EMC_TRAJ_SET_FO_ENABLE",
        "EMC_TRAJ_SET_SO_ENABLE",
        "EMC_TRAJ_SET_FH_ENABLE",
        "EMC_MOTION_ADAPTIVE",
        "EMC_MOTION_SET_DOUT",
        "EMC_MOTION_SET_DOUT",
        "EMC_MOTION_SET_AOUT",
        "EMC_AUX_INPUT_WAIT",
    ]
    out = list(canon.out)
    assert (out[4].mode, out[5].spindle, out[5].mode, out[6].mode, out[7].status) == (0, 1, 1, 0, 1)
    assert (out[8].index, out[8].start, out[8].end, out[8].now) == (2, 1, 1, 0)
    assert (out[9].index, out[9].start, out[9].now) == (3, 0, 1)
    assert (out[10].start, out[10].now) == (2.5, 1)
    assert (out[11].index, out[11].input_type, out[11].wait_type, out[11].timeout) == (4, 1, 1, 2)


def test_tool_messages() -> None:
    tools = ToolTable()
    tools.load_lines(["T5 P2\n"])
    canon = TaskCanon(make_setup(), tools)
    canon.out.clear()
    canon.SELECT_TOOL(5)
    canon.START_CHANGE()
    canon.CHANGE_TOOL(1)
    canon.CHANGE_TOOL_NUMBER(1)
    canon.SET_TOOL_TABLE_ENTRY(1, 5, [0, 0, 2.5, 0, 0, 0, 0, 0, 0], 6.0, 0, 0, 0)
    canon.RELOAD_TOOLDATA()
    out = list(canon.out)
    assert names(canon) == [
        "EMC_TOOL_PREPARE",
        "EMC_TOOL_START_CHANGE",
        "EMC_TOOL_LOAD",
        "EMC_TOOL_SET_NUMBER",
        "EMC_TOOL_SET_OFFSET",
        "EMC_TOOL_LOAD_TOOL_TABLE",
    ]
    assert out[0].tool == 5
    assert out[3].tool == 1
    assert (out[4].pocket, out[4].toolno, out[4].diameter) == (1, 5, 6.0)
    assert pose(out[4].offset)[2] == 2.5
    assert canon.GET_EXTERNAL_TOOL_TABLE(1).offset[2] == 2.5  # seen at once by a synch


def test_tool_change_position_is_a_rapid_before_the_load() -> None:
    canon = make_canon(tool_change_position=[0.0, 0.0, 50.0])
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 30, 0, 0)
    canon.CHANGE_TOOL(1)
    move = messages(canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1]
    assert move.type == emc.EMC_MOTION_TYPE.TOOLCHANGE
    assert pose(move.end)[:4] == approx([0, 0, 50, 30])  # in machine coordinates; A stays
    assert names(canon)[-1] == "EMC_TOOL_LOAD"


def test_tool_length_offset_applies_to_later_moves() -> None:
    canon = make_canon()
    canon.USE_TOOL_LENGTH_OFFSET([0, 0, 10, 0, 0, 0, 0, 0, 0])
    canon.STRAIGHT_TRAVERSE(1, 0, 0, 0, 0, 0, 0)
    assert pose(last_move(canon).end)[2] == 10


def test_program_flow_and_messages() -> None:
    canon = make_canon()
    canon.PROGRAM_STOP()
    canon.OPTIONAL_PROGRAM_STOP()
    canon.MESSAGE("change the tool " + "x" * 300)
    canon.COMMENT("just a comment")
    canon.PALLET_SHUTTLE()
    canon.PROGRAM_END()
    assert names(canon) == [
        "EMC_TASK_PLAN_PAUSE",
        "EMC_TASK_PLAN_OPTIONAL_STOP",
        "EMC_OPERATOR_DISPLAY",
        "EMC_TASK_PLAN_END",
    ]
    assert canon.out[2].display.startswith("change the tool xx")
    assert len(canon.out[2].display) == emc.LINELEN - 1


def test_user_m_codes_run_their_program() -> None:
    canon = make_canon(user_m_commands={101: "/bin/M101"})
    assert canon.USER_DEFINED_FUNCTION(101, 1.5, 2) is True
    assert canon.out[-1].string == "/bin/M101 1.500000 2.000000"
    assert canon.USER_DEFINED_FUNCTION(102, 0, 0) is False


def test_probe_file_records_probed_points(tmp_path: Path) -> None:
    canon = make_canon()
    stat = emc.EMC_STAT()
    stat.motion.traj.probedPosition.tran.z = -3
    canon.set_status(stat)
    name = tmp_path / "probe.txt"
    canon.COMMENT(f"PROBEOPEN {name}")
    canon.GET_EXTERNAL_PROBE_POSITION()
    canon.GET_EXTERNAL_PROBE_POSITION()  # the same point: written once
    canon.COMMENT("PROBECLOSE")
    assert name.read_text().splitlines() == [
        " ".join(["0.000000"] * 2 + ["-3.000000"] + ["0.000000"] * 6)
    ]


def test_log_file(tmp_path: Path) -> None:
    canon = make_canon()
    name = tmp_path / "log.txt"
    canon.LOGOPEN(str(name))
    canon.LOG("one")
    canon.LOGCLOSE()
    canon.LOGAPPEND(str(name))
    canon.LOG("two")
    canon.LOGCLOSE()
    assert name.read_text() == "one\ntwo\n"


def test_gcode_writes_files_only_in_the_writable_folders(tmp_path: Path) -> None:
    (tmp_path / "machine").mkdir()
    outside = tmp_path / "outside.txt"
    outside.write_text("precious\n")
    canon = make_canon(writable_dirs=[str(tmp_path / "machine")])
    canon.COMMENT(f"PROBEOPEN {outside}")
    canon.LOGOPEN(str(outside))
    canon.LOGAPPEND(str(tmp_path / "machine" / ".." / "outside.txt"))  # no way around it
    assert outside.read_text() == "precious\n"  # not truncated
    refusals = [m.error for m in messages(canon, emc.EMC_OPERATOR_ERROR)]
    assert len(refusals) == 3 and all("refused" in text for text in refusals)
    assert "(PROBEOPEN " in refusals[0] and "WRITABLE_DIRS" in refusals[0]
    canon.LOGOPEN(str(tmp_path / "machine" / "log.txt"))  # inside: allowed
    canon.LOG("kept")
    canon.LOGCLOSE()
    assert (tmp_path / "machine" / "log.txt").read_text() == "kept\n"


# ============================================================ with the interpreter
class Machine:
    """The interpreter on a TaskCanon, with task's part played by hand: after each queue
    buster, motion is where the canon's last move ended and iocontrol did its part."""

    def __init__(self, tmp_path: Path, units: str = "mm", tools: ToolTable | None = None) -> None:
        self.canon = TaskCanon(make_setup(units), tools)
        self.stat = emc.EMC_STAT()
        self.stat.io.tool.pocketPrepped = -1
        self.stat.motion.traj.feed_override_enabled = True
        self.stat.motion.spindle[0].spindle_override_enabled = True
        self.canon.set_status(self.stat)
        self.interp = Interpreter(self.canon, parameter_file=str(tmp_path / "test.var"))
        self.interp.init()
        self.canon.out.clear()
        self.executed = 0  # messages of canon.out task has executed
        self.prepared = 0  # the tool iocontrol prepared

    def synch_world(self) -> None:
        """What task does at a queue buster: execute everything, then report the world."""
        p = self.stat.motion.traj.position
        end = self.canon.end_point
        p.tran.x, p.tran.y, p.tran.z = end[:3]
        p.a, p.b, p.c, p.u, p.v, p.w = end[3:]
        tools = self.canon.tools
        for msg in list(self.canon.out)[self.executed :]:
            if isinstance(msg, emc.EMC_TOOL_PREPARE):
                self.prepared = msg.tool
            elif isinstance(msg, emc.EMC_TOOL_LOAD):  # a nonrandom changer's load
                tools.put(0, tools.get(tools.find_index_for_tool(self.prepared)))
                self.stat.io.tool.toolInSpindle = self.prepared
        self.executed = len(self.canon.out)

    def mdi(self, *lines: str) -> None:
        for line in lines:
            if self.interp.execute(line) == INTERP_EXECUTE_FINISH:
                self.canon.FINISH()
                self.synch_world()
                self.interp.synch()
            self.canon.FINISH()  # as task does after each MDI command

    def run(self, path: Path) -> None:
        self.interp.open(str(path))
        while self.interp.read() != INTERP_ENDFILE:
            status = self.interp.execute()
            if status == INTERP_EXECUTE_FINISH:
                self.synch_world()
                self.interp.synch()
            elif status == INTERP_EXIT:
                break
        self.interp.close()


def test_interpreter_mdi_moves_in_inches_on_a_mm_machine(tmp_path: Path) -> None:
    m = Machine(tmp_path)
    m.mdi("G20", "G10 L2 P1 X1", "G0 X1 Y1", "G1 F60 X2")
    moves = messages(m.canon, emc.EMC_TRAJ_LINEAR_MOVE)
    assert [pose(mv.end)[:2] for mv in moves] == [approx([50.8, 25.4]), approx([76.2, 25.4])]
    assert moves[1].vel == pytest.approx(25.4)  # 60 in/min
    g5x = messages(m.canon, emc.EMC_TRAJ_SET_G5X)[-1]
    assert pose(g5x.origin)[0] == pytest.approx(25.4)


def test_interpreter_program(tmp_path: Path) -> None:
    tools = ToolTable()
    tools.load_lines(["T1 P1 Z10 D6\n"])
    m = Machine(tmp_path, tools=tools)
    program = tmp_path / "prog.ngc"
    program.write_text(
        "G21 G17 G90 G64 P0.01\n"
        "T1 M6\n"
        "G43\n"
        "S1000 M3 M8\n"
        "G0 X10 Y0 Z5\n"
        "G1 F600 Z0\n"
        "G3 X0 Y10 I-10 J0\n"
        "G4 P0.5\n"
        "(MSG, done)\n"
        "M0\n"
        "M1\n"
        "M2\n"
    )
    m.run(program)
    kinds = [n for n in names(m.canon) if n != "EMC_TRAJ_SET_MOTION_ID"]
    assert kinds == [
        "EMC_TRAJ_SET_TERM_COND",  # G64
        "EMC_TOOL_PREPARE",
        "EMC_TOOL_START_CHANGE",
        "EMC_SPINDLE_OFF",
        "EMC_TOOL_LOAD",
        "EMC_TRAJ_SET_OFFSET",  # G43
        "EMC_SPINDLE_SPEED",
        "EMC_SPINDLE_ON",
        "EMC_COOLANT_FLOOD_ON",
        "EMC_TRAJ_LINEAR_MOVE",
        "EMC_TRAJ_LINEAR_MOVE",
        "EMC_TRAJ_CIRCULAR_MOVE",
        "EMC_TRAJ_DELAY",
        "EMC_OPERATOR_DISPLAY",
        "EMC_TASK_PLAN_PAUSE",
        "EMC_TASK_PLAN_OPTIONAL_STOP",
        # M2: back to G54, feed per minute, spindle and coolant off, the end
        "EMC_TRAJ_SET_G5X",
        "EMC_TRAJ_SET_ROTATION",
        "EMC_TRAJ_SET_SPINDLESYNC",
        "EMC_SPINDLE_OFF",
        "EMC_COOLANT_FLOOD_OFF",
        "EMC_TASK_PLAN_END",
    ]
    assert messages(m.canon, emc.EMC_TOOL_PREPARE)[0].tool == 1
    moves = messages(m.canon, emc.EMC_TRAJ_LINEAR_MOVE)
    assert pose(moves[0].end)[:3] == approx([10, 0, 15])  # Z includes the tool length
    arc = messages(m.canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    assert pose(arc.end)[:3] == approx([0, 10, 10])
    assert xyz(arc.center) == approx([0, 0, 10])
    assert arc.turn == 0
    # the interpreter's line numbers, announced before the moves of each line
    ids = [msg.id for msg in messages(m.canon, emc.EMC_TRAJ_SET_MOTION_ID)]
    assert ids == [5, 6, 7]
    assert messages(m.canon, emc.EMC_OPERATOR_DISPLAY)[0].display.strip() == "done"


def test_interpreter_synch_after_m6_reads_the_world(tmp_path: Path) -> None:
    tools = ToolTable()
    tools.load_lines(["T3 P1 Z2\n"])
    m = Machine(tmp_path, tools=tools)
    m.mdi("G0 X7", "T3 M6", "G43", "G1 F100 X8")
    assert m.interp.current_pocket == 1
    assert m.interp.parameters[5400] == 3
    assert pose(messages(m.canon, emc.EMC_TRAJ_SET_OFFSET)[-1].offset)[2] == 2
    # G43 moves the program's origin, not the machine: Z stays where it was
    move = messages(m.canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1]
    assert pose(move.end)[:3] == approx([8, 0, 0])
    assert m.interp.current[2] == pytest.approx(-2)


def test_helix_velocity_is_limited_by_the_slow_helix_axis() -> None:
    canon = arc_canon()
    canon.setup.axis_max_vel[2] = 5.0
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    canon.ARC_FEED(2, 0, 10, 0, 0, 1, 10, 0, 0, 0)  # a quarter turn, 10 along Z
    arc = messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE)[0]
    quarter = 10 * math.pi / 2
    assert arc.ini_maxvel == pytest.approx(math.hypot(quarter, 10) / (10 / 5))


def test_interpreter_probe_and_input_reach_the_parameters(tmp_path: Path) -> None:
    m = Machine(tmp_path)
    m.mdi("G10 L2 P1 Z1")
    m.stat.motion.traj.probedPosition.tran.z = -4.0
    m.stat.motion.traj.probe_tripped = True
    m.stat.motion.synch_di[3] = 1
    m.mdi("G38.2 Z-10 F100", "M66 P3 L0", "G0 X1")
    assert names(m.canon)[:5] == [
        "EMC_TRAJ_SET_G5X",
        "EMC_TRAJ_SET_ROTATION",
        "EMC_TRAJ_CLEAR_PROBE_TRIPPED_FLAG",
        "EMC_TRAJ_SET_MOTION_ID",
        "EMC_TRAJ_PROBE",
    ]
    assert pose(messages(m.canon, emc.EMC_TRAJ_PROBE)[0].pos)[2] == pytest.approx(-9)
    assert m.interp.parameters[5063] == pytest.approx(-5)  # program coordinates
    assert m.interp.parameters[5070] == 1
    assert messages(m.canon, emc.EMC_AUX_INPUT_WAIT)[0].index == 3
    assert m.interp.parameters[5399] == 1


def test_naive_cam_turns_a_flat_arc_into_a_feed() -> None:
    canon = arc_canon()
    canon.SET_MOTION_CONTROL_MODE(C.CONTINUOUS, 0.5)
    canon.SET_NAIVECAM_TOLERANCE(0.5)
    canon.STRAIGHT_TRAVERSE(1, 10, 0, 0, 0, 0, 0)
    end = (10 * math.cos(0.1), 10 * math.sin(0.1))  # 0.0125 from its chord
    canon.ARC_FEED(2, *end, 0, 0, 1, 0, 0, 0, 0)
    canon.FINISH()
    assert messages(canon, emc.EMC_TRAJ_CIRCULAR_MOVE) == []
    move = last_move(canon)
    assert move.type == emc.EMC_MOTION_TYPE.FEED
    assert pose(move.end)[:2] == approx(end)


def test_tools_come_from_iocontrols_tool_data_when_not_given() -> None:
    canon = make_canon()
    assert canon.find_tool_index(4) == -1  # no iocontrol yet: an empty table
    writer = ToolDataWriter()
    try:
        table = ToolTable()
        table.load_lines(["T4 P1 Z3\n"])
        writer.publish(table)
        assert canon.find_tool_index(4) == 1
        assert canon.GET_EXTERNAL_TOOL_TABLE(1).offset[2] == 3
        table.load_lines(["T4 P1 Z3\n", "T6 P2 Z1\n"])
        writer.publish(table)  # iocontrol changed it: read again
        assert canon.find_tool_index(6) == 2
    finally:
        writer.close()
