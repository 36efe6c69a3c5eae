"""The hostmot2 driver against the simulated 7I96S, period by period in one process.

The board's clock is the test's (``FakeClock``): each period moves it 1 ms, so step
positions and the watchdog's timing are exact. Answers are waited for up to 50 ms of
real time (``packet-read-timeout``), so a busy machine does not count as packet loss.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator

import pytest

from hal.core import Hal
from hal.hm2.driver import Board, ConfigError, LowLevel, parse_config
from hal.hm2.eth import EthLink
from hal.hm2.firmware import SEVEN_I96S
from hal.hm2.idrom import GTAG_INM, GTAG_STEPGEN
from tests.hw.conftest import FakeClock, Served, serve

PERIOD = 1_000_000
SETTLE = 20  # periods for a changed setting to reach the board (one check per period)
NAME = "hm2_7i96s.0"


class Rig:
    """A board driver, its simulated board and the clock they share."""

    def __init__(self, served: Served, clock: FakeClock, config: str) -> None:
        self.served, self.sim, self.clock = served, served.board, clock
        self.hal = Hal()
        self.hal.new_component("hm2_eth", "rt")
        llio = LowLevel(NAME, 3, 17, 4, SEVEN_I96S.pin_names)
        self.board = Board(EthLink(served.ip), llio, parse_config(config), self.hal, "hm2_eth")
        self.board.read_timeout_param = 50_000_000
        self.faults: list[str] = []
        self.board.report_fault_hook = self.faults.append

    def _slot(self, name: str) -> tuple[int, int]:
        """(type, value slot) of a pin or parameter of the board."""
        pin = self.hal.find_pin(f"{NAME}.{name}")
        if pin:
            return pin[1]["type"], self.hal.ptr[pin[1]["slot"]]
        found = self.hal.find_param(f"{NAME}.{name}")
        assert found, name
        return found[1]["type"], found[1]["slot"]

    def get(self, name: str):
        return self.hal.read_slot(*self._slot(name))

    def set(self, name: str, value) -> None:
        self.hal.write_slot(*self._slot(name), value)

    def run(self, periods: int, *, is_writing: bool = True) -> None:
        for _ in range(periods):
            self.clock.advance(PERIOD)
            self.board.read(PERIOD)
            if is_writing:
                self.board.write(PERIOD)
        if not (self.sim.is_mute or self.sim.drop_one_in):
            self.board.link.read(0x0100, 1)  # answered after every packet sent before it

    def close(self) -> None:
        self.board.close()
        self.served.server.close()
        self.hal.destroy()
        self.hal.close()


@pytest.fixture
def rig(fake_clock: FakeClock) -> Iterator[Rig]:
    r = Rig(serve(fake_clock), fake_clock, "num_encoders=1 num_pwmgens=1 num_stepgens=5")
    yield r
    r.close()


def test_the_board_describes_itself_and_every_pin_has_an_owner_or_is_gpio(rig: Rig) -> None:
    board = rig.board
    assert board.idrom.board_name == b"MESA7I96"
    assert len(board.pins) == 51
    assert board.pin_owner[17:27] == [GTAG_STEPGEN] * 10  # TB1/TB2 step and direction
    assert board.pin_owner[0:11] == [GTAG_INM] * 11  # TB3 inputs
    assert board.pin_owner[34:51] == [None] * 17  # P1: GPIO


def test_stepgen_feedback_follows_the_command_and_the_motor(rig: Rig) -> None:
    rig.set("stepgen.00.position-scale", 100.0)  # steps per unit
    rig.set("stepgen.00.maxvel", 50.0)
    rig.set("stepgen.00.maxaccel", 2000.0)
    rig.set("stepgen.00.enable", True)
    rig.run(5)
    position = 0.0
    for _ in range(400):  # a 20 unit/s move of 4 units, as motion would command it
        position = min(position + 0.02, 4.0)
        rig.set("stepgen.00.position-cmd", position)
        rig.run(1)
    rig.run(200)  # settle
    feedback = rig.get("stepgen.00.position-fb")
    assert feedback == pytest.approx(4.0, abs=1 / 100)  # within a step
    assert rig.sim.step_position(0) / 100.0 == pytest.approx(feedback, abs=1e-6)
    assert rig.get("stepgen.00.counts") == round(rig.sim.step_position(0) - 0.5)


def test_gpio_outputs_reach_the_pins_and_inputs_come_back(rig: Rig) -> None:
    rig.set("gpio.040.is_output", True)
    rig.set("gpio.040.out", True)
    rig.run(SETTLE)
    assert rig.sim.is_output(40) and rig.sim.pin_out(40)
    rig.set("gpio.040.invert_output", True)
    rig.run(SETTLE)
    assert not rig.sim.pin_out(40)
    levels = [rig.sim.field_in(io) for io in range(51)]
    levels[3] = True  # TB3 input 3 switched on
    rig.sim.set_field_inputs(levels)
    rig.run(2)
    assert rig.get("gpio.003.in") and not rig.get("gpio.003.in_not")
    assert rig.get("inm.00.input-03")


def test_ssr_outputs_drive_their_pins(rig: Rig) -> None:
    rig.set("ssr.00.out-01", True)
    rig.run(2)
    assert rig.sim.pin_out(12)
    rig.set("ssr.00.invert-01", True)
    rig.run(2)
    assert not rig.sim.pin_out(12)


def test_the_watchdog_bites_when_the_writes_stop(rig: Rig) -> None:
    rig.set("stepgen.00.enable", True)
    rig.run(10)
    assert rig.sim.is_output(17) and not rig.get("watchdog.has_bit")
    rig.run(6, is_writing=False)  # 6 ms without a pet, the timeout is 5 ms
    assert rig.sim.has_bit
    assert not any(rig.sim.is_output(io) for io in range(51))  # every output off
    assert rig.get("watchdog.has_bit")
    assert rig.faults == [f"{NAME}: Watchdog has bit! (set the .has_bit pin to False to resume)"]
    rig.run(5)  # writing again does not wake it: the user must acknowledge
    assert not rig.sim.is_output(17)
    rig.set("watchdog.has_bit", False)
    rig.run(3)
    assert rig.sim.is_output(17) and not rig.sim.has_bit


def test_lost_answers_are_counted_and_forgiven_below_the_limit(rig: Rig) -> None:
    rig.board.read_timeout_param = 20_000_000  # a lost answer costs this wait
    rig.sim.drop_one_in = 4  # one answer in four lost (of the read requests and writes)
    rig.run(40)
    rig.sim.drop_one_in = 0
    assert rig.board.errors.total > 0
    assert not rig.board.is_io_error
    rig.run(30)
    assert rig.board.errors.level == 0 and not rig.board.errors.is_exceeded
    assert rig.faults == []


def test_past_the_error_limit_the_board_stops_and_says_so(rig: Rig) -> None:
    rig.board.read_timeout_param = 200_000
    rig.run(5)
    rig.sim.is_mute = True
    rig.run(4)
    assert not rig.board.is_io_error  # level 8 of 10
    rig.run(1)
    assert rig.board.is_io_error and rig.board.errors.is_exceeded
    assert rig.faults and "packet errors" in rig.faults[0] and "io_error" in rig.faults[0]
    sent = rig.sim.rx_packets
    rig.run(5)
    assert rig.sim.rx_packets == sent  # read and write do nothing until io_error is cleared
    rig.sim.is_mute = False
    rig.set("io_error", False)
    rig.run(3)
    assert not rig.board.is_io_error and rig.sim.rx_packets > sent


def test_fewer_instances_than_the_firmware_has_leave_their_pins_to_gpio(
    fake_clock: FakeClock,
) -> None:
    r = Rig(serve(fake_clock), fake_clock, "num_stepgens=3 num_encoders=0")
    try:
        assert r.board.pin_owner[23:27] == [None] * 4  # stepgen 3 and 4's pins
        assert r.hal.find_pin(f"{NAME}.gpio.023.out")
        assert not r.hal.find_pin(f"{NAME}.stepgen.03.enable")
        assert not r.hal.find_pin(f"{NAME}.encoder.00.count")
    finally:
        r.close()


def test_asking_for_more_instances_than_the_firmware_has_is_refused(
    fake_clock: FakeClock,
) -> None:
    served = serve(fake_clock)
    hal = Hal()
    try:
        hal.new_component("hm2_eth", "rt")
        llio = LowLevel(NAME, 3, 17)
        with pytest.raises(ConfigError, match="num_encoders=2, but only 1 are available"):
            Board(EthLink(served.ip), llio, parse_config("num_encoders=2"), hal, "hm2_eth")
    finally:
        served.server.close()
        hal.destroy()
        hal.close()


def test_periods_leave_no_reference_cycles(rig: Rig, collector_off) -> None:
    """The host runs with the garbage collector off (ARCH-017): read and write, with
    settings changing and answers lost, must leave nothing to collect."""
    for n in range(3):
        rig.set(f"stepgen.{n:02d}.enable", True)
    gc.collect()
    for period in range(300):
        rig.set("stepgen.00.position-cmd", period * 0.01)
        rig.set("stepgen.01.control-type", period // 50 % 2)
        rig.set("gpio.040.is_output", period // 20 % 2)
        rig.sim.drop_one_in = 7 if period > 150 else 0
        rig.run(1)
    assert gc.collect() == 0


@pytest.mark.parametrize("text", ["num_stepgens", "num_stepgens=x", "frobnicate=1"])
def test_a_bad_config_string_is_refused(text: str) -> None:
    with pytest.raises(ConfigError, match="config string"):
        parse_config(text)
