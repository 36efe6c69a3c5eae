"""[HAL]HALFILE search as LinuxCNC's launcher does it (issue 17, "HAL file search")."""

from __future__ import annotations

from pathlib import Path

import pytest

from hal.core import HalError
from hal.hallib import LIBRARY_DIR, exported_environment, find_halfile, search_path

# every hallib file LinuxCNC 2.9's sample sim configs name (HALFILE entries and sources)
SAMPLE_CONFIG_LIBRARY = [
    "axis_manualtoolchange.hal",
    "basic_sim.tcl",
    "check_xyz_constraints.hal",
    "core_sim.hal",
    "core_sim9.hal",
    "gantrysim.hal",
    "hal_procs_lib.tcl",
    "hookup_moveoff.tcl",
    "lathe.hal",
    "locking_indexer.hal",
    "moveoff_external.hal",
    "sim_lib.tcl",
    "sim_ldelta.hal",
    "sim_rdelta.hal",
    "sim_spindle_encoder.hal",
    "simulated-gantry-home.hal",
    "simulated_home.hal",
    "util_lib.tcl",
    "wheeljogpins.tcl",
    "xhc-hb04.tcl",
    "xhc-hb04-layout1.cfg",
    "xhc-hb04-layout2.cfg",
]


@pytest.mark.parametrize("name", SAMPLE_CONFIG_LIBRARY)
def test_the_library_has_every_file_the_sample_configs_use(name: str) -> None:
    assert (LIBRARY_DIR / name).is_file()
    assert find_halfile(f"LIB:{name}", "/nonexistent").path == LIBRARY_DIR / name


def test_the_config_folder_comes_before_the_library(tmp_path: Path) -> None:
    (tmp_path / "core_sim.hal").write_text("# mine\n")
    found = find_halfile("core_sim.hal", tmp_path)
    assert (found.path, found.how) == (tmp_path / "core_sim.hal", "REL")
    # LIB: skips the config folder
    assert find_halfile("LIB:core_sim.hal", tmp_path).path == LIBRARY_DIR / "core_sim.hal"
    # not in the config folder: the library
    found = find_halfile("simulated_home.hal", tmp_path)
    assert (found.path, found.how) == (LIBRARY_DIR / "simulated_home.hal", "lib")


def test_h_folders_come_first_and_arguments_are_kept(tmp_path: Path) -> None:
    extra = tmp_path / "extra"
    extra.mkdir()
    (extra / "basic_sim.tcl").write_text("# override\n")
    found = find_halfile("basic_sim.tcl -no_sim_spindle  -NO_MAKE_DDTS", tmp_path, [str(extra)])
    assert found.path == extra / "basic_sim.tcl"
    assert found.args == ["-no_sim_spindle", "-NO_MAKE_DDTS"]
    assert found.is_tcl
    assert search_path(tmp_path, [str(extra)]) == [extra, tmp_path, LIBRARY_DIR]


def test_absolute_and_home_relative_names(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    hal = tmp_path / "abs.hal"
    hal.write_text("\n")
    assert find_halfile(str(hal), "/nonexistent").how == "ABS"
    monkeypatch.setenv("HOME", str(tmp_path))
    assert find_halfile("~/abs.hal", "/nonexistent").path == hal


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("LIB:", "nothing after 'LIB:'"),
        ("LIB:nowhere.hal", "not found in the HAL library"),
        ("/no/such/file.hal", "'/no/such/file.hal' not found"),
        ("nowhere.hal", "not found (looked in"),
        ("", "empty HALFILE entry"),
    ],
)
def test_a_missing_file_says_where_it_looked(tmp_path: Path, value: str, message: str) -> None:
    with pytest.raises(HalError, match=message.replace("(", r"\(")):
        find_halfile(value, tmp_path)


def test_exported_environment_is_linuxcncs(tmp_path: Path) -> None:
    env = exported_environment(tmp_path, ["/x"])
    assert env == {"HALLIB_DIR": str(LIBRARY_DIR), "HALLIB_PATH": f"/x:{tmp_path}:{LIBRARY_DIR}"}
