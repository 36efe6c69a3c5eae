"""``xhc-hb04``, the HAL side of the XHC-HB04 pendant driver, with no pendant plugged in:
what a LinuxCNC user without the pendant sees (its ``xhc-hb04.tcl`` starts it with
``loadusr -W``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from hal import xhc_hb04
from tests.hal.halrun_util import REPO, halrun_text

LAYOUT1 = REPO / "hal" / "lib" / "xhc-hb04-layout1.cfg"


def test_buttons_are_read_from_the_layout_file(tmp_path: Path) -> None:
    buttons = xhc_hb04.read_buttons(str(LAYOUT1))
    assert buttons[:2] == [(0x01, "button-stop"), (0x02, "button-start-pause")]
    bad = tmp_path / "bad.cfg"
    bad.write_text("[XHC-HB04]\nBUTTON=01:button-stop\nBUTTON=zz\n")
    with pytest.raises(xhc_hb04.ConfigError, match=r"bad.cfg:3: BUTTON wants"):
        xhc_hb04.read_buttons(str(bad))


def test_per_axis_buttons_get_one_pin_per_axis() -> None:
    names = [name for name, _, _ in xhc_hb04.pin_specs([(0x0C, "button-goto-zero")])]
    assert [n for n in names if n.startswith("button")] == [
        "button-goto-zero",
        *(f"button-goto-zero-{axis}" for axis in "xyza"),
    ]
    assert {"connected", "require_pendant", "jog.counts", "jog.plus-a"} <= set(names)


def test_pendant_is_found_by_its_usb_ids(tmp_path: Path) -> None:
    assert not xhc_hb04.is_pendant_plugged_in(tmp_path)
    device = tmp_path / "1-1"
    device.mkdir()
    (device / "idVendor").write_text("10ce\n")
    (device / "idProduct").write_text("eb70\n")
    assert xhc_hb04.is_pendant_plugged_in(tmp_path)


def test_without_minus_x_the_pins_are_ready_at_once(tmp_path: Path) -> None:
    result = halrun_text(
        tmp_path,
        f"loadusr -W xhc-hb04 -I {LAYOUT1} -H\n"
        "getp xhc-hb04.connected\ngetp xhc-hb04.require_pendant\ngetp xhc-hb04.stepsize\n"
        "show pin xhc-hb04.button-goto-zero-a\nunloadusr xhc-hb04\n",
    )
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if not line.startswith("xhc-hb04:")]
    assert "xhc-hb04: waiting for XHC-HB04 device" in result.stdout
    assert lines[:3] == ["FALSE", "FALSE", "1"]
    assert "xhc-hb04.button-goto-zero-a" in result.stdout


def test_with_minus_x_and_no_pendant_the_driver_gives_up(monkeypatch, tmp_path) -> None:
    """-x (require_pendant = yes): no pins, exit status 1 after the wait, so that
    ``loadusr -W`` fails and the Tcl file continues without the pendant."""
    monkeypatch.setattr(xhc_hb04, "MAX_WAIT_S", 0)
    monkeypatch.setattr(xhc_hb04, "USB_DEVICES", tmp_path)
    made = []
    monkeypatch.setattr(xhc_hb04.Driver, "make_pins", lambda self, required: made.append(1))
    assert xhc_hb04.main(["-x", "-I", str(LAYOUT1), "-H"]) == 1
    assert made == []


def test_bad_options_are_reported(capsys) -> None:
    assert xhc_hb04.main(["-s", "9"]) == 1
    assert "-s wants 1..5" in capsys.readouterr().err
