"""stepgen's step types 1 to 15: pins and parameters as LinuxCNC names them, and the output
sequences of ``man 9 stepgen`` / the HAL manual (``test_hal_oracle.py`` also compares all
types with LinuxCNC period by period)."""

from __future__ import annotations

import pytest

from hal.core import HalError
from tests.hal.comp_harness import bench

BASE_NS = 10_000
SERVO_NS = 1_000_000

# The HAL manual's state tables: phases A, B, ... of each state, '1' = high, forward order.
DOCUMENTED = {
    2: ["10", "11", "01", "00"],
    3: ["100", "010", "001"],
    4: ["100", "110", "010", "011", "001", "101"],
    5: ["1000", "0100", "0010", "0001"],
    6: ["1100", "0110", "0011", "1001"],
    7: ["1000", "1110", "0111", "0001"],
    8: ["1010", "0110", "0101", "1001"],
    9: ["1000", "1100", "0100", "0110", "0010", "0011", "0001", "1001"],
    10: ["1000", "1010", "1110", "0110", "0111", "0101", "0001", "1001"],
    11: ["10000", "01000", "00100", "00010", "00001"],
    12: ["11000", "01100", "00110", "00011", "10001"],
    13: ["10000", "11000", "01000", "01100", "00100", "00110", "00010", "00011", "00001", "10001"],
    14: ["11000", "11100", "01100", "01110", "00110", "00111", "00011", "10011", "10001", "11001"],
}


def _phases(b, count: int) -> str:
    return "".join("1" if b.value(f"stepgen.0.phase-{'ABCDE'[i]}") else "0" for i in range(count))


def _run_states(b, count: int, velocity: float, periods: int) -> list[str]:
    """Phase patterns seen while make-pulses runs ``periods`` base periods (changes only)."""
    b.hal.write_slot(*_pin_slot(b, "stepgen.0.velocity-cmd"), velocity)
    b.run(1, SERVO_NS, functs=["stepgen.update-freq"])
    seen = [_phases(b, count)]
    for _ in range(periods):
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])
        state = _phases(b, count)
        if state != seen[-1]:
            seen.append(state)
    return seen


def _pin_slot(b, name: str) -> tuple[int, int]:
    found = b.hal.find_pin(name)
    assert found is not None, name
    return found[1]["type"], found[1]["slot"]


def _set(b, name: str, value: float) -> None:
    found = b.hal.find_pin(name)
    info = found[1] if found else b.hal.find_param(name)[1]
    b.hal.write_slot(info["type"], info["slot"], value)


@pytest.mark.parametrize("step_type", sorted(DOCUMENTED))
def test_phase_types_follow_the_documented_sequence_both_ways(step_type: int) -> None:
    table = DOCUMENTED[step_type]
    count = len(table[0])
    with bench("stepgen", f"step_type={step_type} ctrl_type=v") as b:
        _set(b, "stepgen.0.enable", 1)
        _set(b, "stepgen.0.dirdelay", 0)
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])
        assert _phases(b, count) == table[0]  # state 0 before any step
        # 1000 steps/s at 10 µs periods: a step every 100 periods, 12 steps forward
        forward = _run_states(b, count, 1000.0, 1200)
        assert forward == [table[i % len(table)] for i in range(len(forward))]
        assert len(forward) == 13
        # reversing walks the same table backwards from where it is
        backward = _run_states(b, count, -1000.0, 1200)
        start = (len(forward) - 1) % len(table)
        expected = [table[(start - i) % len(table)] for i in range(len(backward))]
        assert backward == expected
        assert len(backward) >= 12


@pytest.mark.parametrize(
    ("step_type", "pins", "params"),
    [
        (0, {"step", "dir"}, {"stepspace", "dirsetup", "dirhold"}),
        (1, {"up", "down"}, {"stepspace", "dirdelay"}),
        (2, {"phase-A", "phase-B"}, {"dirdelay"}),
        (4, {"phase-A", "phase-B", "phase-C"}, {"dirdelay"}),
        (10, {"phase-A", "phase-B", "phase-C", "phase-D"}, {"dirdelay"}),
        (14, {f"phase-{p}" for p in "ABCDE"}, {"dirdelay"}),
    ],
)
def test_each_step_type_exports_linuxcncs_pins_and_params(
    step_type: int, pins: set[str], params: set[str]
) -> None:
    common_pins = {"counts", "enable", "position-fb", "velocity-cmd"}
    common_params = {"frequency", "maxaccel", "maxvel", "position-scale", "rawcounts", "steplen"}
    with bench("stepgen", f"step_type={step_type} ctrl_type=v") as b:
        meta = b.hal.meta
        prefix = "stepgen.0."
        found_pins = {n.removeprefix(prefix) for n in meta["pins"] if n.startswith(prefix)}
        found_params = {n.removeprefix(prefix) for n in meta["params"] if n.startswith(prefix)}
        assert found_pins == common_pins | pins
        assert found_params == common_params | params


def _count_pulses(b, periods: int) -> tuple[int, int]:
    """Rising edges on up and down while make-pulses runs; never both high at once."""
    ups = downs = 0
    was_up = was_down = False
    for _ in range(periods):
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])
        is_up, is_down = b.value("stepgen.0.up"), b.value("stepgen.0.down")
        assert not (is_up and is_down)
        ups += is_up and not was_up
        downs += is_down and not was_down
        was_up, was_down = is_up, is_down
    return ups, downs


def test_up_down_pulses_up_forward_and_down_after_reversing() -> None:
    with bench("stepgen", "step_type=1 ctrl_type=v") as b:
        _set(b, "stepgen.0.enable", 1)
        _set(b, "stepgen.0.dirdelay", 50_000)
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])  # learn the base period
        _set(b, "stepgen.0.velocity-cmd", 1000.0)
        b.run(1, SERVO_NS, functs=["stepgen.update-freq"])
        assert _count_pulses(b, 1000) == (10, 0)
        _set(b, "stepgen.0.velocity-cmd", -1000.0)
        b.run(1, SERVO_NS, functs=["stepgen.update-freq"])
        assert _count_pulses(b, 1000) == (0, 10)
        assert b.value("stepgen.0.rawcounts") == 0  # ten up, ten down
        assert b.value("stepgen.0.dirdelay") == 50_000  # a whole number of base periods


def test_phase_types_step_every_period_where_step_dir_needs_two() -> None:
    with bench("stepgen", "step_type=0,2 ctrl_type=v,v") as b:
        for channel in (0, 1):
            _set(b, f"stepgen.{channel}.enable", 1)
            _set(b, f"stepgen.{channel}.velocity-cmd", 1e6)  # far above both limits
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])  # learn the base period
        b.run(1, SERVO_NS, functs=["stepgen.update-freq"])
        # steplen 1 period: step/dir needs steplen + stepspace, quadrature only steplen
        assert b.value("stepgen.0.frequency") == pytest.approx(1e9 / (2 * BASE_NS))
        assert b.value("stepgen.1.frequency") == pytest.approx(1e9 / BASE_NS)


def test_user_step_type_uses_the_given_pattern() -> None:
    with bench("stepgen", "step_type=15 ctrl_type=v user_step_type=1,3,2,6") as b:
        assert b.hal.find_pin("stepgen.0.phase-C") is not None
        assert b.hal.find_pin("stepgen.0.phase-D") is None  # 6 = B and C: three phases
        _set(b, "stepgen.0.enable", 1)
        b.run(1, BASE_NS, functs=["stepgen.make-pulses"])
        states = _run_states(b, 3, 1000.0, 500)
        assert states == ["100", "110", "010", "011", "100", "110"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ("step_type=16", "bad stepping type '16', axis 0"),
        ("step_type=0,x", "bad stepping type 'x', axis 1"),
        ("step_type=0 ctrl_type=q", "bad control type 'q' for axis 0"),
        ("step_type=15", "step_type 15 needs user_step_type="),
        ("step_type=15 user_step_type=1,32", "uses more than 5 phases"),
        ("step_type=15 user_step_type=" + ",".join(["1"] * 11), "more than 10 states"),
        ("step_type=" + ",".join(["0"] * 17), "at most 16 channels"),
    ],
)
def test_bad_step_types_are_refused_with_a_clear_error(args: str, message: str) -> None:
    with pytest.raises(HalError, match=message), bench("stepgen", args):
        pass
