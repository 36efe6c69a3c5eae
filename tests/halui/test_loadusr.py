"""``loadusr halui`` in a HAL file starts our halui (``python -m cnc.halui``): its pins are
there once ``-W`` returns, even before the controller runs, and ``unloadusr`` removes them."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from hal.core import Hal
from hal.halcmd import HalCmd


@pytest.fixture
def hal() -> Iterator[Hal]:
    h = Hal()
    yield h
    h.destroy()
    h.close()


def test_loadusr_halui_waits_for_its_pins_and_unloadusr_removes_them(
    hal: Hal, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ini = tmp_path / "machine.ini"
    ini.write_text("[KINS]\nJOINTS = 2\n[HALUI]\nMDI_COMMAND = G0 X0\n")
    monkeypatch.setenv("CNC_INI_FILE", str(ini))  # what `cnc run` gives the programs it starts
    halcmd = HalCmd(hal=hal)
    try:
        assert halcmd.run_words(["loadusr", "-W", "halui"])
        comp = hal.meta["comps"]["halui"]
        assert comp["kind"] == "user" and comp["is_ready"]
        pins = hal.meta["pins"]
        assert "halui.mdi-command-00" in pins and "halui.joint.1.home" in pins
        assert "halui.joint.2.home" not in pins
    finally:
        halcmd.run_words(["unloadusr", "halui"])
    assert "halui" not in hal.meta["comps"]
    assert not any(name.startswith("halui.") for name in hal.meta["pins"])
