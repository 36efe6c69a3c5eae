"""[HAL]HALFILE/HALCMD from an INI file, and components loaded from user files."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from hal.core import Hal
from hal.halcmd import run_ini_halfiles
from hal.rtapi_app import HostClient, release_if_unused
from tests.hal.halrun_util import FILES, halrun_text

SLEEP = f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.05)'\n"


def test_halfiles_then_halcmd_in_ini_order(tmp_path: Path) -> None:
    (tmp_path / "a.hal").write_text("newsig first s32\nsets first [HAL]VALUE\n")
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "b.hal").write_text("newsig second s32\nsets second 2\n")
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[HAL]\nVALUE = 7\nHALFILE = a.hal\nHALFILE = sub/b.hal\n"
        "HALCMD = sets second 3\nPOSTGUI_HALFILE = a.hal\n"
    )
    hal = Hal()
    try:
        assert run_ini_halfiles(str(ini)) == 0
        sigs = hal.meta["sigs"]
        assert hal.q[sigs["first"]["slot"]] == 7
        assert hal.q[sigs["second"]["slot"]] == 3
        assert run_ini_halfiles(str(ini), is_postgui=True) == 1  # 'first' exists already
    finally:
        release_if_unused(hal)
        hal.close()


def test_missing_halfile_is_reported_with_the_ini(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    ini = tmp_path / "m.ini"
    ini.write_text("[HAL]\nHALFILE = nope.hal\n")
    hal = Hal()
    try:
        assert run_ini_halfiles(str(ini)) == 1
        assert f"{ini}: [HAL]HALFILE: HAL file 'nope.hal' not found" in capsys.readouterr().err
    finally:
        release_if_unused(hal)
        hal.close()


def test_component_from_a_file_and_from_the_search_path(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    text = (
        "loadrt threads name1=t period1=1000000\n"
        f"loadrt {FILES / 'blend.py'} names=mix\n"
        "setp mix.in1 4\naddf mix t\nstart\n" + SLEEP + "getp mix.out\ngetp mix.mixing\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["2", "TRUE"]
    monkeypatch.setenv("CNC_HAL_COMPONENTS", str(FILES))
    result = halrun_text(tmp_path, "loadrt blend\nlist pin blend.0.in\n")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["blend.0.in0", "blend.0.in1"]
    assert os.environ["CNC_HAL_COMPONENTS"] == str(FILES)
    assert not HostClient().is_running()
