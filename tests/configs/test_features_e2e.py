"""configs/sim/features.ini end to end: a locking indexer, an extra joint and external
offsets, through the real processes (``cnc run --headless``, ``cnc sh``, ``cnc halcmd``)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

import cnc
from tests.configs.test_sim_machines_e2e import cnc_command, launch_sim

C, Z = 5, 2  # axis indices


def pin(name: str, folder: Path) -> float:
    text = cnc_command("halcmd", "getp", name, cwd=folder).strip()
    words = {"TRUE": 1.0, "FALSE": 0.0}
    return words[text] if text in words else float(text)


def until_pin(name: str, value: float, folder: Path, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while pin(name, folder) != pytest.approx(value, abs=1e-6):
        assert time.monotonic() < deadline, f"{name} = {pin(name, folder)}, not {value}"
        time.sleep(0.1)


@pytest.mark.slow
def test_indexer_extra_joint_and_external_offsets_work_on_the_running_machine(
    procs, tmp_path: Path, cnc_instance: str
) -> None:
    launcher, folder = launch_sim(procs, tmp_path, "features")
    try:
        # the C move needs the indexer's unlock (a timedelay answers it): it would wait
        # forever without the handshake; afterwards the table is locked again
        script = "estop off; machine on; home all; wait; mode mdi; mdi G0 C90; wait"
        script += "; mdi G0 Z-10; wait"  # (an indexing axis moves alone)
        output = cnc_command("sh", "-c", script, cwd=folder)
        assert "ERROR" not in output, output
        stat = cnc.stat()
        stat.poll()
        assert stat.position[C] == pytest.approx(90.0)
        until_pin("joint.3.unlock", 0, folder)

        # the extra joint follows its posthome command (through limit3) once homed
        cnc_command("halcmd", "sets", "magazine-pos", "20", cwd=folder)
        until_pin("joint.4.motor-pos-cmd", 20.0, folder)

        # an external offset on Z: counts x scale (counts that change while enabled, as an
        # encoder's, as LinuxCNC's), added to the commanded Z
        for signal, value in (("z-eoffset-enable", "1"), ("z-eoffset-scale", "0.5")):
            cnc_command("halcmd", "sets", signal, value, cwd=folder)
        cnc_command("halcmd", "sets", "z-eoffset-counts", "-8", cwd=folder)
        until_pin("axis.z.eoffset", -4.0, folder)
        until_pin("joint.2.motor-pos-cmd", -14.0, folder)
        assert pin("motion.eoffset-active", folder) == 1.0
        stat.poll()
        assert stat.task_state == cnc.STATE_ON
    finally:
        launcher.terminate()
        launcher.wait(timeout=60)
