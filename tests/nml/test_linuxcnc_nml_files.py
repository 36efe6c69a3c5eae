"""A LinuxCNC NML file runs our controller unchanged (nml.channels.with_our_lines): it names
only the buffers of task, iocontrol and the UIs, and ``emcsvr`` as master; our task <->
motion pair and our motion process's lines are added from our file."""

from __future__ import annotations

from pathlib import Path

import pytest

from nml import emc
from nml.channels import (
    DEFAULT_NML_FILE,
    EMC_COMMAND,
    EMC_ERROR,
    EMC_STATUS,
    MOTION_COMMAND,
    MOTION_STATUS,
    TOOL_COMMAND,
    TOOL_STATUS,
    Nml,
    load_config,
)
from nml.config import NmlConfigWarning

# The B/P layout of a LinuxCNC networked NML file (its tests/linuxcncrsh-tcp/tcp.nml),
# written for this test: TCP options, an ``emcsvr`` master with a ``default`` line, REMOTE
# UI lines, and c_num 3 of emcError taken by iocontrol (``tool``).
LINUXCNC_TCP_NML = """\
B emcCommand SHMEM localhost 8192   0 0 1 16 1001 TCP=5005 xdr queue confirm_write serial
B emcStatus  SHMEM localhost 170000 0 0 2 16 1002 TCP=5005 xdr
B emcError   SHMEM localhost 8192   0 0 3 16 1003 TCP=5005 xdr queue
B toolCmd    SHMEM localhost 1024   0 0 4 16 1004 TCP=5005 xdr
B toolSts    SHMEM localhost 131072 0 0 5 16 1005 TCP=5005 xdr
P emc    emcCommand LOCAL  localhost RW 0 1.0  0 0
P emc    emcStatus  LOCAL  localhost W  0 1.0  0 0
P emc    emcError   LOCAL  localhost W  0 1.0  0 0
P emc    toolCmd    LOCAL  localhost W  0 1.0  0 0
P emc    toolSts    LOCAL  localhost R  0 1.0  0 0
P emcsvr emcCommand LOCAL  localhost W  1 1.0  1 2
P emcsvr emcStatus  LOCAL  localhost R  1 1.0  1 2
P emcsvr emcError   LOCAL  localhost R  1 1.0  1 2
P emcsvr toolCmd    LOCAL  localhost W  1 1.0  1 2
P emcsvr toolSts    LOCAL  localhost R  1 1.0  1 2
P emcsvr default    LOCAL  localhost RW 1 1.0  1 2
P tool   emcError   LOCAL  localhost W  0 1.0  0 3
P tool   toolCmd    LOCAL  localhost RW 0 1.0  0 3
P tool   toolSts    LOCAL  localhost W  0 1.0  0 3
P xemc   emcCommand REMOTE localhost W  0 10.0 0 10
P xemc   emcStatus  REMOTE localhost R  0 10.0 0 10
P xemc   emcError   REMOTE localhost R  0 10.0 0 10
"""


@pytest.fixture
def tcp_nml(tmp_path: Path) -> Path:
    path = tmp_path / "tcp.nml"
    path.write_text(LINUXCNC_TCP_NML)
    return path


def test_a_linuxcnc_file_gets_our_motion_pair_with_its_master_as_ours(tcp_nml: Path) -> None:
    with pytest.warns(NmlConfigWarning, match="TCP=5005 ignored"):
        config = load_config(tcp_nml)
    ours = load_config(DEFAULT_NML_FILE)
    for name in (MOTION_COMMAND, MOTION_STATUS):
        assert config.buffers[name] == ours.buffers[name]
        master = config.process("emcsvr", name)
        assert (master.is_master, master.ops) == (True, "RW")
    assert config.process("emc", MOTION_COMMAND).ops == "W"
    assert config.process("motion", MOTION_COMMAND).ops == "R"
    assert not any(p.name == "cnc" for p in config.processes)  # no second master
    # the file's own lines are untouched
    assert config.buffers[EMC_STATUS].size == 170000
    assert config.process("xemc", EMC_STATUS).type == "REMOTE"


def test_our_motion_writes_errors_on_a_connection_number_the_file_left_free(
    tcp_nml: Path,
) -> None:
    with pytest.warns(NmlConfigWarning):
        config = load_config(tcp_nml)
    motion = config.process("motion", EMC_ERROR)
    assert motion.ops == "W" and motion.timeout == 0  # never blocks a servo period
    others = {p.c_num for p in config.processes_of(EMC_ERROR) if p.name != "motion"}
    assert motion.c_num not in others
    assert 0 <= motion.c_num < config.buffers[EMC_ERROR].max_procs


def test_our_own_file_is_complete_already() -> None:
    config = load_config(DEFAULT_NML_FILE)
    lines = [(p.name, p.buffer) for p in config.processes]
    assert len(lines) == len(set(lines))
    assert all(p.is_master for p in config.processes if p.name == "cnc")


def test_every_process_of_ours_attaches_through_a_linuxcnc_file(tcp_nml: Path) -> None:
    with pytest.warns(NmlConfigWarning):
        config = load_config(tcp_nml)
    every = [EMC_COMMAND, EMC_STATUS, EMC_ERROR, TOOL_COMMAND, TOOL_STATUS]
    with Nml(config, "emcsvr") as master:  # the launcher creates every buffer
        assert set(master.channels) == {*every, MOTION_COMMAND, MOTION_STATUS}
        with (
            Nml(config, "emc", [*every, MOTION_COMMAND, MOTION_STATUS]) as task,
            Nml(config, "motion", [MOTION_COMMAND, MOTION_STATUS, EMC_ERROR]) as motion,
            Nml(config, "tool", [TOOL_COMMAND, TOOL_STATUS, EMC_ERROR]),
        ):
            serial = task[MOTION_COMMAND].write(emc.EMC_TRAJ_SET_SCALE(scale=0.5))
            received = motion[MOTION_COMMAND].read()
            assert received is not None and received.serial_number == serial
