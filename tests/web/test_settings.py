"""cnc ui web: the INI values it reads ([DISPLAY], [MDI_COMMAND_LIST], [FILTER]) and the
command line's access rule."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ui.web.server import main
from cnc.ui.web.settings import (
    Settings,
    angular_increments,
    cycle_time,
    increments,
    macros,
    override_percent,
)


@pytest.mark.parametrize(
    ("value", "seconds"), [("100", 0.1), ("0.05", 0.05), ("", 0.1), ("fast", 0.1), ("0", 0.1)]
)
def test_cycle_time_reads_milliseconds_or_seconds(value: str, seconds: float) -> None:
    assert cycle_time(value) == pytest.approx(seconds)


def test_increments_start_with_continuous_and_convert_units() -> None:
    found = increments("1 mm, 0.1 inch, 0.5, rubbish", 1 / 25.4)  # an inch machine
    assert [step["label"] for step in found] == ["continuous", "1 mm", "0.1 inch", "0.5"]
    assert [step["distance"] for step in found] == pytest.approx([0, 1 / 25.4, 0.1, 0.5])


def test_angular_increments_are_degrees_with_continuous_first() -> None:
    found = angular_increments("continuous, .5, 45 deg, junk")
    assert [step["label"] for step in found] == ["continuous", ".5°", "45 deg"]
    assert [step["distance"] for step in found] == [0, 0.5, 45]
    assert angular_increments(None)[1]["distance"] == 90  # the default list


def test_macros_have_commands_and_a_label_with_line_breaks() -> None:
    assert macros(["G0 Z25;X0 Y0;Z0, Goto\\nUser\\nZero", "G53 G0 Z0"]) == [
        {"label": "Goto\nUser\nZero", "commands": "G0 Z25;X0 Y0;Z0"},
        {"label": "G53 G0 Z0", "commands": "G53 G0 Z0"},
    ]


def test_override_limits_are_percent_or_a_factor() -> None:
    assert override_percent("120", 100) == 120
    assert override_percent("1.5", 100) == 150
    assert override_percent(None, 100) == 100


def test_settings_from_an_ini_file(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[EMC]\nMACHINE = test\n"
        "[DISPLAY]\nTITLE = Big Mill\nCYCLE_TIME = 50\n"
        "PROGRAM_PREFIX = ~/nc\nMDI_HISTORY_FILE = hist.txt\n"
        "DEFAULT_LINEAR_VELOCITY = 2\nMAX_LINEAR_VELOCITY = 10\nMAX_FEED_OVERRIDE = 1.2\n"
        "MIN_SPINDLE_0_OVERRIDE = 50\nMAX_SPINDLE_0_OVERRIDE = 120\n"
        "POSITION_FEEDBACK = COMMANDED\n"
        "[MDI_COMMAND_LIST]\nMDI_COMMAND_MACRO0 = G0 X0, Zero\nMDI_COMMAND_MACRO1 = M5\n"
        "[FILTER]\nPROGRAM_EXTENSION = .ngc,.nc G-code\nPROGRAM_EXTENSION = .py Python\n"
        "[TRAJ]\nCOORDINATES = X Y Z A\nLINEAR_UNITS = inch\n"
    )
    settings = Settings.load(str(ini))
    assert settings.machine == "test" and settings.cycle_time_s == pytest.approx(0.05)
    assert settings.program_prefix == Path.home() / "nc"
    assert settings.mdi_history_file == tmp_path / "hist.txt"
    # never down to 0 (motion refuses a zero jog velocity): 1 % of the top at least
    assert settings.jog_speed == {"default": 120.0, "min": 6.0, "max": 600.0}
    assert settings.max_feed_override == pytest.approx(120)
    assert (settings.min_spindle_override, settings.max_spindle_override) == (50, 120)
    assert settings.is_position_actual is False and settings.is_position_relative is True
    assert [macro["label"] for macro in settings.macros] == ["Zero", "M5"]
    assert settings.extensions == (".ngc", ".nc", ".py")
    assert settings.axes == "XYZA" and settings.page_config()["places"] == 4
    assert settings.page_config()["title"] == "Big Mill"


def test_another_address_without_a_token_refuses_to_start(capsys, monkeypatch) -> None:
    monkeypatch.delenv("CNC_WEB_TOKEN", raising=False)
    assert main(["web", "--host", "0.0.0.0"]) == 2
    assert "refusing to serve on 0.0.0.0 without a key" in capsys.readouterr().err


def test_the_arguments_must_start_with_web(capsys) -> None:
    assert main(["desktop"]) == 2
    assert "usage: cnc ui web" in capsys.readouterr().err


def test_filter_programs_by_extension(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[FILTER]\nPROGRAM_EXTENSION = .py Python\npy = python3\nPNG = image-to-gcode\n")
    assert Settings.load(str(ini)).filters == {".py": "python3", ".png": "image-to-gcode"}


@pytest.mark.parametrize(
    ("display", "is_lathe"),
    [("MACHINE_TYPE_HINT = LATHE", True), ("LATHE = 1", True), ("MACHINE_TYPE_HINT = FOAM", False)],
)
def test_a_lathe_is_recognised_by_the_hint_or_the_old_switch(
    tmp_path: Path, display: str, is_lathe: bool
) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(f"[DISPLAY]\n{display}\nMIN_SPINDLE_0_SPEED = 50\nMAX_SPINDLE_0_SPEED = 900\n")
    settings = Settings.load(str(ini))
    assert settings.is_lathe is is_lathe
    assert (settings.spindle["min"], settings.spindle["max"]) == (50, 900)


def test_the_message_pins_and_the_tool_changer_come_from_the_ini(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[DISPLAY]\nMESSAGE_TEXT = Lube\nMESSAGE_TYPE = okdialog\nMESSAGE_PINNAME = lube\n"
        "MESSAGE_TEXT = Air\nMESSAGE_TYPE = dialog\nMESSAGE_PINNAME = air\n"
        "[EMCIO]\nTOOL_TABLE = t.tbl\nRANDOM_TOOLCHANGER = 1\n"
    )
    settings = Settings.load(str(ini))
    assert [pin.name for pin in settings.message_pins] == ["lube"]
    assert settings.problems == [
        f"{ini}:6: [DISPLAY]MESSAGE_TYPE = dialog: expected status and/or one of okdialog, "
        "yesnodialog, nonedialog"
    ]
    assert settings.tool_table == tmp_path / "t.tbl" and settings.is_random_toolchanger
    assert Settings().message_pins == [] and not Settings().is_random_toolchanger


def test_the_spindle_range_comes_from_the_display_and_the_spindle_sections(
    tmp_path: Path,
) -> None:
    """GUI-013: the manual controls within [SPINDLE_0]'s limits (LinuxCNC 2.9's keys; the
    reverse maximum is the forward one unless given), and which key set each bound."""
    ini = tmp_path / "m.ini"
    ini.write_text("[SPINDLE_0]\nMAX_FORWARD_VELOCITY = 6000\nMIN_FORWARD_VELOCITY = 100\n")
    settings = Settings.load(str(ini))
    assert settings.spindle == {
        "increment": 100.0, "default": 500.0, "min": 100.0, "max": 6000.0, "max_reverse": 6000.0,
    }  # fmt: skip
    assert settings.spindle_limit_keys == {
        "max": "[SPINDLE_0]MAX_FORWARD_VELOCITY",
        "max_reverse": "[SPINDLE_0]MAX_FORWARD_VELOCITY",
    }
    ini.write_text(
        "[DISPLAY]\nMAX_SPINDLE_0_SPEED = 3000\nDEFAULT_SPINDLE_0_SPEED = 8000\n"
        "[SPINDLE_0]\nMAX_FORWARD_VELOCITY = 6000\nMAX_REVERSE_VELOCITY = 1000\n"
    )
    settings = Settings.load(str(ini))
    assert (settings.spindle["max"], settings.spindle["max_reverse"]) == (3000, 1000)
    assert settings.spindle["default"] == 3000  # within the range
    assert settings.spindle_limit_keys["max_reverse"] == "[SPINDLE_0]MAX_REVERSE_VELOCITY"


def test_allowed_hosts_job_history_and_the_tool_setter(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[DISPLAY]\nWEB_ALLOWED_HOSTS = CNC.local, shop-pc\n"
        "[TOOLSENSOR]\nX = 10\nY = 20\nZ = -5\nMAXPROBE = -30\n"
    )
    settings = Settings.load(str(ini))
    assert settings.allowed_hosts == ("cnc.local", "shop-pc")
    assert settings.job_history_file == tmp_path / "job_history.json"
    assert settings.tool_sensor == {
        "x": 10.0, "y": 20.0, "z": -5.0, "maxprobe": -30.0, "search_vel": 200.0, "probe_vel": 20.0,
    }  # fmt: skip
    ini.write_text("[TOOLSENSOR]\nX = 10\nY = here\n")
    settings = Settings.load(str(ini))
    assert settings.tool_sensor is None
    assert settings.problems == [f"{ini}:3: [TOOLSENSOR]Y must be a number: tool setter off"]
