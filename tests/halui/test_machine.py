"""halui on a whole machine: ``cnc run`` starts it from [HAL]HALUI and the test is the
operator's panel, setting ``halui.*`` pins in HAL and watching the ``is-*`` pins follow.

One machine (tests/halui/machine: task's test mill with halui and two MDI buttons) serves
every test of this module, in order; the tests share its IPC instance, checked for leftovers
once the machine has stopped.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from cnc.runtime import read_runtime_info
from hal.core import Hal
from hal.halcmd import HalCmd
from nml.ipcnames import INSTANCE_ENV, remove_instance_objects
from tests.conftest import Processes

MACHINE = Path(__file__).with_name("machine")
WAIT_S = 20.0


class Panel:
    """The machine's HAL as an operator's panel sees it: buttons to set, lamps to watch."""

    def __init__(self, hal: Hal) -> None:
        self.hal = hal
        self.halcmd = HalCmd(hal=hal)

    def value(self, name: str) -> Any:
        found = self.hal.find_pin(name)
        assert found is not None, f"no pin {name}"
        return self.hal.pin_value(found[1])

    def setp(self, name: str, value: float) -> None:
        assert self.halcmd.run_words(["setp", name, str(value)])

    def until(self, name: str, expected: float) -> None:
        """Until pin ``name`` shows ``expected``."""
        deadline = time.monotonic() + WAIT_S
        while self.value(name) != pytest.approx(expected):
            assert time.monotonic() < deadline, f"{name} = {self.value(name)}, not {expected}"
            time.sleep(0.01)

    def press(self, button: str, lamp: str, expected: float = 1) -> None:
        """Press ``button`` until ``lamp`` shows ``expected``, then release it."""
        self.setp(button, 1)
        self.until(lamp, expected)
        self.setp(button, 0)


@pytest.fixture(scope="module")
def module_instance() -> Iterator[str]:
    instance = f"t{os.getpid()}-halui"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(INSTANCE_ENV, instance)
        yield instance
    leftovers = remove_instance_objects(instance)
    assert not leftovers, f"the machine left IPC objects behind (now removed): {leftovers}"


@pytest.fixture(autouse=True)
def cnc_instance(module_instance: str) -> str:
    """Replaces tests/conftest.py's per-test instance: the tests here share one machine."""
    return module_instance


@pytest.fixture(scope="module")
def panel(module_instance: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Panel]:
    folder = tmp_path_factory.mktemp("halui") / "machine"
    shutil.copytree(MACHINE, folder)
    procs = Processes()
    launcher = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    hal = None
    try:
        deadline = time.monotonic() + WAIT_S
        while (info := read_runtime_info()) is None or info.pid != launcher.pid:
            assert launcher.poll() is None, launcher.communicate()[1]
            assert time.monotonic() < deadline, "the machine did not come up"
            time.sleep(0.05)
        hal = Hal(is_creating=False)
        yield Panel(hal)
    finally:
        if hal is not None:
            hal.close()
        launcher.send_signal(signal.SIGTERM)  # the launcher stops halui with the rest
        with contextlib.suppress(subprocess.TimeoutExpired):
            launcher.wait(timeout=30)
        procs.kill_all()


def test_halui_starts_before_the_hal_files_and_shows_the_machine_at_rest(panel: Panel) -> None:
    # mill.hal nets halui.machine.is-on: halui's pins existed when it ran, as in LinuxCNC
    assert panel.hal.meta["pins"]["halui.machine.is-on"]["sig"] == "machine-is-on"
    panel.until("halui.estop.is-activated", 1)
    assert panel.value("halui.machine.is-on") == 0
    assert panel.value("halui.mode.is-manual") == 1
    assert panel.value("halui.program.is-idle") == 1
    assert panel.value("halui.joint.0.is-homed") == 0
    assert panel.value("halui.feed-override.value") == 1.0
    assert panel.value("halui.mdi-command-01") == 0  # one pin per [HALUI]MDI_COMMAND


def test_panel_buttons_drive_the_machine_and_the_lamps_follow(panel: Panel) -> None:
    panel.press("halui.estop.reset", "halui.estop.is-activated", 0)
    panel.press("halui.machine.on", "halui.machine.is-on")
    panel.press("halui.home-all", "halui.joint.2.is-homed")  # Z first: HOME_SEQUENCE 0
    panel.until("halui.joint.0.is-homed", 1)
    panel.until("halui.joint.1.is-homed", 1)
    assert panel.value("halui.axis.z.pos-feedback") == pytest.approx(10.0)  # [JOINT_2]HOME

    # G0 X10 Y-5 in MDI mode, then back to manual mode once the move has ended
    panel.press("halui.mdi-command-00", "halui.axis.x.pos-commanded", 10.0)
    panel.until("halui.axis.y.pos-feedback", -5.0)
    panel.until("halui.mode.is-manual", 1)
    assert panel.value("halui.program.is-idle") == 1

    panel.press("halui.mdi-command-01", "halui.mist.is-on")  # M7

    # an encoder on feed-override.counts: +5 x 0.1, held at [DISPLAY]MAX_FEED_OVERRIDE
    panel.setp("halui.feed-override.counts", 5)
    panel.until("halui.feed-override.value", 1.2)
    panel.press("halui.feed-override.decrease", "halui.feed-override.value", 1.1)

    panel.press("halui.machine.off", "halui.machine.is-on", 0)
