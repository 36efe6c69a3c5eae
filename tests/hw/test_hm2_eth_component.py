"""``loadrt hostmot2`` / ``loadrt hm2_eth`` in a real realtime host, against the simulator."""

from __future__ import annotations

from pathlib import Path

from tests.hal.halrun_util import halrun_text
from tests.hw.conftest import Served, free_loopback_ip
from tests.hw.record_linuxcnc import FIXTURE, objects

CONFIG = 'config="num_encoders=1 num_pwmgens=1 num_stepgens=5"'


def test_pins_parameters_aliases_and_functions_are_linuxcncs(
    tmp_path: Path, sim_board: Served
) -> None:
    """Everything LinuxCNC's own hm2_eth made of the same simulated board (the fixture),
    with the same types and directions, and nothing else."""
    text = (
        f"loadrt hostmot2\nloadrt hm2_eth board_ip={sim_board.ip} {CONFIG}\n"
        "show pin\nshow param\nshow funct\nshow alias\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    ours = objects(result.stdout)
    theirs = [line for line in FIXTURE.read_text().splitlines() if not line.startswith("#")]
    assert len(theirs) > 500
    assert ours == theirs


def test_the_board_runs_in_a_thread_and_counts_no_errors(tmp_path: Path, sim_board: Served) -> None:
    text = (
        f"loadrt hostmot2\nloadrt hm2_eth board_ip={sim_board.ip} {CONFIG}\n"
        "loadrt threads name1=servo-thread period1=1000000\n"
        "addf hm2_7i96s.0.read-request servo-thread\n"
        "addf hm2_7i96s.0.read servo-thread\naddf hm2_7i96s.0.write servo-thread\n"
        # a busy test machine is neither packet loss nor a stuck host
        "setp hm2_7i96s.0.packet-read-timeout 20000000\n"
        "setp hm2_7i96s.0.watchdog.timeout_ns 200000000\n"
        "setp hm2_7i96s.0.stepgen.01.enable 1\nsetp hm2_7i96s.0.stepgen.01.control-type 1\n"
        "setp hm2_7i96s.0.stepgen.01.maxaccel 0\nsetp hm2_7i96s.0.stepgen.01.velocity-cmd 1000\n"
        "start\nloadusr -w sleep 0.3\n"
        "getp hm2_7i96s.0.packet-error-total\ngetp hm2_7i96s.0.stepgen.01.velocity-fb\n"
        "getp hm2_7i96s.0.watchdog.has_bit\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    errors, velocity, has_bit = result.stdout.split()
    assert (errors, float(velocity), has_bit) == ("0", 1000.0, "FALSE")
    assert sim_board.board.step_rate_hz(1) == 0 or sim_board.board.has_bit  # unloaded: bit
    assert sim_board.board.step_position(1) > 0


def test_unloading_makes_the_watchdog_bite(tmp_path: Path, sim_board: Served) -> None:
    text = (
        f"loadrt hostmot2\nloadrt hm2_eth board_ip={sim_board.ip}\n"
        "loadrt threads name1=servo-thread period1=1000000\n"
        "addf hm2_7i96s.0.read servo-thread\naddf hm2_7i96s.0.write servo-thread\n"
        "start\nloadusr -w sleep 0.1\nunloadrt hm2_eth\nloadusr -w sleep 0.1\n"
    )
    result = halrun_text(tmp_path, text)
    assert result.returncode == 0, result.stderr
    sim_board.board.advance()
    assert sim_board.board.has_bit


def test_hm2_eth_needs_hostmot2_and_a_board_that_answers(tmp_path: Path) -> None:
    result = halrun_text(tmp_path, "loadrt hm2_eth board_ip=127.0.0.1\n")
    assert result.returncode != 0
    assert "load hostmot2 first" in result.stderr
    silent = free_loopback_ip()
    result = halrun_text(tmp_path, f"loadrt hostmot2\nloadrt hm2_eth board_ip={silent}\n")
    assert result.returncode != 0
    # nobody there: loopback refuses at once, a cable to nowhere times out
    assert f"hm2_eth: {silent}: " in result.stderr
    assert "did not answer within 0.2 s" in result.stderr or "refused" in result.stderr
