"""GUI parts of a config on a machine without a display (issue 17, "Configs whose parts are
GUI toolkits"): skipped with a warning, their pins stood in for when a net needs them."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from cnc.halfiles import LauncherHalCmd, gui_component_name, gui_toolkit
from hal.core import HAL_FLOAT, HAL_IN, HAL_OUT, HAL_S32


@pytest.fixture
def launcher_hal() -> Iterator[tuple[LauncherHalCmd, list[str]]]:
    warnings: list[str] = []
    session = LauncherHalCmd(is_headless=True, warn=warnings.append)
    with session.hal.edit():
        session.hal.new_component("tc")
        session.hal.new_pin("tc", "tc.in", HAL_FLOAT, HAL_IN)
        session.hal.new_pin("tc", "tc.out", HAL_FLOAT, HAL_OUT)
    try:
        yield session, warnings
    finally:
        session.run_words(["unload", "all"])
        session.hal.close()
        session.hal.destroy()


def test_a_panel_is_skipped_and_nets_get_placeholder_pins(
    launcher_hal: tuple[LauncherHalCmd, list[str]],
) -> None:
    session, warnings = launcher_hal
    assert session.run_words(["loadusr", "-Wn", "panel", "pyvcp", "-c", "panel", "panel.xml"])
    assert "skipping loadusr of the PyVCP panel 'pyvcp'" in warnings[-1]
    # a net with a pin of the panel: made, the pin an input of the signal's type
    assert session.run_words(["net", "speed", "tc.out", "=>", "panel.speed"])
    pin = session.hal.meta["pins"]["panel.speed"]
    assert (pin["type"], pin["dir"], pin["sig"], pin["owner"]) == (
        HAL_FLOAT,
        HAL_IN,
        "speed",
        "panel",
    )
    assert "a placeholder float input pin stands in for it on signal 'speed'" in warnings[-1]
    # a panel output driving a new signal with nothing else: left out, reported, no failure
    assert session.run_words(["net", "button", "panel.button"])
    assert "button" not in session.hal.meta["sigs"]
    assert "its type is unknown" in warnings[-1]
    # setp of a panel pin is skipped; waitusr of the panel does not wait
    assert session.run_words(["setp", "panel.led", "1"])
    assert "setp panel.led: skipped" in warnings[-1]
    assert session.run_words(["waitusr", "panel"])
    # other pins still fail as usual
    assert not session.run_words(["net", "x", "nobody.pin"])
    session.run_words(["unload", "all"])
    assert "panel" not in session.hal.meta["comps"]


def test_which_programs_are_gui(tmp_path: Path) -> None:
    model = tmp_path / "mymodel"
    model.write_text("#!/usr/bin/env python3\nfrom vismach import *\n")
    plain = tmp_path / "plain"
    plain.write_text("#!/usr/bin/env python3\nimport hal\n")
    assert gui_toolkit(str(model), []) == "GUI program (vismach)"
    assert gui_toolkit(str(plain), []) == ""
    assert gui_toolkit("classicladder", ["demo.clp"]) == "classicladder editor"
    assert gui_toolkit("classicladder", ["--nogui", "demo.clp"]) == ""
    assert gui_toolkit("lineardelta", ["MIN_JOINT=-420"]) == "vismach model"
    assert gui_component_name("gladevcp", ["-u", "h.py", "panels/probe.ui"]) == "probe"
    assert gui_component_name("pyvcp", ["vcp.xml"]) == "pyvcp"
    assert gui_component_name("./5axisgui", []) == "5axisgui"


def test_hal_manualtoolchange_confirms_each_change(
    launcher_hal: tuple[LauncherHalCmd, list[str]],
) -> None:
    session, _ = launcher_hal
    assert session.run_words(["loadusr", "-W", "hal_manualtoolchange"])
    pins = session.hal.meta["pins"]
    assert pins["hal_manualtoolchange.number"]["type"] == HAL_S32
    assert session.run_words(["setp", "hal_manualtoolchange.number", "7"])
    assert session.run_words(["setp", "hal_manualtoolchange.change", "1"])
    assert wait_for(session, "hal_manualtoolchange.changed", 1)
    assert session.run_words(["setp", "hal_manualtoolchange.change", "0"])
    assert wait_for(session, "hal_manualtoolchange.changed", 0)


def wait_for(session: LauncherHalCmd, pin: str, value: int) -> bool:
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        found = session.hal.find_pin(pin)
        if found and session.hal.pin_value(found[1]) == value:
            return True
        time.sleep(0.01)
    return False


def test_a_gui_program_runs_when_there_is_a_display(tmp_path: Path) -> None:
    session = LauncherHalCmd(is_headless=False, warn=lambda text: None)
    try:
        # not headless: the program is started as usual (here a script that just exits)
        script = tmp_path / "panel"
        script.write_text(f"#!{sys.executable}\nimport tkinter\n")
        script.chmod(0o755)
        assert session.run_words(["loadusr", "-w", str(script)])
        assert not session.skipped
    finally:
        session.hal.close()
        session.hal.destroy()
