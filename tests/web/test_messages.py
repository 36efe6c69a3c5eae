"""[DISPLAY] MESSAGE_* / MULTIMESSAGE_* dialogs driven by HAL pins (GUI-018, GUI-019):
the INI keys, and the pins of the ``web`` component in a real (shared-memory) HAL."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from cnc.ini import IniFile
from cnc.ui.web.messages import MessagePin, UserMessage, UserMessages, read_message_pins
from cnc.ui.web.settings import Settings
from hal.api import HAL_BIT, HAL_OUT, HAL_S32, HalError, component
from hal.core import Hal
from tests.web.conftest import is_result, page, receive_until

GMOCCAPY_STYLE = """\
[DISPLAY]
MESSAGE_BOLDTEXT = NONE
MESSAGE_TEXT = This is a statusbar test
MESSAGE_DETAILS = STATUS DETAILS
MESSAGE_TYPE = status
MESSAGE_PINNAME = statustest

MESSAGE_BOLDTEXT = Lube
MESSAGE_TEXT = Lube fault
MESSAGE_DETAILS = Refill the tank
MESSAGE_TYPE = okdialog status
MESSAGE_PINNAME = lube-fault

MESSAGE_BOLDTEXT = Door
MESSAGE_TEXT = Close the door?
MESSAGE_DETAILS =
MESSAGE_TYPE = yesnodialog
MESSAGE_PINNAME = door

MESSAGE_BOLDTEXT = NONE
MESSAGE_TEXT = Waiting for air
MESSAGE_DETAILS =
MESSAGE_TYPE = nonedialog
MESSAGE_PINNAME = air

MULTIMESSAGE_ID = VFD
MULTIMESSAGE_VFD_NUMBER = 1
MULTIMESSAGE_VFD_TYPE = okdialog status
MULTIMESSAGE_VFD_TITLE = VFD Error: 1
MULTIMESSAGE_VFD_TEXT = Overcurrent
MULTIMESSAGE_VFD_DETAILS = DETAILS for VFD error 1
MULTIMESSAGE_VFD_ICON = WARNING
MULTIMESSAGE_VFD_NUMBER = 2
MULTIMESSAGE_VFD_TYPE = nonedialog status
MULTIMESSAGE_VFD_TITLE = VFD Error: 2
MULTIMESSAGE_VFD_TEXT = Overvoltage
MULTIMESSAGE_VFD_DETAILS = DETAILS for VFD error 2
MULTIMESSAGE_VFD_ICON = INFO
"""


def pins_of(text: str) -> tuple[list[MessagePin], list[str]]:
    return read_message_pins(IniFile.from_text(text, "m.ini"))


def test_the_ini_keys_as_gmoccapy_and_qtvcp_read_them() -> None:
    pins, problems = pins_of(GMOCCAPY_STYLE)
    assert problems == []
    by_name = {pin.name: pin for pin in pins}
    assert list(by_name) == ["statustest", "lube-fault", "door", "air", "VFD"]
    assert by_name["statustest"].choices == {
        1: UserMessage("This is a statusbar test", "", "STATUS DETAILS", "INFO", "", True)
    }
    lube = by_name["lube-fault"].choices[1]
    assert (lube.title, lube.text, lube.dialog, lube.is_status) == (
        "Lube",
        "Lube fault",
        "ok",
        True,
    )
    assert by_name["door"].choices[1].dialog == "yesno"
    assert by_name["air"].choices[1].dialog == "none"
    vfd = by_name["VFD"]
    assert vfd.is_multi and sorted(vfd.choices) == [1, 2]
    assert vfd.choices[1].icon == "WARNING" and vfd.choices[2].dialog == "none"
    assert by_name["door"].has_response and by_name["door"].has_waiting
    assert by_name["lube-fault"].has_waiting and not by_name["lube-fault"].has_response
    assert not by_name["air"].has_waiting and not by_name["statustest"].has_waiting


def test_bad_message_keys_are_reported_with_file_and_line_and_left_out() -> None:
    pins, problems = pins_of(
        "[DISPLAY]\n"
        "MESSAGE_TEXT = one\nMESSAGE_TYPE = okdialog\nMESSAGE_PINNAME = one\n"
        "MESSAGE_TEXT = two\nMESSAGE_TYPE = popup\nMESSAGE_PINNAME = two\n"
        "MESSAGE_ICON = WARNING\n"  # one icon for two messages
        "MULTIMESSAGE_ID = VFD\nMULTIMESSAGE_VFD_NUMBER = x\nMULTIMESSAGE_VFD_TEXT = t\n"
        "MULTIMESSAGE_ID = one\nMULTIMESSAGE_one_NUMBER = 3\n"
    )
    assert [pin.name for pin in pins] == ["one"]
    assert pins[0].choices[1].icon == "INFO" and not pins[0].is_multi
    assert problems == [
        "m.ini:8: 1 [DISPLAY]MESSAGE_ICON for 2 messages: give one per message; ignored",
        "m.ini:6: [DISPLAY]MESSAGE_TYPE = popup: expected status and/or one of okdialog, "
        "yesnodialog, nonedialog",
        "m.ini:10: [DISPLAY]MULTIMESSAGE_VFD_NUMBER = x: not a whole number",
        "m.ini:9: MULTIMESSAGE_ID = VFD: no messages",
        "m.ini: message pin name 'one' used twice; the second ignored",
    ]


@pytest.fixture
def hal() -> Iterator[Hal]:
    """A HAL of this test's own instance, removed afterwards."""
    own = Hal()
    yield own
    own.destroy()
    own.close()


def drive(hal: Hal, target: str, hal_type: int) -> Any:
    """A component "driver" whose out pin feeds ``target`` through a signal, as a postgui
    HAL file would net them; ``driver["out"] = value`` sets it."""
    driver = component("driver", hal=hal)
    driver.newpin("out", hal_type, HAL_OUT)
    hal.new_signal("fed", hal_type)
    hal.link("driver.out", "fed")
    hal.link(target, "fed")
    return driver


@pytest.fixture
def messages(hal: Hal) -> Iterator[tuple[UserMessages, Any]]:
    """The web component's message pins, and a driver component whose out pins feed them
    through signals, as a postgui HAL file would net them."""
    pins, _ = pins_of(GMOCCAPY_STYLE)
    found = UserMessages(pins)
    found.open(hal)
    driver = component("driver", hal=hal)
    for name, hal_type in (("lube", HAL_BIT), ("door", HAL_BIT), ("air", HAL_BIT)):
        driver.newpin(name, hal_type, HAL_OUT)
    driver.newpin("vfd", HAL_S32, HAL_OUT)
    for pin, target in (("lube", "lube-fault"), ("door", "door"), ("air", "air"), ("vfd", "VFD")):
        hal.new_signal(pin, HAL_S32 if pin == "vfd" else HAL_BIT)
        hal.link(f"driver.{pin}", pin)
        hal.link(f"web.messages.{target}", pin)
    yield found, driver
    driver.exit()
    found.close()


def value(hal: Hal, name: str) -> Any:
    found = hal.find_pin(name)
    assert found is not None, name
    return hal.pin_value(found[1])


def test_a_rising_edge_shows_an_ok_dialog_until_it_is_answered(hal: Hal, messages) -> None:
    found, driver = messages
    assert found.poll() == []
    driver["lube"] = True
    shown = found.poll()
    assert shown == [
        {"type": "notice", "kind": "display", "text": "Lube: Lube fault"},
        {"type": "dialog", "name": "lube-fault", "kind": "ok", "title": "Lube",
         "text": "Lube fault", "details": "Refill the tank", "icon": "INFO"},
    ]  # fmt: skip
    assert value(hal, "web.messages.lube-fault-waiting") == 1
    assert found.poll() == []  # a level, not an edge: shown once
    driver["lube"] = False
    assert found.poll() == []  # the pin falling does not close an ok dialog
    assert found.open_dialogs() == [shown[1]]
    assert found.answer("lube-fault", True) == {"type": "dialog_close", "name": "lube-fault"}
    assert value(hal, "web.messages.lube-fault-waiting") == 0
    assert found.open_dialogs() == []
    with pytest.raises(ValueError, match="no message dialog 'lube-fault' is open"):
        found.answer("lube-fault", True)


def test_a_yes_no_dialog_sets_the_response_pin(hal: Hal, messages) -> None:
    found, driver = messages
    driver["door"] = True
    assert [m["type"] for m in found.poll()] == ["dialog"]  # no "status" word: no notice
    found.answer("door", True)
    assert value(hal, "web.messages.door-response") == 1
    assert value(hal, "web.messages.door-waiting") == 0
    driver["door"] = False
    found.poll()
    driver["door"] = True
    found.poll()
    assert value(hal, "web.messages.door-response") == 0  # reset when shown again
    assert value(hal, "web.messages.door-waiting") == 1
    found.answer("door", False)
    assert value(hal, "web.messages.door-response") == 0


def test_a_none_dialog_follows_its_pin_and_cannot_be_answered(messages) -> None:
    found, driver = messages
    driver["air"] = True
    assert found.poll()[0]["kind"] == "none"
    with pytest.raises(ValueError, match="no button"):
        found.answer("air", True)
    driver["air"] = False
    assert found.poll() == [{"type": "dialog_close", "name": "air"}]


def test_a_multimessage_number_selects_the_message_and_zero_closes_it(messages) -> None:
    found, driver = messages
    driver["vfd"] = 1
    first = found.poll()
    assert first[0] == {"type": "notice", "kind": "display", "text": "VFD Error: 1: Overcurrent"}
    assert first[1]["name"] == "VFD" and first[1]["text"] == "Overcurrent"
    driver["vfd"] = 2
    assert found.poll()[1]["text"] == "Overvoltage"  # replaces the dialog shown
    driver["vfd"] = 7  # no such message: the dialog closes
    assert found.poll() == [{"type": "dialog_close", "name": "VFD"}]


def test_a_second_web_component_is_refused_cleanly(hal: Hal, messages) -> None:
    pins, _ = pins_of(GMOCCAPY_STYLE)
    other = UserMessages(pins)
    with pytest.raises(HalError, match="duplicate component name 'web'"):
        other.open(hal)
    assert other.poll() == []
    other.close()


@pytest.mark.asyncio
async def test_every_page_sees_the_dialog_and_one_answer_closes_it_everywhere(
    hal: Hal, fake_task, web
) -> None:
    fake_task()
    pins, problems = pins_of(GMOCCAPY_STYLE + "MULTIMESSAGE_ID = NOPE\n")
    client = await web(Settings(cycle_time_s=0.02, message_pins=pins, problems=problems))
    driver = drive(hal, "web.messages.door", HAL_BIT)
    try:
        async with page(client) as first, page(client) as second:
            for socket in (first, second):  # the INI's problems, as error notices
                notice = await receive_until(socket, lambda m: m["type"] == "notice")
                assert notice["kind"] == "error" and "NOPE: no messages" in notice["text"]
            driver["out"] = True
            for socket in (first, second):
                shown = await receive_until(socket, lambda m: m["type"] == "dialog")
                assert (shown["name"], shown["kind"], shown["text"]) == (
                    "door",
                    "yesno",
                    "Close the door?",
                )
            assert value(hal, "web.messages.door-waiting") == 1
            async with page(client) as late:  # a page that connects later
                shown = await receive_until(late, lambda m: m["type"] == "dialog")
                assert shown["name"] == "door"
            await second.send_json({"cmd": "answer", "name": "door", "is_yes": True, "id": 5})
            assert (await receive_until(second, is_result(5)))["status"] == "DONE"
            for socket in (first, second):
                closed = await receive_until(socket, lambda m: m["type"] == "dialog_close")
                assert closed["name"] == "door"
            assert value(hal, "web.messages.door-response") == 1
            assert value(hal, "web.messages.door-waiting") == 0
            await first.send_json({"cmd": "answer", "name": "door", "is_yes": False, "id": 6})
            late_answer = await receive_until(first, is_result(6))
            assert late_answer["status"] == "ERROR"
            assert late_answer["message"] == "answer: no message dialog 'door' is open"
    finally:
        driver.exit()


@pytest.mark.asyncio
async def test_without_a_hal_the_pages_are_told_why_there_are_no_message_pins(
    fake_task, web
) -> None:
    fake_task()
    pins, _ = pins_of(GMOCCAPY_STYLE)
    client = await web(Settings(cycle_time_s=0.02, message_pins=pins))
    async with page(client) as socket:
        notice = await receive_until(socket, lambda m: m["type"] == "notice")
    assert notice == {
        "type": "notice",
        "kind": "error",
        "text": "[DISPLAY] MESSAGE_* pins not created: HAL is not running (no HAL shared memory)",
    }
