"""[HAL]TWOPASS: loadrt merged across HAL files, the rest run in a second pass (issue 17)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cnc.ini import IniFile
from hal.halcmd import HalCmd
from hal.hallib import find_halfile
from hal.twopass import TwoPass
from tests.launch.conftest import needs_tcl

pytestmark = needs_tcl


def twopass(session: HalCmd, tmp_path: Path, files: dict[str, str], options: str = "on") -> bool:
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    ini_text = "[HAL]\nTWOPASS = on\n" + "".join(f"HALFILE = {name}\n" for name in files)
    ini = IniFile.from_text(ini_text, str(tmp_path / "test.ini"))
    halfiles = [find_halfile(name, tmp_path) for name in files]
    return TwoPass(session, ini, halfiles, options).run()


def test_loadrt_of_one_module_in_several_files_is_merged(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    files = {
        "threads.hal": "loadrt threads name1=t period1=1000000\n",
        "a.hal": "loadrt and2 names=a1\naddf a1 t\nsetp a1.in0 1\n",
        "b.tcl": "loadrt and2 names=b1,b2\naddf b1 t\nnet x a1.out b1.in0\n"
        'puts "pass [::tp::passnumber]"\n',
        "later.hal": "#  NoTwoPass (run once, at once)\nloadrt or2 names=n1\n",
    }
    assert twopass(session, tmp_path, files)
    meta = session.hal.meta
    assert meta["threads"]["t"]["functs"] == ["a1", "b1"]  # addf where it stands, in pass 1
    assert meta["pins"]["b1.in0"]["sig"] == "x"
    assert {"a1.out", "b2.out", "n1.out"} <= set(meta["pins"])
    modules = session.host.call({"cmd": "modules"}).get("modules", {})
    assert "and2" in modules  # one module, all three instances
    out = capfd.readouterr().out.splitlines()
    assert [line for line in out if line.startswith("pass")] == ["pass 0", "pass 1"]


def test_mixing_count_and_names_is_refused_with_the_file_and_line(
    session: HalCmd, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    files = {"a.hal": "loadrt and2 count=1\n", "b.hal": "\nloadrt and2 names=x\n"}
    assert not twopass(session, tmp_path, files)
    err = capfd.readouterr().err
    assert f"{tmp_path / 'b.hal'}:2: loadrt and2: cannot mix count=, num_chan= and names=" in err


def test_counts_add_up(session: HalCmd, tmp_path: Path) -> None:
    files = {"a.hal": "loadrt not count=2\n", "b.tcl": "loadrt not count=1\n"}
    assert twopass(session, tmp_path, files)
    assert {"not.0.out", "not.1.out", "not.2.out"} <= set(session.hal.meta["pins"])
