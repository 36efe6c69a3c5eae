"""State tags (task/interp/statetag.py): the interpreter's modes travel with each move to
motion and back, so that task shows the modes of the move being carried out and, after
an abort, brings the interpreter back to them (LinuxCNC's StateTag, restore_from_tag)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion.tp.planner import TrajectoryPlanner
from nml import emc
from task.canon import state_tag_bytes, state_tag_of
from task.interp import statetag
from tests.task.test_canon import Machine, messages


def test_the_tag_numbers_are_the_message_catalogues() -> None:
    floats = [statetag.FLOAT_FEED, statetag.FLOAT_SPEED, statetag.FLOAT_PATH_TOLERANCE]
    assert floats == [emc.StateFieldFloat.FEED, emc.StateFieldFloat.SPEED, 3]
    for field in emc.StateField:
        assert getattr(statetag, field.name) == statetag.FLOAT_FIELDS + field.value
    for flag in emc.StateFlag:
        assert getattr(statetag, f"FLAG_{flag.name}") == flag.value


def test_a_tag_survives_the_message_struct() -> None:
    tag = (1.5, 2.0, 3.0, 0.25, -1.0, 7, -1, 400, 10, 170, -1, 550, -1, 1 << 20 | 5)
    struct = emc.StateTag.from_bytes(state_tag_bytes(tag))
    assert struct.to_python() == {
        "fields_float": [1.5, 2.0, 3.0, 0.25, -1.0],
        "fields": [7, -1, 400, 10, 170, -1, 550, -1],
        "packed_flags": 1 << 20 | 5,
    }
    assert state_tag_of(struct) == tag


def test_moves_carry_the_modes_of_their_line(tmp_path: Path) -> None:
    machine = Machine(tmp_path)
    machine.mdi("G55 G0 X1", "G56 G91 G1 X1 F100", "G17 G90")
    first, second = messages(machine.canon, emc.EMC_TRAJ_LINEAR_MOVE)
    g_first, _, _ = statetag.active_modes(state_tag_of(first.tag))
    g_second, _, settings = statetag.active_modes(state_tag_of(second.tag))
    assert (g_first[8], g_first[6], g_first[1]) == (550, 900, 0)  # G55 G90, G0
    assert (g_second[8], g_second[6], g_second[1]) == (560, 910, 10)  # G56 G91, G1
    assert settings[statetag.FLOAT_FEED] == 100.0


def test_a_tag_unpacks_into_the_interpreters_active_codes(tmp_path: Path) -> None:
    machine = Machine(tmp_path)
    machine.mdi("G20 G56 G91 G93 G98 G61.1 G91.1 G7 M3 S500 M8 M52 P1", "G1 X1 F2")
    interp = machine.interp
    move = messages(machine.canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1]
    g_codes, m_codes, settings = statetag.active_modes(state_tag_of(move.tag))
    expected_g = interp.active_g_codes()
    expected_g[2] = -1  # (the tag's G_MODE_0: the block's non-modal code, none here)
    assert g_codes == expected_g
    assert m_codes[2:6] == interp.active_m_codes()[2:6]  # spindle, coolant
    assert m_codes[7] == 52
    assert settings[1:] == pytest.approx(interp.active_settings()[1:])


def test_restore_brings_back_the_modes_of_an_earlier_move(tmp_path: Path) -> None:
    """Motion was on line 2's G55 G90 F100 move; the interpreter had read on to line 3."""
    machine = Machine(tmp_path)
    program = tmp_path / "program.ngc"
    program.write_text("%\nG55 G90 G1 X2 F100\nG56 G91 F50\n%\n")
    machine.run(program)
    tag = state_tag_of(messages(machine.canon, emc.EMC_TRAJ_LINEAR_MOVE)[-1].tag)
    interp = machine.interp
    assert interp.active_g_codes()[8] == 560
    machine.canon.out.clear()
    assert not interp.restore_from_tag((*tag[:5], 1, *tag[6:]))  # line 1: never a move's
    assert interp.restore_from_tag(tag)
    g_codes = interp.active_g_codes()
    assert (g_codes[8], g_codes[6], interp.feed_rate) == (550, 900, 100.0)
    assert interp.parameters[5220] == 2
    # the canon heard of it: the G55 origin goes out in the queue
    assert [m.g5x_index for m in messages(machine.canon, emc.EMC_TRAJ_SET_G5X)] == [2]


def test_no_restore_from_a_move_inside_a_subroutine(tmp_path: Path) -> None:
    machine = Machine(tmp_path)
    tag = list(state_tag_of(emc.StateTag()))
    tag[statetag.LINE_NUMBER], tag[statetag.ORIGIN], tag[statetag.PLANE] = 5, 550, 170
    tag[statetag.FLAGS] = 1 << statetag.FLAG_IN_SUB
    assert statetag.is_valid(tuple(tag)) and not statetag.is_restorable(tuple(tag))
    assert not machine.interp.restore_from_tag(tuple(tag))


def test_the_planner_reports_the_tag_of_the_move_it_carries_out() -> None:
    tp = TrajectoryPlanner([100.0] * 9, [1000.0] * 9, cycle_time=0.001)
    first, second = b"A" * 60, b"B" * 60
    tp.add_line([1.0] + [0.0] * 8, 50.0, 100.0, 1000.0, motion_id=1, tag=first)
    tp.add_line([1.0, 1.0] + [0.0] * 7, 50.0, 100.0, 1000.0, motion_id=2, tag=second)
    seen = []
    for _ in range(200):
        tp.step()
        seen.append((tp.motion_id, tp.tag))
    assert (1, first) in seen and (2, second) in seen
    assert all(tag == (first if line == 1 else second) for line, tag in seen if line)
    assert np.allclose(tp.pos[:2], [1.0, 1.0])
