"""halcmd's -v/-Q/-q/-e/-R and halrun's -U, checked against LinuxCNC 2.9's output, and the
realtime host's latency settings (environment knobs, CPU choice, spin limit)."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import posix_ipc
import pytest

from hal import rtapi_app
from hal.core import Hal, release_hal_mutex
from hal.rtapi_app import Host, default_rt_cpu, host_options_from_env
from nml.ipcnames import instance_objects, ipc_name
from nml.shmem import is_process_alive
from tests.hal.halrun_util import FILES, run_cnc

# lines of LinuxCNC's uspace halcmd that come from it starting rtapi_app per loadrt
_USPACE_ONLY = ("' ready", "Program '/usr/bin/rtapi_app' started")


def _linuxcnc_lines(name: str) -> list[str]:
    """A recorded LinuxCNC output, as lines (its lock messages lack their newline)."""
    text = (FILES / name).read_text().replace("completed", "completed\n")
    return [line for line in text.splitlines() if line]


def _drop_owner(lines: list[str]) -> list[str]:
    return [line[6:] if line[:6].strip().isdigit() else line for line in lines]


def _run_verbose_file(tmp_path: Path, *options: str):  # type: ignore[no-untyped-def]
    shutil.copy(FILES / "lcnc_verbose.hal", tmp_path)
    return run_cnc("halrun", *options, "-f", "lcnc_verbose.hal", cwd=tmp_path)


def test_verbose_reports_each_command_like_linuxcnc(tmp_path: Path) -> None:
    result = _run_verbose_file(tmp_path, "-v")
    assert result.returncode == 0, result.stderr
    theirs = [
        line
        for line in _linuxcnc_lines("lcnc_verbose_output.txt")
        if not line.endswith(_USPACE_ONLY)
    ]
    ours = [line for line in result.stdout.splitlines() if line]
    assert _drop_owner(ours) == _drop_owner(theirs)


def test_quiet_silences_show_but_not_get_commands(tmp_path: Path) -> None:
    result = _run_verbose_file(tmp_path, "-Q")
    assert result.returncode == 0, result.stderr
    assert result.stdout == (FILES / "lcnc_quiet_output.txt").read_text()
    default = _run_verbose_file(tmp_path, "-q")
    assert "Component Pins:" in default.stdout
    assert "loaded" not in default.stdout  # -q: no -v messages


def test_errors_still_show_when_quiet(tmp_path: Path) -> None:
    (tmp_path / "bad.hal").write_text("newsig a bit\nsetp nosuch 1\n")
    result = run_cnc("halrun", "-Q", "-f", "bad.hal", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.strip().endswith("bad.hal:2: parameter or pin 'nosuch' not found")


def test_echo_option_echoes_each_command_on_stderr(tmp_path: Path) -> None:
    (tmp_path / "e.hal").write_text("newsig a bit   # a comment\nsets a 1\ngets a\n")
    result = run_cnc("halrun", "-e", "-f", "e.hal", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "TRUE\n"
    assert result.stderr.splitlines() == [
        "(1)<echo>: newsig a bit",
        "(2)<echo>: sets a 1",
        "(3)<echo>: gets a",
    ]


def test_verbose_single_command_names_the_command_line() -> None:
    hal = Hal()
    try:
        hal.new_component("keeper", "user")  # keeps the HAL alive between the two halcmds
        result = run_cnc("halcmd", "-v", "newsig", "x", "float")
        assert result.returncode == 0, result.stderr
        result = run_cnc("halcmd", "-v", "sets", "x", "2.5")
        assert result.stdout == "<commandline>:0: Signal 'x' set to 2.5\n"
    finally:
        hal.destroy()
        hal.close()


def test_release_mutex_frees_a_mutex_left_held() -> None:
    assert run_cnc("halcmd", "-R").stdout == "HALCMD: Release Mutex failed!\n"
    assert release_hal_mutex() is None  # no HAL: nothing to release
    hal = Hal()
    try:
        mutex = posix_ipc.Semaphore(ipc_name("hal", "mutex"))
        mutex.acquire()  # as a program that crashed while changing HAL would leave it
        mutex.close()
        result = run_cnc("halcmd", "-R", "newsig", "ignored", "bit")
        assert result.returncode == 0, result.stderr
        assert release_hal_mutex() is False  # released: free now
        assert "ignored" not in hal.meta["sigs"]  # -R runs nothing else, like halcmd
    finally:
        hal.destroy()
        hal.close()


@pytest.mark.allow_leftovers
def test_halrun_force_cleanup_stops_a_stale_host_and_removes_hal(procs) -> None:  # type: ignore[no-untyped-def]
    host = procs.python("-m", "hal.rtapi_app", "--no-rt")
    assert host.stdout.readline().strip() == "rtapi_app: ready"
    assert run_cnc("halcmd", "loadrt", "and2").returncode == 0
    user = procs.python("-c", "import time; time.sleep(60)")
    hal = Hal()
    try:  # a userspace component of a program that hangs
        hal.new_component("stale", "user", pid=user.pid)
        mutex = posix_ipc.Semaphore(ipc_name("hal", "mutex"))
        mutex.acquire()  # and a mutex left held
        mutex.close()
    finally:
        hal.close()
    busy = run_cnc("halrun", "-f", "/dev/null")
    assert busy.returncode == 1
    assert "Realtime already running.  Use 'halrun -U'" in busy.stderr
    assert host.poll() is None  # and left the running host alone
    result = run_cnc("halrun", "-U")
    assert result.returncode == 0, result.stderr
    assert host.wait(timeout=10) is not None
    deadline = time.monotonic() + 10
    while is_process_alive(user.pid) and user.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert user.poll() is not None
    assert instance_objects() == []  # no segment or semaphore left
    again = run_cnc("halrun", "-f", "/dev/null")  # and HAL works again
    assert again.returncode == 0, again.stderr


def test_host_settings_come_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("CNC_HAL_NO_RT", "CNC_HAL_SPIN_US", "CNC_HAL_KEEP_CPU_AWAKE", "CNC_HAL_CPU"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.delenv("CNC_HAL_PRIORITY", raising=False)
    assert host_options_from_env() == {
        "is_rt": True,
        "spin_us": rtapi_app.DEFAULT_SPIN_US,
        "is_cpu_kept_awake": True,
        "cpu": None,
        "priority": rtapi_app.RT_PRIORITY,
    }
    monkeypatch.setenv("CNC_HAL_SPIN_US", "0")
    monkeypatch.setenv("CNC_HAL_KEEP_CPU_AWAKE", "0")
    monkeypatch.setenv("CNC_HAL_CPU", "0")
    monkeypatch.setenv("CNC_HAL_PRIORITY", "50")
    monkeypatch.setenv("CNC_HAL_NO_RT", "1")
    assert host_options_from_env() == {
        "is_rt": False,
        "spin_us": 0,
        "is_cpu_kept_awake": False,
        "cpu": 0,
        "priority": 50,
    }
    monkeypatch.setenv("CNC_HAL_SPIN_US", "lots")  # ignored with a message
    assert host_options_from_env()["spin_us"] == rtapi_app.DEFAULT_SPIN_US


def test_realtime_cpu_prefers_the_highest_isolated_cpu(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    isolated = tmp_path / "isolated"
    monkeypatch.setattr(rtapi_app, "ISOLATED_CPUS", isolated)
    isolated.write_text("\n")
    assert default_rt_cpu() == (rtapi_app.os.cpu_count() or 1) - 1
    isolated.write_text("2-3,6\n")
    assert default_rt_cpu() == 6
    isolated.write_text("1\n")
    assert default_rt_cpu() == 1


def test_threads_spin_at_most_a_quarter_of_their_period() -> None:
    hal = Hal()
    host = Host(hal, is_rt=True, spin_us=100)
    assert host.spin_ns == 100_000
    assert Host(hal, is_rt=False, spin_us=100).spin_ns == 0  # not realtime: no spinning
    try:
        host.is_rt = False  # run the threads without SCHED_FIFO in the test
        fast = host.new_thread("fast", 40_000)
        slow = host.new_thread("slow", 1_000_000)
        assert (fast.priority, slow.priority) == (host.priority, host.priority - 1)
        assert fast.spin_ns == 10_000
        assert slow.spin_ns == 100_000
    finally:
        host.unload_all()
        hal.destroy()
        hal.close()


def test_host_keeps_the_cpu_awake_while_it_runs(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    latency = tmp_path / "cpu_dma_latency"
    monkeypatch.setattr(rtapi_app, "CPU_LATENCY_FILE", latency)
    hal = Hal()
    try:
        host = Host(hal, is_rt=True, is_cpu_kept_awake=True)
        host.keep_cpu_awake()
        assert latency.read_bytes() == bytes(4)  # a 32-bit 0: no wake-up latency accepted
        assert not host._cpu_latency_file.closed  # the request lasts while the file is open
        host.release_cpu()
        assert host._cpu_latency_file is None
        Host(hal, is_rt=False, is_cpu_kept_awake=True).keep_cpu_awake()  # not realtime
        latency.unlink()
        Host(hal, is_rt=True, is_cpu_kept_awake=False).keep_cpu_awake()  # turned off
        assert not latency.exists()
    finally:
        hal.destroy()
        hal.close()
