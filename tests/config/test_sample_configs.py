"""The INI schema accepts what users have: LinuxCNC 2.9's sample configs (every one where
LinuxCNC is installed, the copies in tests/config/linuxcnc/ everywhere), and every INI file
of this project (configs/, tests/), with no error."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniFile
from cnc.inischema import ConfigError, load_config, read_config

REPO = Path(__file__).resolve().parents[2]
COPIES = REPO / "tests" / "config" / "linuxcnc"
INSTALLED = Path("/usr/share/doc/linuxcnc/examples/sample-configs")

# Sample INI files that are not machines: a panelui key layout, a display's settings file
NOT_MACHINES = {"sim/axis/panelui-demo/_panelui.ini", "sim/craftsman/cnc_settings.ini"}
# Refused by design, each with the reason the start-up gives
REFUSED = {
    # LinuxCNC's layout before 2.8, which its launcher converts (update_ini) before running
    "sim/axis/vismach/rolfmill/rolfmill.ini": "an INI file in LinuxCNC's layout before 2.8",
    "sim/craftsman/craftsmancnc-axis.ini": "an INI file in LinuxCNC's layout before 2.8",
}


def sample_inis(root: Path) -> list[str]:
    return sorted(str(path.relative_to(root)) for path in root.rglob("*.ini"))


def check(root: Path, name: str) -> None:
    path = root / name
    if name in REFUSED:
        with pytest.raises(ConfigError) as caught:
            load_config(path)
        assert REFUSED[name] in str(caught.value)
    else:
        load_config(path)  # no ConfigError


@pytest.mark.parametrize("name", sample_inis(COPIES))
def test_linuxcncs_sample_configs_copied_here(name: str) -> None:
    check(COPIES, name)


@pytest.mark.skipif(not INSTALLED.is_dir(), reason="LinuxCNC's sample configs are not installed")
def test_every_installed_linuxcnc_sample_config() -> None:
    names = [name for name in sample_inis(INSTALLED) if name not in NOT_MACHINES]
    assert len(names) > 250
    failures = []
    for name in names:
        try:
            check(INSTALLED, name)
        except (ConfigError, pytest.fail.Exception) as exc:
            failures.append(f"{name}: {exc}")
    assert failures == []


def test_the_copies_are_linuxcncs_unchanged() -> None:
    if not INSTALLED.is_dir():
        pytest.skip("LinuxCNC's sample configs are not installed")
    for copy in COPIES.rglob("*.in[ic]"):
        original = INSTALLED / copy.relative_to(COPIES)
        assert copy.read_bytes() == original.read_bytes(), copy


def test_includes_demo_reads_its_included_files_and_warns_what_linuxcnc_prints() -> None:
    folder = COPIES / "sim" / "axis" / "ini_with_includes"
    config = load_config(folder / "includes_demo.ini")
    assert config.value("JOINT_0", "MAX_VELOCITY") == 5
    assert config.entry("JOINT_0", "MAX_VELOCITY").file == str(folder / "joint_0.inc")
    assert IniFile.load(folder / "includes_demo.ini").find("EXAMPLE_C", "parm6") == "6 66"
    assert [w.split(": ", 1)[1] for w in config.warnings if "#INCLUDE" in w] == [
        "#INCLUDE without a file name: ignored",
        f"#INCLUDE nosuchfile: cannot read {folder / 'nosuchfile'}: ignored",
    ]


def test_the_line_without_equals_in_mm_base_inc_is_ignored_as_linuxcnc_does() -> None:
    folder = COPIES / "sim" / "axis" / "xhc-hb04"
    config = load_config(folder / "xhc-hb04-layout2_mm.ini")
    assert f"{folder / 'mm_base.inc'}:22: ignored, not KEY = VALUE: duh" in config.warnings


def project_inis() -> list[Path]:
    found = sorted((REPO / "configs").rglob("*.ini")) + sorted((REPO / "tests").rglob("*.ini"))
    return [path for path in found if COPIES not in path.parents]


@pytest.mark.parametrize("path", project_inis(), ids=lambda path: str(path.relative_to(REPO)))
def test_every_ini_file_of_this_project(path: Path) -> None:
    """Machines are checked whole and without a warning; the interpreter corpus's files
    (for ``cnc rs274 -i``) are checked for the values they hold."""
    ini = IniFile.load(path)
    if "interp" in path.parts:
        read_config(ini, is_machine=False)
    else:
        assert read_config(ini).warnings == []
