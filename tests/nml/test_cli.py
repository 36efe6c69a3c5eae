"""``cnc nml check|ls|dump`` as a user runs them (in a separate process, on live buffers)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from nml import emc
from nml.channels import DEFAULT_NML_FILE, load_config
from nml.shmem import ShmBuffer

REPO = Path(__file__).resolve().parents[2]


def cnc(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cnc", *args], capture_output=True, text=True, cwd=REPO, timeout=60
    )


def test_check_accepts_a_good_file() -> None:
    result = cnc("nml", "check", str(DEFAULT_NML_FILE))
    assert result.returncode == 0
    assert "7 buffers, 23 P lines: OK" in result.stdout


def test_check_lists_every_error_with_file_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.nml"
    bad.write_text(
        "B emcStatus SHMEM localhost 512 0 0 1 16 1\nB a SHMEM localhost x 0 0 2 4 2\n"
        "P p zz LOCAL localhost R 0 1 0 0\n"
    )
    result = cnc("nml", "check", str(bad))
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        f"{bad}:2: buffer a: size 'x' is not a number",
        f"{bad}:3: process p: buffer 'zz' is not defined by a B line",
        f"{bad}:1: buffer emcStatus: size 512 is too small for its largest message "
        f"({emc.EMC_STAT.fixed_size() + 16} bytes encoded; needs at least "
        f"{emc.EMC_STAT.fixed_size() + 16})",
    ]


@pytest.fixture
def running() -> dict[str, ShmBuffer]:
    cfg = load_config()
    buffers = {
        name: ShmBuffer(cfg.buffers[name], cfg.process("cnc", name))
        for name in ("emcCommand", "emcStatus")
    }
    yield buffers
    for buf in buffers.values():
        buf.close()


def test_ls_shows_buffers_and_live_counts(running: dict[str, ShmBuffer]) -> None:
    running["emcCommand"].write(emc.EMC_TASK_SET_MODE(mode=emc.EMC_TASK_MODE_ENUM.MDI))
    result = cnc("nml", "ls")
    assert result.returncode == 0, result.stderr
    lines = {line.split()[0]: line for line in result.stdout.splitlines()}
    assert "queue" in lines["emcCommand"]
    assert f"written 1, attached 1 (pids {os.getpid()}), queued 1" in lines["emcCommand"]
    assert "latest" in lines["emcStatus"] and lines["emcError"].rstrip().endswith("-")
    assert "xemc(R,c10,10 s)" in lines["emcStatus"]


def test_dump_decodes_queued_and_latest_messages(running: dict[str, ShmBuffer]) -> None:
    running["emcCommand"].write(emc.EMC_TASK_PLAN_OPEN(file="/tmp/part.ngc"))
    running["emcCommand"].write(emc.EMC_TASK_PLAN_RUN(line=12))
    status = emc.EMC_STAT()
    status.task.mode = 3
    status.motion.joint[2].homed = 1
    running["emcStatus"].write(status)
    queued = cnc("nml", "dump", str(DEFAULT_NML_FILE), "emcCommand")
    assert queued.returncode == 0, queued.stderr
    assert "EMC_TASK_PLAN_OPEN (type 506)" in queued.stdout
    assert "file: '/tmp/part.ngc'" in queued.stdout
    assert queued.stdout.index("PLAN_OPEN") < queued.stdout.index("EMC_TASK_PLAN_RUN (type 507)")
    assert running["emcCommand"].stats()["count"] == 2  # dump consumed nothing
    latest = cnc("nml", "dump", str(DEFAULT_NML_FILE), "emcStatus").stdout
    assert latest.startswith("EMC_STAT (type 1999)")
    assert "joint[2]:" in latest and "homed: 1" in latest


def test_dump_of_a_buffer_that_is_not_running() -> None:
    result = cnc("nml", "dump", str(DEFAULT_NML_FILE), "emcError")
    assert result.returncode == 1
    assert "buffer emcError: not running" in result.stderr


def test_demo_runs_two_processes_through_shared_memory(cnc_instance: str) -> None:
    result = cnc("demo", "--moves", "25")
    assert result.returncode == 0, result.stderr
    assert "task: move 24 serial 25 DONE, motion now at X24" in result.stdout
    assert "task: 25 commands acknowledged" in result.stdout
    assert result.stdout.rstrip().endswith("demo: buffers removed")
