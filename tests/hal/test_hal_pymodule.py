"""LinuxCNC's Python ``hal`` module (``import hal``): what a script written for LinuxCNC
sees, checked line by line against LinuxCNC 2.9's own module (files/README.md)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import hal
from hal.api import set_shared_hal, shared_hal
from tests.hal.halrun_util import FILES, REPO


@pytest.fixture
def clean_hal():  # type: ignore[no-untyped-def]
    set_shared_hal(None)  # (an earlier test's host may have left its own, closed)
    yield shared_hal()
    own = shared_hal()
    set_shared_hal(None)
    own.destroy()
    own.close()


def _halcmd_on_path(folder: Path) -> dict[str, str]:
    """An environment whose ``halcmd`` is ours (the probe runs it)."""
    script = folder / "halcmd"
    script.write_text(f'#!/bin/sh\nexec {sys.executable} -m cnc halcmd "$@"\n')
    script.chmod(0o755)
    return {**os.environ, "PATH": f"{folder}{os.pathsep}{os.environ['PATH']}"}


def test_a_script_sees_what_linuxcnc_shows_it(tmp_path: Path) -> None:
    env = _halcmd_on_path(tmp_path)
    try:
        result = subprocess.run(
            [sys.executable, str(FILES / "pyhal_probe.py")],
            capture_output=True,
            text=True,
            cwd=REPO,
            env=env,
            timeout=60,
        )
    finally:
        subprocess.run([sys.executable, "-m", "cnc", "halrun", "-U"], env=env, timeout=60)
    assert result.returncode == 0, result.stderr
    expected = (FILES / "lcnc_pyhal_probe_output.txt").read_text().splitlines()
    assert result.stdout.splitlines() == expected


def test_from_hal_import_star_gives_linuxcncs_names() -> None:
    namespace: dict[str, object] = {}
    exec("from hal import *", namespace)
    assert {"component", "HAL_FLOAT", "HAL_IN", "stream", "connect", "error"} <= set(namespace)
    assert "core" not in namespace  # our own modules stay out of the way


def test_component_attributes_items_and_exit(clean_hal) -> None:  # type: ignore[no-untyped-def]
    comp = hal.component("ui", prefix="ui.0")
    speed = comp.newpin("speed", hal.HAL_FLOAT, hal.HAL_OUT)
    comp.newparam("gain", hal.HAL_S32, hal.HAL_RW)
    assert speed.get_name() == "speed" and speed.name == "speed"
    comp.speed = 2.5  # an attribute write is a pin write
    comp["gain"] = 7
    assert hal.get_value("ui.0.speed") == 2.5 and comp.gain == 7
    assert clean_hal.meta["comps"]["ui"]["kind"] == "user"
    comp.exit()
    assert not hal.component_exists("ui")
    with pytest.raises(RuntimeError, match="closed HAL component"):
        comp["speed"]


def test_loadusr_runs_a_python_component_with_our_hal(tmp_path: Path) -> None:
    """A Python program loadusr starts imports our ``hal`` whatever its first line says."""
    program = tmp_path / "mycomp.py"
    program.write_text(
        "#!/usr/bin/python3\nimport hal, time\nc = hal.component('mycomp')\n"
        "c.newpin('out', hal.HAL_S32, hal.HAL_OUT)\nc['out'] = 42\nc.ready()\n"
        "try:\n    while True:\n        time.sleep(0.05)\nexcept KeyboardInterrupt:\n"
        "    raise SystemExit(0)\n"
    )
    program.chmod(0o755)
    result = subprocess.run(
        [sys.executable, "-m", "cnc", "halrun", "-f", "/dev/stdin"],
        input=f"loadusr -W {program}\ngetp mycomp.out\nunload mycomp\nlist comp\n",
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == "42"
    assert "mycomp" not in result.stdout.splitlines()[1]
