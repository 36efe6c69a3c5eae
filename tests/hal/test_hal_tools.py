"""``cnc hal watch|sample|stream`` against a running realtime host (real processes)."""

from __future__ import annotations

import sys
from pathlib import Path

from tests.hal.halrun_util import halrun_text, run_cnc, without_halcmd

CNC = f"{sys.executable} -m cnc"
SLEEP = f"loadusr -w {sys.executable} -c 'import time; time.sleep(0.1)'\n"


def test_sample_records_every_period_with_sample_numbers(tmp_path: Path) -> None:
    out = tmp_path / "samples.txt"
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt sampler depth=200 cfg=fbs\n"
        "setp sampler.0.pin.0 2.5\nsetp sampler.0.pin.1 1\nsetp sampler.0.pin.2 -7\n"
        "addf sampler.0 servo-thread\nstart\n"
        f"loadusr -w {CNC} hal sample -c 0 -n 5 -t {out}\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert out.read_text().splitlines() == [f"{n} 2.500000 1 -7 " for n in range(5)]


def test_stream_plays_lines_into_pins_one_per_period(tmp_path: Path) -> None:
    data = tmp_path / "in.txt"
    data.write_text("1.5 3\n2.5 4\n# a comment\n3.5 5\n")
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt streamer depth=10 cfg=fs\n"
        "loadrt scale\nsetp scale.0.gain 2\n"
        "net x streamer.0.pin.0 scale.0.in\n"
        f"loadusr -w {CNC} hal stream -c 0 {data}\n"
        "addf streamer.0 servo-thread\naddf scale.0 servo-thread\nstart\n"
        + SLEEP
        + "getp scale.0.out\ngetp streamer.0.pin.1\ngetp streamer.0.empty\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["7", "5", "TRUE"]


def test_sample_and_stream_wire_themselves_with_a_thread(tmp_path: Path) -> None:
    data = tmp_path / "in.txt"
    data.write_text("".join(f"{v}\n" for v in (1, 2, 3, 4)))
    out = tmp_path / "out.txt"
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt scale\nsetp scale.0.gain 10\naddf scale.0 servo-thread\nstart\n"
        f"loadusr -w {CNC} hal stream -T servo-thread -i {data} scale.0.in\n"
        f"loadusr -w {CNC} hal sample -T servo-thread -n 3 -o {out} scale.0.out scale.0.in\n"
        "list comp\nlist sig\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert out.read_text().splitlines() == ["40.000000 4.000000 "] * 3
    assert without_halcmd(result.stdout.split()) == ["scale", "__servo-thread", "threads"]


def test_watch_prints_values_once(tmp_path: Path) -> None:
    text = (
        "loadrt and2\nsetp and2.0.in0 1\nnewsig s float\nsets s 0.25\n"
        f"loadusr -w {CNC} hal watch -n 1 and2.0.in0 s and2.0.tmax\n"
        f"loadusr -w -i {CNC} hal watch -n 1 no.such.pin\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["and2.0.in0 TRUE", "s 0.25", "and2.0.tmax 0"]


def test_tools_usage_and_errors() -> None:
    assert run_cnc("hal").returncode == 0
    bad = run_cnc("hal", "watch", "-n", "1", "x")
    assert bad.returncode == 1 and "HAL is not running" in bad.stderr


def test_sample_of_a_missing_channel_is_an_error(tmp_path: Path) -> None:
    text = f"loadrt and2\nloadusr -w {CNC} hal sample -c 3 -n 1\n"
    result = halrun_text(tmp_path, text)
    assert result.returncode == 1
    assert "cnc hal sample: no FIFO 'sampler.3' (is the component loaded?)" in result.stderr


def test_a_bad_sampler_config_leaves_no_fifo(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "loadrt sampler depth=10 cfg=ff,fz\n")
    assert result.returncode == 1
    assert "bad cfg letter 'z'" in result.stderr
    # the autouse fixture fails the test if the first channel's FIFO segment is left


def test_linuxcnc_halsampler_lines_run_our_tool(tmp_path: Path) -> None:
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt sampler depth=100 cfg=s\nsetp sampler.0.pin.0 42\n"
        "addf sampler.0 servo-thread\nstart\nloadusr -w halsampler -c 0 -n 2\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["42 ", "42 "]


def test_halstreamer_reads_lines_as_linuxcnc(tmp_path: Path) -> None:
    """Comments and bad lines are skipped with a message naming line and field; a last line
    without its newline is cut short (LinuxCNC's halstreamer skips it too)."""
    data = tmp_path / "in.txt"
    data.write_text("# comment\n1 5\n\n0 x\n0 7\n1 8")  # messages as LinuxCNC 2.9's
    text = (
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt streamer depth=10 cfg=bs\n"
        "loadusr -w halstreamer in.txt\n"
        "addf streamer.0 servo-thread\nstart\n" + SLEEP + "getp streamer.0.pin.1\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["7"]
    assert result.stderr.splitlines() == [
        "line 2, field 0: bit value not 0 or 1, skipping the line",
        "line 3, field 1: bad character, skipping the line",
        "line 5, field 1: premature end of line, skipping the line",
    ]
