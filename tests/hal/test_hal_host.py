"""The realtime host: thread timing parameters, overruns, failing functions, RT setup."""

from __future__ import annotations

import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from hal.core import Hal
from hal.rtapi_app import Host, host_environment
from tests.hal.halrun_util import FILES, halrun_text, without_halcmd

SLEEP = f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.05)'\n"


def test_thread_and_functions_publish_time_and_tmax(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=servo-thread period1=1000000\nloadrt and2\n"
        "addf and2.0 servo-thread\nstart\n"
        + SLEEP
        + "getp servo-thread.tmax\ngetp and2.0.tmax\ngetp and2.0.tmax-increased\n"
        "getp servo-thread.time\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    thread_tmax, funct_tmax, increased, thread_time = result.stdout.split()
    assert int(thread_tmax) >= int(funct_tmax) > 0
    assert increased == "TRUE"
    assert 0 < int(thread_time) <= int(thread_tmax)


def test_overruns_are_counted(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        f"loadrt {FILES / 'slow.py'}\naddf slow.0 servo-thread\nstart\n"
        + SLEEP
        + "getp slow.0.calls\n"
        'loadusr -w python3 -c "from hal.core import Hal; '
        "print(Hal(is_creating=False).thread_overruns('servo-thread'))\"\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    calls, overruns = (int(word) for word in result.stdout.split())
    assert overruns >= calls - 1 > 0


def test_a_failing_function_is_said_once_and_everything_keeps_running(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        f"loadrt {FILES / 'broken.py'}\nloadrt not\n"
        "addf broken.0 servo-thread\naddf not.0 servo-thread\nstart\n"
        + SLEEP
        + "getp broken.0.calls\ngetp not.0.out\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    calls, out = result.stdout.split()
    assert int(calls) > 1 and out == "TRUE"  # never disabled: it goes on being called
    assert "function 'broken.0' failed (machine to E-stop)" in result.stderr
    assert result.stderr.count("RuntimeError: broken on purpose") == 1


def test_small_memlock_limit_is_reported_once_with_the_recommendation(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("os.geteuid", lambda: 1000)
    monkeypatch.setattr(resource, "getrlimit", lambda _: (8192 * 1024, 8192 * 1024))
    hal = Hal()
    try:
        host = Host(hal)
        host.lock_memory()
        host.lock_memory()
    finally:
        hal.destroy()
        hal.close()
    err = capsys.readouterr().err
    assert err.count("Locked memory limit is 8192KiB, recommended at least 20480KiB") == 1


def test_loadrt_errors_leave_nothing_half_loaded(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "loadrt pid num_chan=x\nlist comp\n", "-k")
    assert "pid: num_chan=x is not a number" in result.stderr
    assert without_halcmd(result.stdout.split()) == []


def test_stepgen_steps_from_a_base_thread(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=base-thread period1=100000 name2=servo-thread period2=1000000\n"
        "loadrt stepgen step_type=0 ctrl_type=v\n"
        "addf stepgen.make-pulses base-thread\n"
        "addf stepgen.capture-position servo-thread\naddf stepgen.update-freq servo-thread\n"
        "setp stepgen.0.position-scale 1000\nsetp stepgen.0.enable 1\n"
        "setp stepgen.0.velocity-cmd -1\nstart\n"
        + SLEEP.replace("0.05", "0.2")
        + "stop\n"
        + SLEEP
        + "getp stepgen.0.counts\ngetp stepgen.0.position-fb\n"
        "getp stepgen.0.dir\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    counts, position, direction = result.stdout.split()
    assert int(counts) < 0
    assert float(position) == pytest.approx(int(counts) / 1000, abs=1 / 1000)
    assert direction == "TRUE"


def test_host_objects_come_from_malloc_unless_the_user_chose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("PYTHONMALLOC", raising=False)
    assert host_environment()["PYTHONMALLOC"] == "malloc"
    monkeypatch.setenv("PYTHONMALLOC", "debug")
    assert host_environment()["PYTHONMALLOC"] == "debug"


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_host_waiting_for_requests_exits_on_a_signal(signum: int) -> None:
    host = subprocess.Popen(
        [sys.executable, "-m", "hal.rtapi_app", "--no-rt"],
        env=host_environment(),
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert host.stdout.readline().strip() == "rtapi_app: ready"
        host.send_signal(signum)
        assert host.wait(timeout=10) == 0
    finally:
        if host.poll() is None:
            host.kill()
            host.wait()
