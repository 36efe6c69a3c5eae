"""The cnc namespace: cheap import, LinuxCNC's constants, cnc.ini, cnc.error."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import cnc
from nml import emc
from tests.conftest import REPO


def test_import_cnc_loads_neither_numpy_nor_nml() -> None:
    code = (
        "import sys, cnc; cnc.STATE_ESTOP; cnc.ini; cnc.error; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'nml')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True
    ).stdout
    assert out.strip() == "[]"


def test_constants_have_linuxcncs_values() -> None:
    groups = [
        ("STATE_", emc.EMC_TASK_STATE_ENUM),
        ("MODE_", emc.EMC_TASK_MODE_ENUM),
        ("INTERP_", emc.EMC_TASK_INTERP_ENUM),
        ("EXEC_", emc.EMC_TASK_EXEC_ENUM),
        ("TRAJ_MODE_", emc.EMC_TRAJ_MODE_ENUM),
        ("MOTION_TYPE_", emc.EMC_MOTION_TYPE),
        ("KINEMATICS_", emc.KINEMATICS_TYPE),
        ("SPINDLE_", emc.LOCAL_SPINDLE),
        ("JOG_", emc.LOCAL_JOG),
        ("AUTO_", emc.LOCAL_AUTO),
        ("DEBUG_", emc.EMC_DEBUG),
    ]
    for prefix, enum in groups:
        names = [name for name in dir(cnc.api.constants) if name.startswith(prefix)]
        assert names, prefix
        for name in names:
            assert getattr(cnc, name) == enum[name[len(prefix) :]], name
    assert (cnc.LINEAR, cnc.ANGULAR) == (emc.EmcJointType.LINEAR, emc.EmcJointType.ANGULAR)
    assert (cnc.RCS_DONE, cnc.RCS_EXEC, cnc.RCS_ERROR) == (1, 2, 3)
    assert (cnc.OPERATOR_ERROR, cnc.OPERATOR_TEXT, cnc.OPERATOR_DISPLAY) == (
        emc.EMC_OPERATOR_ERROR.TYPE,
        emc.EMC_OPERATOR_TEXT.TYPE,
        emc.EMC_OPERATOR_DISPLAY.TYPE,
    )
    assert (cnc.NML_ERROR, cnc.NML_TEXT, cnc.NML_DISPLAY) == (1, 2, 3)
    assert (cnc.MAX_JOINTS, cnc.MAX_AXIS) == (emc.EMCMOT_MAX_JOINTS, emc.EMCMOT_MAX_AXIS)
    assert (cnc.FLOOD_ON, cnc.MIST_OFF, cnc.BRAKE_ENGAGE) == (1, 0, 1)


def test_ini_finds_values_as_linuxcnc_does(tmp_path: Path) -> None:
    path = tmp_path / "mill.ini"
    path.write_text("[EMC]\nMACHINE = mill\n[HAL]\nHALFILE = a.hal\nHALFILE = b.hal\n")
    ini = cnc.ini(str(path))
    assert ini.find("EMC", "MACHINE") == "mill"
    assert ini.find("EMC", "NOPE") is None
    assert ini.find("HAL", "HALFILE", 2) == "b.hal"
    assert ini.find("HAL", "HALFILE", 3) is None
    assert ini.findall("HAL", "HALFILE") == ["a.hal", "b.hal"]
    assert ini.findall("HAL", "NOPE") == []
    with pytest.raises(cnc.error, match=r"inifile\.open"):
        cnc.ini(str(tmp_path / "missing.ini"))


def test_cnc_ini_is_still_the_ini_module() -> None:
    from cnc.ini import IniFile

    assert cnc.ini.IniFile is IniFile


def test_error_is_a_runtime_error_and_dir_lists_the_api() -> None:
    assert issubclass(cnc.error, RuntimeError)
    for name in ("stat", "command", "error_channel", "ini", "error", "STATE_ON", "tool"):
        assert name in dir(cnc)
    with pytest.raises(AttributeError):
        cnc.no_such_name  # noqa: B018
