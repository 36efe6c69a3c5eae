"""Joint record: position forms, backlash and leadscrew compensation, following error
(MOT-005/007, MOT-072..074)."""

import numpy as np
import pytest

from motion.joint import CompFileError, CompTable, Joint

DT = 0.001


def drive(joint: Joint, positions) -> list[float]:
    """Command ``positions`` one per period with a perfect servo; motor commands out."""
    out = []
    for pos in positions:
        joint.pos_cmd = pos
        joint.update_command(DT)
        joint.update_feedback(joint.motor_pos_cmd)
        out.append(joint.motor_pos_cmd)
    return out


def test_without_compensation_motor_and_joint_positions_agree() -> None:  # MOT-007
    joint = Joint(30, 500)
    motor = drive(joint, np.linspace(0, 5, 100))
    assert motor == list(np.linspace(0, 5, 100))
    assert joint.pos_fb == joint.motor_pos_fb == 5


def test_home_offset_shifts_motor_positions_only() -> None:
    joint = Joint(30, 500)
    drive(joint, [2.0])
    joint.set_position(10.0)  # homing: here is 10
    assert joint.pos_fb == joint.pos_cmd == 10.0
    assert joint.motor_pos_cmd == 2.0 and joint.motor_offset == -8.0
    drive(joint, [11.0])
    assert joint.motor_pos_cmd == pytest.approx(3.0)


def test_backlash_adds_half_on_each_side_of_a_reversal() -> None:  # MOT-072
    joint = Joint(30, 500, backlash=0.2)
    up = np.linspace(0, 2, 200)
    motor = drive(joint, list(up) + [2.0] * 300)
    assert motor[-1] - 2.0 == pytest.approx(0.1)
    motor = drive(joint, list(up[::-1]) + [0.0] * 300)
    assert motor[-1] == pytest.approx(-0.1)
    steps = np.abs(np.diff(motor))
    assert steps.max() < 0.05  # slewed, never a step
    assert joint.pos_fb == pytest.approx(0.0)  # feedback removes the correction again


def test_comp_file_type_0_and_1(tmp_path) -> None:  # MOT-073
    positions = tmp_path / "type0.comp"
    positions.write_text("# nominal forward reverse\n0 0.01 -0.01\n10 10.03 9.99\n\n")
    table = CompTable.load(positions, 0)
    assert table.correction(5.0, is_forward=True) == pytest.approx(0.02)
    assert table.correction(5.0, is_forward=False) == pytest.approx(-0.01)
    assert table.correction(-5.0, is_forward=True) == pytest.approx(0.01)  # held at the ends
    assert table.correction(50.0, is_forward=False) == pytest.approx(-0.01)
    corrections = tmp_path / "type1.comp"
    corrections.write_text("0 0.01 -0.01\n10 0.03 -0.01\n")
    assert CompTable.load(corrections, 1).correction(5.0, True) == pytest.approx(0.02)


def test_comp_is_applied_to_the_motor_command(tmp_path) -> None:
    path = tmp_path / "x.comp"
    path.write_text("0 0.0 0.0\n100 100.1 100.1\n")
    joint = Joint(30, 500, comp=CompTable.load(path))
    drive(joint, list(np.linspace(0, 50, 1000)) + [50.0] * 500)
    assert joint.motor_pos_cmd == pytest.approx(50.05)
    assert joint.pos_fb == pytest.approx(50.0)


@pytest.mark.parametrize(
    ("text", "message"),
    [("0 1\n", "three numbers"), ("1 1 1\n0 0 0\n", "must increase"), ("0 x 1\n", "numbers")],
)
def test_bad_comp_files_name_the_line(tmp_path, text, message) -> None:
    path = tmp_path / "bad.comp"
    path.write_text(text)
    with pytest.raises(CompFileError, match=message) as info:
        CompTable.load(path)
    assert str(path) in str(info.value)


def test_following_error_limit_scales_with_speed() -> None:  # MOT-074
    joint = Joint(30, 500, ferror=1.0, min_ferror=0.1)
    drive(joint, [0.0, 0.0])
    assert joint.following_error_limit() == pytest.approx(0.1)
    joint.pos_cmd = 0.015  # 15 mm/s: half the max velocity
    joint.update_command(DT)
    assert joint.following_error_limit() == pytest.approx(0.5)
    joint.update_feedback(-0.6)
    joint.update_command(DT)
    assert joint.is_following_error()


def test_invalid_joint_parameters() -> None:
    with pytest.raises(ValueError, match="FERROR"):
        Joint(30, 500, ferror=0)
    with pytest.raises(ValueError, match="backlash"):
        Joint(30, 500, backlash=-1)
