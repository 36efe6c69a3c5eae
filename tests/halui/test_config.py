"""What halui reads from the INI file, and its errors as ``file:line: cause``."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.halui.__main__ import main
from cnc.halui.config import AXIS_LETTERS, load_config
from cnc.ini import IniError


def write_ini(folder: Path, text: str) -> Path:
    path = folder / "machine.ini"
    path.write_text(text)
    return path


def test_defaults_are_linuxcncs(tmp_path: Path) -> None:
    config = load_config(write_ini(tmp_path, "[EMC]\nMACHINE = x\n"))
    assert (config.num_joints, config.num_spindles, config.axes) == (3, 1, AXIS_LETTERS)
    assert not config.has_home_all and config.mdi_commands == ()
    assert (config.max_feed_override, config.max_velocity, config.cycle_time) == (1.0, 1.0, 0.02)
    assert (config.min_spindle_override, config.max_spindle_override) == (0.0, 1.0)


def test_machine_limits_and_mdi_commands(tmp_path: Path) -> None:
    config = load_config(
        write_ini(
            tmp_path,
            "[KINS]\nJOINTS = 4\n"
            "[TRAJ]\nCOORDINATES = Z X Y X\nSPINDLES = 2\nMAX_LINEAR_VELOCITY = 40\n"
            "[DISPLAY]\nMAX_FEED_OVERRIDE = 1.5\nMAX_SPINDLE_OVERRIDE = 2\n"
            "MIN_SPINDLE_OVERRIDE = 0.5\n"
            "[JOINT_0]\nHOME_SEQUENCE = 0\n"
            "[HALUI]\nMDI_COMMAND = G0 X0\nMDI_COMMAND = o<probe> call\nCYCLE_TIME = 0.05\n",
        )
    )
    assert (config.num_joints, config.num_spindles, config.axes) == (4, 2, "xyz")
    assert config.has_home_all
    assert config.mdi_commands == ("G0 X0", "o<probe> call")
    assert (config.max_feed_override, config.max_velocity, config.cycle_time) == (1.5, 40, 0.05)
    assert (config.min_spindle_override, config.max_spindle_override) == (0.5, 2.0)


def test_an_empty_last_mdi_command_is_not_set_as_in_linuxcnc(tmp_path: Path) -> None:
    config = load_config(write_ini(tmp_path, "[HALUI]\nMDI_COMMAND = G0 X1\nMDI_COMMAND =\n"))
    assert config.mdi_commands == ("G0 X1",)


def test_max_velocity_falls_back_to_the_x_axis(tmp_path: Path) -> None:
    config = load_config(write_ini(tmp_path, "[AXIS_X]\nMAX_VELOCITY = 12\n"))
    assert config.max_velocity == 12


@pytest.mark.parametrize(
    ("text", "line", "cause"),
    [
        ("[KINS]\nJOINTS = three\n", 2, "[KINS]JOINTS = 'three' is not an integer"),
        ("[KINS]\nJOINTS = 17\n", 2, "out of range; allowed: an integer from 1 to 16"),
        (
            "[HALUI]\nMDI_COMMAND = G0 X1\nMDI_COMMAND =\nMDI_COMMAND = G0 X2\n",
            4,
            "[HALUI]MDI_COMMAND after an empty one",
        ),
        ("[HALUI]\nMDI_COMMAND = G1 " + "X1 " * 100 + "\n", 2, "longer than 254 bytes"),
        ("[HALUI]\n" + "MDI_COMMAND = G0\n" * 65, 66, "more than 64 lines"),
        ("[DISPLAY]\nMAX_FEED_OVERRIDE = lots\n", 2, "is not a finite number"),
        ("[DISPLAY]\nMAX_FEED_OVERRIDE = 0\n", 2, "allowed: a number > 0"),
    ],
)
def test_bad_values_name_file_and_line(tmp_path: Path, text: str, line: int, cause: str) -> None:
    path = write_ini(tmp_path, text)
    with pytest.raises(IniError) as caught:
        load_config(path)
    assert (caught.value.file, caught.value.line) == (str(path), line)
    assert cause in caught.value.cause


def test_the_program_refuses_a_bad_ini_before_touching_hal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_ini(tmp_path, "[KINS]\nJOINTS = many\n")
    assert main(["-ini", str(path)]) == 1
    err = capsys.readouterr().err
    assert f"halui: {path}:2: [KINS]JOINTS = 'many' is not an integer" in err


def test_the_program_needs_an_ini_file(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("CNC_INI_FILE", raising=False)
    assert main([]) == 1
    assert "no INI file" in capsys.readouterr().err


def test_the_program_needs_a_running_hal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_ini(tmp_path, "[KINS]\nJOINTS = 3\n")
    assert main(["-ini", str(path)]) == 1
    assert "HAL is not running" in capsys.readouterr().err
