"""A UI outlives controllers: it notices one stopping and attaches to the next (GUI-*)."""

from __future__ import annotations

import subprocess

import pytest

import cnc
from cnc.api import connection
from nml import emc
from nml.channels import EMC_STATUS, Nml, load_config

# A stand-in controller: makes the buffers, publishes one status, waits for a line on stdin,
# then dies without cleaning up (os._exit), like a killed launcher.
CONTROLLER = """
import os, sys
from nml import emc
from nml.channels import Nml, load_config
nml = Nml(load_config(), "cnc")
stat = emc.EMC_STAT()
stat.task.state = int(sys.argv[1])
nml["emcStatus"].write(stat)
print("up", flush=True)
sys.stdin.readline()
os._exit(0)
"""


@pytest.fixture(autouse=True)
def quick_liveness_checks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(connection, "LIVENESS_CHECK_S", 0.0)


def start_controller(procs, state: int):
    proc = procs.python("-c", CONTROLLER, str(state), stdin=subprocess.PIPE)
    assert proc.stdout.readline().strip() == "up"
    return proc


def test_poll_raises_once_the_controller_died_and_works_again_after_a_restart(procs) -> None:
    first = start_controller(procs, cnc.STATE_ESTOP)
    s = cnc.stat()
    s.poll()
    assert s.task_state == cnc.STATE_ESTOP
    first.stdin.write("\n")
    first.stdin.flush()
    first.wait(10)
    with pytest.raises(cnc.error, match="not running"):
        s.poll()  # its buffers are still in /dev/shm, but nobody owns them any more
    # a new controller replaces the left-over buffers; the same stat object follows it
    with Nml(load_config(), "cnc") as second:
        status = emc.EMC_STAT()
        status.task.state = cnc.STATE_ON
        second[EMC_STATUS].write(status)
        s.poll()
        assert s.task_state == cnc.STATE_ON
