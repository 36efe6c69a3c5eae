"""``cnc latency-test``: LinuxCNC's period syntax, its verdict bands, and a real run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cnc.latency import parse_time, verdict
from tests.hal.halrun_util import run_cnc


@pytest.mark.parametrize(
    "text, ns",
    [("25us", 25_000), ("25µs", 25_000), ("1ms", 1_000_000), ("50000", 50_000),
     ("25", 25_000), ("0.5ms", 500_000), ("2s", 2_000_000_000), ("100ns", 100)],
)  # fmt: skip
def test_periods_are_read_as_latency_test_reads_them(text: str, ns: int) -> None:
    assert parse_time(text) == ns


def test_a_bad_period_is_refused() -> None:
    with pytest.raises(ValueError, match="not a time: '1 hour'"):
        parse_time("1 hour")


@pytest.mark.parametrize(
    "jitter_us, first_word",
    [(5, "GOOD"), (19.9, "GOOD"), (20, "USABLE"), (49, "USABLE"), (50, "NEEDS A STEP CARD"),
     (499, "NEEDS A STEP CARD"), (500, "NOT USABLE"), (3000, "NOT USABLE")],
)  # fmt: skip
def test_the_verdict_follows_linuxcncs_bands(jitter_us: float, first_word: str) -> None:
    assert verdict(jitter_us).startswith(first_word)


def test_a_run_measures_each_thread_idle_and_loaded(tmp_path: Path) -> None:
    done = run_cnc("latency-test", "200us", "2ms", "--seconds", "0.6", "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    for phase in ("idle", "loaded"):
        for name, period in (("base-thread", 200_000), ("servo-thread", 2_000_000)):
            figures = result[phase][name]
            assert figures["period_ns"] == period
            assert figures["lateness"]["periods"] > 0
            assert figures["jitter"]["max_us"] is not None
    assert result["verdict"] == verdict(result["worst_jitter_us"])


def test_the_text_report_names_the_threads_and_what_to_change(tmp_path: Path) -> None:
    done = run_cnc("latency-test", "1ms", "--seconds", "0.4", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "servo-thread (1000 µs):" in done.stdout and "base-thread" not in done.stdout
    assert "max jitter" in done.stdout and "Worst max jitter" in done.stdout
    if "GOOD" not in done.stdout:
        assert "isolcpus" in done.stdout and "PREEMPT_RT" in done.stdout
