"""The INI schema (cnc/inischema.py, CFG-004): every key's type, default and bounds declared
once, every bad value refused with file, line, key and the allowed range."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cnc.ini import IniError, IniFile
from cnc.inischema import (
    HUGE,
    MAX_JOINTS,
    MAX_SPINDLES,
    MDI_COMMAND_BYTES,
    SCHEMA,
    ConfigError,
    load_config,
    read_config,
    real,
    schema_section,
)

MACHINE = """\
[EMC]
VERSION = 1.1
[TASK]
TASK = milltask
CYCLE_TIME = 0.01
[EMCIO]
TOOL_TABLE = tool.tbl
[RS274NGC]
PARAMETER_FILE = sim.var
[TRAJ]
COORDINATES = X Y Z
LINEAR_UNITS = mm
ANGULAR_UNITS = degree
MAX_LINEAR_VELOCITY = 50
[KINS]
KINEMATICS = trivkins
JOINTS = 3
[AXIS_X]
MIN_LIMIT = -100
MAX_LIMIT = 100
[AXIS_Y]
MIN_LIMIT = -100
MAX_LIMIT = 100
[AXIS_Z]
MIN_LIMIT = -50
MAX_LIMIT = 50
[JOINT_0]
MIN_LIMIT = -100
MAX_LIMIT = 100
MAX_ACCELERATION = 500
HOME_SEQUENCE = 0
[JOINT_1]
MIN_LIMIT = -100
MAX_LIMIT = 100
[JOINT_2]
MIN_LIMIT = -50
MAX_LIMIT = 50
"""


def machine(tmp_path: Path, text: str = MACHINE, **changes: str) -> Path:
    """The test machine's INI file, with ``SECTION__KEY="value"`` lines changed or added."""
    lines = text.splitlines()
    for name, value in changes.items():
        section, key = name.split("__")
        header = lines.index(f"[{section}]") if f"[{section}]" in lines else None
        if header is None:
            lines += [f"[{section}]", f"{key} = {value}"]
            continue
        end = next(
            (i for i in range(header + 1, len(lines)) if lines[i].startswith("[")), len(lines)
        )
        for i in range(header + 1, end):
            if lines[i].split("=")[0].strip() == key:
                lines[i] = f"{key} = {value}"
                break
        else:
            lines.insert(header + 1, f"{key} = {value}")
    path = tmp_path / "m.ini"
    path.write_text("\n".join(lines) + "\n")
    return path


def line_of(path: Path, section: str, key: str) -> int:
    entry = IniFile.load(path).entry(section, key)
    assert entry is not None
    return entry.line


def refused(path: Path) -> list[str]:
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert isinstance(caught.value, IniError)
    return str(caught.value).splitlines()


def test_the_test_machine_is_accepted_with_linuxcncs_defaults(tmp_path: Path) -> None:
    config = load_config(machine(tmp_path))
    assert config.warnings == []
    assert (config.joints, config.coordinates, config.axes) == (3, "XYZ", "XYZ")
    value = config.value
    assert value("JOINT_1", "MAX_VELOCITY") == value("JOINT_1", "MAX_ACCELERATION") == 1.0
    assert (value("JOINT_1", "FERROR"), value("JOINT_1", "MIN_FERROR")) == (1.0, 1.0)
    assert value("JOINT_1", "HOME_FINAL_VEL") == -1.0
    assert value("JOINT_1", "HOME_SEQUENCE") is None and value("JOINT_0", "HOME_SEQUENCE") == 0
    assert value("JOINT_1", "HOME_USE_INDEX") is False
    assert value("AXIS_A", "MIN_LIMIT") == -HUGE and value("AXIS_A", "MAX_LIMIT") == HUGE
    assert value("TRAJ", "MAX_LINEAR_VELOCITY") == 50.0
    assert value("TRAJ", "MAX_LINEAR_ACCELERATION") == HUGE
    assert (value("TRAJ", "LINEAR_UNITS"), value("TRAJ", "ANGULAR_UNITS")) == ("mm", 1.0)
    assert (value("TASK", "CYCLE_TIME"), value("EMCIO", "CYCLE_TIME")) == (0.01, 0.1)
    assert value("SPINDLE_0", "MAX_REVERSE_VELOCITY") == value("SPINDLE_0", "MAX_FORWARD_VELOCITY")
    assert config.file("EMCIO", "TOOL_TABLE") == tmp_path / "tool.tbl"
    assert config.file("TRAJ", "POSITION_FILE") is None


def test_min_ferror_defaults_to_ferror(tmp_path: Path) -> None:
    config = load_config(machine(tmp_path, JOINT_2__FERROR="2.5"))
    assert config.value("JOINT_2", "MIN_FERROR") == 2.5


@pytest.mark.parametrize(
    ("section", "key", "value", "cause"),
    [
        ("JOINT_0", "MAX_LIMIT", "nan", "is not a finite number; allowed: a number"),
        ("JOINT_0", "MAX_LIMIT", "inf", "is not a finite number; allowed: a number"),
        ("AXIS_X", "MIN_LIMIT", "-1e999", "is not a finite number; allowed: a number"),
        ("AXIS_X", "MIN_LIMIT", "1,5", "is not a finite number; allowed: a number"),
        ("JOINT_0", "MAX_ACCELERATION", "0", "is out of range; allowed: a number > 0"),
        ("AXIS_Y", "MAX_VELOCITY", "-3", "is out of range; allowed: a number > 0"),
        ("TASK", "CYCLE_TIME", "-5", "is out of range; allowed: a number > 0 and <= 1"),
        ("TASK", "CYCLE_TIME", "0", "is out of range; allowed: a number > 0 and <= 1"),
        ("TRAJ", "COORDINATES", "X Y Q", "names no axis Q; allowed: axis letters from XYZ"),
        ("TRAJ", "LINEAR_UNITS", "furlong", "is not allowed; allowed: one of mm, metric, in"),
        ("TRAJ", "SPINDLES", "9", "is out of range; allowed: an integer from 1 to 8"),
        ("KINS", "JOINTS", "2.5", "is not an integer; allowed: an integer from 1 to 16"),
        ("KINS", "JOINTS", "0", "is out of range; allowed: an integer from 1 to 16"),
        ("JOINT_1", "HOME_USE_INDEX", "maybe", "is not a flag; allowed: 1 or 0 (yes/no"),
        ("JOINT_1", "HOME_SEQUENCE", "999", "is out of range; allowed: an integer from -16"),
        ("JOINT_1", "HOME_ABSOLUTE_ENCODER", "3", "allowed: an integer from 0 to 2"),
        ("JOINT_1", "BACKLASH", "-0.1", "allowed: a number >= 0"),
        ("AXIS_Z", "OFFSET_AV_RATIO", "0.95", "allowed: a number from 0 to 0.9"),
        ("EMCIO", "TOOL_CHANGE_POSITION", "1 2", "has 2 numbers; allowed: 3 or 6 or 9 numbers"),
        ("EMCIO", "TOOL_CHANGE_POSITION", "0 0 nan", "is not a list of finite numbers"),
        ("EMCIO", "CYCLE_TIME", "0", "allowed: a number > 0 and <= 1"),
        ("EMCMOT", "SERVO_PERIOD", "0", "allowed: an integer > 0"),
        ("DISPLAY", "MAX_FEED_OVERRIDE", "-1", "allowed: a number > 0"),
    ],
)
def test_a_bad_value_is_refused_with_file_line_key_and_range(
    tmp_path: Path, section: str, key: str, value: str, cause: str
) -> None:
    path = machine(tmp_path, **{f"{section}__{key}": value})
    line = line_of(path, section, key)
    found = refused(path)
    assert len(found) == 1 and found[0].startswith(f"{path}:{line}: [{section}]{key} = '{value}' ")
    assert cause in found[0]


def test_every_bad_value_is_listed_at_once(tmp_path: Path) -> None:
    path = machine(tmp_path, JOINT_0__MAX_LIMIT="nan", TASK__CYCLE_TIME="0", KINS__JOINTS="x")
    found = refused(path)
    assert [line.split(": [")[1].split("]")[0] for line in found] == ["TASK", "KINS", "JOINT_0"]


def test_an_empty_ini_file_lacks_what_linuxcnc_cannot_start_without(tmp_path: Path) -> None:
    path = tmp_path / "empty.ini"
    path.write_text("")
    assert refused(path) == [
        f"{path}: [TRAJ]LINEAR_UNITS is missing (required: one of mm, metric, in, inch, imperial)",
        f"{path}: [TRAJ]ANGULAR_UNITS is missing (required: one of deg, degree, grad, gon, "
        "rad, radian)",
        f"{path}: [KINS]JOINTS is missing (required: an integer from 1 to 16)",
    ]


def test_a_joint_without_its_section_runs_on_defaults_with_a_warning(tmp_path: Path) -> None:
    """As LinuxCNC (its panelui-demo.ini has no [JOINT_1]), with a warning saying so."""
    text = MACHINE.replace("[JOINT_1]\nMIN_LIMIT = -100\nMAX_LIMIT = 100\n", "")
    path = machine(tmp_path, text)
    line = line_of(path, "KINS", "JOINTS")
    warnings = "\n".join(load_config(path).warnings)
    assert f"{path}:{line}: [KINS]JOINTS = 3 but [JOINT_1] is missing: LinuxCNC's defaults" in (
        warnings
    )


def test_a_trivkins_joint_of_an_axis_not_used_may_go_without_a_section(tmp_path: Path) -> None:
    """LinuxCNC's lathe configs: JOINTS = 3 with trivkins, COORDINATES = X Z, no [JOINT_1]."""
    text = MACHINE.replace("[JOINT_1]\nMIN_LIMIT = -100\nMAX_LIMIT = 100\n", "")
    text = text.replace("COORDINATES = X Y Z", "COORDINATES = X Z").replace("[AXIS_Y]", "[AXIS_V]")
    path = machine(tmp_path, text)
    config = load_config(path)
    line = line_of(path, "KINS", "JOINTS")
    assert f"{path}:{line}: there is no [JOINT_1]: trivkins joint 1 is axis Y" in "\n".join(
        config.warnings
    )
    # with coordinates=xz the second joint is Z: it runs on defaults, with a warning
    path = machine(tmp_path, text, KINS__KINEMATICS="trivkins coordinates=xz", KINS__JOINTS="2")
    warnings = "\n".join(load_config(path).warnings)
    assert "[KINS]JOINTS = 2 but [JOINT_1] is missing: LinuxCNC's defaults" in warnings


def test_limits_must_be_in_order(tmp_path: Path) -> None:
    path = machine(tmp_path, AXIS_Z__MIN_LIMIT="60")
    line = line_of(path, "AXIS_Z", "MIN_LIMIT")
    assert refused(path) == [f"{path}:{line}: [AXIS_Z]MIN_LIMIT = 60 is above MAX_LIMIT = 50"]


@pytest.mark.parametrize(
    ("changes", "key", "cause"),
    [
        ({"JOINT_2__HOME_SEARCH_VEL": "5"}, "HOME_SEARCH_VEL", "5 needs a non-zero HOME_LATCH"),
        ({"JOINT_2__HOME_LATCH_VEL": "1"}, "HOME_LATCH_VEL", "1 without HOME_SEARCH_VEL needs"),
    ],
)
def test_homing_velocities_linuxcnc_refuses_only_when_homing(
    tmp_path: Path, changes: dict[str, str], key: str, cause: str
) -> None:
    path = machine(tmp_path, **changes)
    line = line_of(path, "JOINT_2", key)
    found = refused(path)
    assert len(found) == 1 and found[0].startswith(f"{path}:{line}: [JOINT_2]{key} = {cause}")
    assert load_config(machine(tmp_path, JOINT_2__HOME_SEARCH_VEL="5", JOINT_2__HOME_LATCH_VEL="1"))


def test_an_ini_file_older_than_linuxcnc_2_8_says_how_to_convert_it(tmp_path: Path) -> None:
    path = tmp_path / "old.ini"
    path.write_text(
        "[EMC]\nVERSION = 1.0\n[TRAJ]\nLINEAR_UNITS = mm\nANGULAR_UNITS = deg\n[AXIS_0]\n"
    )
    found = refused(path)
    assert f"{path}:6: [AXIS_0]: an INI file in LinuxCNC's layout before 2.8" in found[-1]
    assert f"update_ini -d {path}" in found[-1]


def test_unknown_keys_are_warned_unless_a_hal_file_uses_them(tmp_path: Path) -> None:
    (tmp_path / "m.hal").write_text(
        "setp stepgen.0.position-scale [JOINT_0]SCALE_X\nsetp pid.0.Pgain $::JOINT_0(PGAIN)\n"
    )
    path = machine(
        tmp_path,
        HAL__HALFILE="m.hal",
        JOINT_0__SCALE_X="200",
        JOINT_0__PGAIN="1",
        JOINT_0__MAX_VELOCTY="20",  # the typo
        JOINT_0__P="100",  # documented for HAL files
        DISPLAY__ANY_GUI_KEY="1",  # [DISPLAY] belongs to the display
        PROBE__Z_OFFSET="12",  # a custom section
    )
    line = line_of(path, "JOINT_0", "MAX_VELOCTY")
    assert load_config(path).warnings == [
        f"{path}:{line}: [JOINT_0]MAX_VELOCTY is unknown: the controller does not read it and "
        "no HAL file uses it (a typo?)"
    ]


def test_a_repeated_key_uses_the_first_with_a_warning(tmp_path: Path) -> None:
    path = machine(tmp_path, TRAJ__MAX_LINEAR_VELOCITY="50\nMAX_LINEAR_VELOCITY = 70")
    config = load_config(path)
    assert config.value("TRAJ", "MAX_LINEAR_VELOCITY") == 50
    assert "[TRAJ]MAX_LINEAR_VELOCITY repeated: the first" in config.warnings[0]


def test_repeatable_keys_keep_every_value_in_order(tmp_path: Path) -> None:
    path = machine(tmp_path, HAL__HALFILE="a.hal\nHALFILE = b.hal")
    config = load_config(path)
    assert config.values("HAL", "HALFILE") == ["a.hal", "b.hal"]
    assert config.value("HAL", "HALFILE") == "a.hal"


def test_a_file_for_rs274_need_not_describe_a_machine() -> None:
    ini = IniFile.from_text("[EMCIO]\nRANDOM_TOOLCHANGER = 1\n[RS274NGC]\nRETAIN_G43 = 1\n")
    config = read_config(ini, is_machine=False)
    assert config.value("EMCIO", "RANDOM_TOOLCHANGER") and config.value("RS274NGC", "RETAIN_G43")
    with pytest.raises(ConfigError):
        read_config(ini)


def test_units_as_words_or_numbers(tmp_path: Path) -> None:
    for linear, angular, expected in [
        ("inch", "rad", ("inch", math.pi / 180)),
        ("1.0", "1.0", ("mm", 1.0)),
        ("0.03937007874016", "gon", ("inch", 10 / 9)),
        ("Metric", "DEG", ("mm", 1.0)),
    ]:
        config = load_config(
            machine(tmp_path, TRAJ__LINEAR_UNITS=linear, TRAJ__ANGULAR_UNITS=angular)
        )
        assert (config.value("TRAJ", "LINEAR_UNITS"), config.value("TRAJ", "ANGULAR_UNITS")) == (
            expected
        )


def test_adding_a_key_is_one_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """As the supervision heartbeats were added: one line in its section of SCHEMA."""
    keys = dict(SCHEMA["EMCMOT"].keys)
    keys["BRAKE_TIMEOUT"] = real("BRAKE_TIMEOUT", 0.5, above=0, high=10)
    monkeypatch.setattr(SCHEMA["EMCMOT"], "keys", keys)
    assert load_config(machine(tmp_path)).value("EMCMOT", "BRAKE_TIMEOUT") == 0.5
    path = machine(tmp_path, EMCMOT__BRAKE_TIMEOUT="0")
    assert refused(path) == [
        f"{path}:{line_of(path, 'EMCMOT', 'BRAKE_TIMEOUT')}: [EMCMOT]BRAKE_TIMEOUT = '0' "
        "is out of range; allowed: a number > 0 and <= 10"
    ]


def test_the_heartbeat_timeouts_are_checked(tmp_path: Path) -> None:
    """The defaults are those motion/safety.py, task/controller.py, iocontrol and halui use."""
    from motion.safety import DEFAULT_HEARTBEAT_TIMEOUT_S as MOTION
    from task.controller import DEFAULT_HEARTBEAT_TIMEOUT_S as TASK

    config = load_config(machine(tmp_path))
    assert (MOTION, TASK) == (0.5, 1.0)
    assert [config.value(section, "HEARTBEAT_TIMEOUT") for section in
            ("EMCMOT", "TASK", "EMCIO", "HALUI")] == [0.5, 1.0, 1.0, 1.0]  # fmt: skip
    path = machine(tmp_path, TASK__HEARTBEAT_TIMEOUT="nan")
    assert "[TASK]HEARTBEAT_TIMEOUT = 'nan' is not a finite number" in refused(path)[0]


def test_the_sizes_are_the_motion_controllers() -> None:
    from cnc.api.commands import TEXT_LIMIT
    from nml import emc

    assert (MAX_JOINTS, MAX_SPINDLES) == (emc.EMCMOT_MAX_JOINTS, emc.EMCMOT_MAX_SPINDLES)
    assert MDI_COMMAND_BYTES == TEXT_LIMIT


def test_every_default_is_within_its_bounds() -> None:
    for section in SCHEMA.values():
        for key in section.keys.values():
            if isinstance(key.default, (int, float)) and not isinstance(key.default, bool):
                assert key.check(key.default) is None, f"[{section.name}]{key.name}"


def test_task_tells_motion_every_joint_key_with_linuxcncs_defaults(tmp_path: Path) -> None:
    from nml import emc
    from task.setup import load_setup

    path = machine(
        tmp_path,
        JOINT_2__HOME_ABSOLUTE_ENCODER="2",
        JOINT_2__VOLATILE_HOME="yes",
        JOINT_2__HOME_INDEX_NO_ENCODER_RESET="1",
    )
    setup = load_setup(IniFile.load(path))
    homing = [m for m in setup.motion_init_messages() if type(m) is emc.EMC_JOINT_SET_HOMING_PARAMS]
    assert [m.home_sequence for m in homing] == [0, emc.NO_HOME_SEQUENCE, emc.NO_HOME_SEQUENCE]
    last = homing[2]
    assert (last.absolute_encoder, last.volatile_home, last.encoder_does_not_reset) == (2, 1, 1)
    assert last.home_final_vel == -1.0
    types = [type(m) for m in setup.motion_init_messages()]
    assert emc.EMC_TRAJ_SET_MAX_VELOCITY in types  # [TRAJ]MAX_LINEAR_VELOCITY is set
    assert emc.EMC_TRAJ_SET_MAX_ACCELERATION not in types  # not set: the axes' limits apply
    assert (setup.cycle_time, setup.parameter_file) == (0.01, str(tmp_path / "sim.var"))


def test_task_tells_motion_the_spindle_limits_reverse_defaulting_to_forward(
    tmp_path: Path,
) -> None:
    """As LinuxCNC's tests/spindle_limits: a missing reverse limit is the forward one."""
    from nml import emc
    from task.setup import load_setup

    path = machine(
        tmp_path,
        TRAJ__SPINDLES="2",
        SPINDLE_0__MAX_FORWARD_VELOCITY="2000",
        SPINDLE_0__MIN_FORWARD_VELOCITY="200",
        SPINDLE_0__MAX_REVERSE_VELOCITY="2500",
    )
    setup = load_setup(IniFile.load(path))
    sent = [m for m in setup.motion_init_messages() if type(m) is emc.EMC_SPINDLE_SET_PARAMS]
    assert [m.spindle for m in sent] == [0, 1]
    first, second = sent
    limits = (first.max_forward, first.min_forward, first.max_reverse, first.min_reverse)
    assert limits == (2000.0, 200.0, 2500.0, 200.0)
    assert (second.min_forward, second.min_reverse) == (0.0, 0.0)
    assert second.max_reverse == second.max_forward >= 1e9  # no limit


def test_task_refuses_a_bad_parameter_file_before_reading_it(tmp_path: Path) -> None:
    from task.setup import load_setup

    path = machine(tmp_path)
    (tmp_path / "sim.var").write_text("5220\t1\n5161\tx\n")
    with pytest.raises(IniError, match=r"sim\.var:2: not '<parameter number> <value>': 5161 x"):
        load_setup(IniFile.load(path))


def test_every_key_the_controller_reads_is_in_the_schema() -> None:
    """A key read by name anywhere in the controller (``ini.find("TASK", "X")``) is declared
    here, so it is checked at start-up and never warned about as unknown."""
    import re

    read = re.compile(r"\(\s*\"([A-Z][A-Z_0-9]*)\",\s*\"([A-Z][A-Z_0-9]*)\"")
    root = Path(__file__).resolve().parents[2]
    missing = set()
    for package in ("cnc", "task", "motion", "iocontrol", "hal", "nml"):
        for source in (root / package).rglob("*.py"):
            if source.name == "inischema.py":
                continue
            for section, key in read.findall(source.read_text()):
                found = schema_section(section)
                if found is not None and not found.is_open and key not in found.keys:
                    missing.add(f"[{section}]{key} ({source.relative_to(root)})")
    assert sorted(missing) == []
