"""Status values as text, number input and script splitting (no controller needed)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from cnc.ui import formatting as fmt
from cnc.ui.sh import split_commands
from cnc.ui.top import display_interval
from tests.api.fake_task import G_CODES, M_CODES


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1.5", 1.5),
        ("1,5", 1.5),
        (" -2 ", -2.0),
        ("+3.", 3.0),
        ("1 000,25", 1000.25),
        (",5", 0.5),
        ("7", 7),
    ],
)
def test_numbers_take_a_decimal_point_or_comma(text: str, value: float) -> None:
    assert fmt.parse_float(text) == value


@pytest.mark.parametrize(
    "text", ["1,000.5", "1.2.3", "1,2,3", "", "abc", "nan", "inf", "1e3", "1_000", "-", ","]
)
def test_numbers_with_two_separators_or_no_digits_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match="is not"):
        fmt.parse_float(text)


def test_codes_are_shown_as_linuxcnc_shows_them() -> None:
    assert fmt.g_codes(G_CODES) == "G1 G17 G40 G21 G90 G94 G54 G49 G99 G64 G97 G91.1 G8 G92.2"
    assert fmt.m_codes(M_CODES) == "M5 M9 M48"
    assert fmt.feed_and_speed([3.0, 500.0, 1200.0, 0.0, 0.0]) == "F500 S1200"


def test_codes_the_interpreter_has_not_filled_are_not_shown() -> None:
    assert fmt.g_codes([0] * 17) == ""
    assert fmt.m_codes([0] * 10) == ""
    assert fmt.g_codes([]) == "" and fmt.g_codes(None) == ""


def test_work_coordinates_are_computed_as_axis_does() -> None:
    s = SimpleNamespace(
        position=(10.0, 0.0, 5.0, 0, 0, 0, 0, 0, 0),
        g5x_offset=(2.0, 0.0, 1.0, 0, 0, 0, 0, 0, 0),
        tool_offset=(0.0, 0.0, 3.0, 0, 0, 0, 0, 0, 0),
        g92_offset=(1.0, 1.0, 0.0, 0, 0, 0, 0, 0, 0),
        rotation_xy=90.0,
    )
    work = fmt.work_position(s)
    # (10-2, 0) rotated by -90 degrees is (0, -8); minus G92 (1, 1): (-1, -9); Z 5-1-3
    assert work[:3] == pytest.approx([-1.0, -9.0, 1.0])


def test_axes_follow_the_axis_mask() -> None:
    assert fmt.axes(SimpleNamespace(axis_mask=0b101)) == [(0, "X"), (2, "Z")]
    assert fmt.axes(SimpleNamespace(axis_mask="junk")) == []


def test_odd_single_values_are_shown_not_raised() -> None:
    assert fmt.name_of(fmt.TASK_STATES, 9) == "unknown(9)"
    assert fmt.name_of(fmt.TASK_STATES, [1]) == "unknown([1])"
    assert fmt.number(math.nan, 3, 8) == "     nan"
    assert fmt.number(1e300, 3) == "1.000e+300"
    assert fmt.number(None, 3) == "None"
    assert fmt.percent(0.5) == "50%"
    assert fmt.limit_flags(0b1010) == "+H +S"
    assert fmt.clean("a\tb\nc\x1b[0m") == "a b c?[0m"


@pytest.mark.parametrize(
    ("cycle_time", "seconds"),
    [("100", 0.1), ("0.05", 0.05), ("1", 0.001), ("0", None), ("-5", None), ("x", None)],
)
def test_display_cycle_time_in_milliseconds_or_seconds(cycle_time: str, seconds) -> None:
    assert display_interval(cycle_time) == (pytest.approx(seconds) if seconds else None)
    assert display_interval(None) is None


def test_scripts_split_on_lines_and_semicolons_and_skip_comments() -> None:
    text = "# setup\nmachine on; mode mdi\n\n  mdi G0 X1 ;  \n  # done\nwait"
    assert list(split_commands(text, "job.cnc")) == [
        ("job.cnc:2", "machine on"),
        ("job.cnc:2", "mode mdi"),
        ("job.cnc:4", "mdi G0 X1"),
        ("job.cnc:6", "wait"),
    ]
