"""Every machine of configs/sim/ runs end to end (issue 6 "Configs and text UIs"): started
by ``cnc run --headless``, driven by a ``cnc sh`` script (E-stop reset, machine on, home all,
MDI moves and a tool change), watched with ``cnc top --once`` and the ``cnc`` API.

The configs folder is copied first: a running machine writes its parameter file, tool
table and position file.
"""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import cnc
from cnc.runtime import read_runtime_info
from nml.ipcnames import instance_objects
from tests.hal.halrun_util import REPO

# config -> (MDI lines after homing, expected work position of the axes it names, tool)
MACHINES = {
    "mill": (["G0 X10 Y-5 Z-2", "T2 M6", "G43 G0 Z-2"], {"X": 10.0, "Y": -5.0, "Z": -2.0}, 2),
    "mill_switches": (["G0 X-20 Y30"], {"X": -20.0, "Y": 30.0}, 0),
    "mill_inch": (["G20 G0 X1 Y-0.5"], {"X": 1.0, "Y": -0.5}, 0),
    "lathe": (["G7 G0 X20 Z-10"], {"X": 10.0, "Z": -10.0}, 0),  # diameter 20 = radius 10
    "gantry": (["G0 X100 Y200"], {"X": 100.0, "Y": 200.0}, 0),
    "corexy": (["G0 X40 Y25"], {"X": 40.0, "Y": 25.0}, 0),
    "random_tc": (["T3 M6", "G0 X5 Y5"], {"X": 5.0, "Y": 5.0}, 3),
}
AXES = "XYZABCUVW"


def cnc_command(*args: str, cwd: Path) -> str:
    done = subprocess.run(
        [sys.executable, "-m", "cnc", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def launch_sim(procs, tmp_path: Path, name: str) -> tuple[subprocess.Popen[str], Path]:
    """``cnc run --headless`` of configs/sim/NAME.ini from a copy of the configs folder
    (a running machine writes its files); the launcher and the copy's sim folder, once the
    machine runs."""
    configs = tmp_path / "configs"
    shutil.copytree(REPO / "configs", configs)
    folder = configs / "sim"
    launcher = procs.python("-m", "cnc", "run", "--headless", f"{name}.ini", cwd=folder)
    deadline = time.monotonic() + 60
    while (info := read_runtime_info()) is None or info.pid != launcher.pid:
        assert launcher.poll() is None, launcher.stderr.read()
        assert time.monotonic() < deadline, "the machine did not come up"
        time.sleep(0.05)
    return launcher, folder


@pytest.mark.parametrize("name", list(MACHINES))
def test_sim_machine_homes_moves_and_changes_tools(
    name: str, procs, tmp_path: Path, cnc_instance: str
) -> None:
    launcher, folder = launch_sim(procs, tmp_path, name)
    try:
        lines, expected, tool = MACHINES[name]
        script = ["estop off", "machine on", "home all", "wait", "mode mdi"]
        for line in lines:
            script += [f"mdi {line}", "wait"]
        output = cnc_command("sh", "-c", "; ".join(script), cwd=folder)
        assert "ERROR" not in output, output

        stat = cnc.stat()
        stat.poll()
        assert stat.task_state == cnc.STATE_ON and all(stat.homed[: stat.joints])
        assert stat.linear_units == pytest.approx(1 / 25.4 if name == "mill_inch" else 1.0)
        assert stat.angular_units == 1.0
        for letter, value in expected.items():
            work = stat.position[AXES.index(letter)] - stat.g5x_offset[AXES.index(letter)]
            work -= stat.g92_offset[AXES.index(letter)] + stat.tool_offset[AXES.index(letter)]
            assert work == pytest.approx(value, abs=1e-6), letter
        assert stat.tool_in_spindle == tool

        snapshot = cnc_command("top", "--once", cwd=folder)
        assert "Task ON  mode MDI" in snapshot
        assert f"Tool {tool} in spindle" in snapshot
    finally:  # a clean shutdown even when a check failed
        launcher.send_signal(signal.SIGTERM)
        code = launcher.wait(timeout=60)
    assert code == 0, launcher.stderr.read()
    assert instance_objects(cnc_instance) == []
