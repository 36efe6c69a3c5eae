"""cnc ui web end to end without a browser: a real machine (``cnc run --headless``), the
server as its own process, and the test as a page on its websocket.

- A [DISPLAY] MESSAGE_* dialog (GUI-018) pops up when another HAL component drives its pin
  (LinuxCNC's userspace API), and the answer comes back on the -response pin.
- A tool edit rewrites the tool table file, iocontrol reloads it (stat.tool_table shows it)
  and the interpreter uses it (M6, G43).
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import aiohttp
import pytest

import cnc
from hal.api import HAL_BIT, HAL_OUT, component
from hal.core import Hal
from tests.task.test_machine import Machine
from tests.web.conftest import is_result, receive_until


@pytest.fixture
def hal(machine: Machine) -> Iterator[Hal]:
    """This test's attachment to the machine's HAL (never creating one)."""
    attached = Hal(is_creating=False)
    yield attached
    attached.close()


def pin(hal: Hal, name: str) -> Any:
    found = hal.find_pin(name)
    assert found is not None, f"no pin {name}"
    return hal.pin_value(found[1])


async def talk(url: str, request: dict[str, Any]) -> dict[str, Any]:
    """Send one command as a page does; its result."""
    async with aiohttp.ClientSession() as session, session.ws_connect(url + "ws") as page:
        await page.send_json(request | {"id": 1})
        return await receive_until(page, is_result(1))


def test_a_hal_pin_pops_up_a_dialog_and_a_tool_edit_reaches_iocontrol_and_the_interpreter(
    machine: Machine, page_url: str, hal: Hal
) -> None:
    """One machine for both (a machine takes seconds to start)."""
    answer_the_door_dialog(page_url, hal)
    edit_a_tool(machine, page_url)


def answer_the_door_dialog(page_url: str, hal: Hal) -> None:
    driver = component("driver", hal=hal)  # as a postgui HAL file would net it
    driver.newpin("door-open", HAL_BIT, HAL_OUT)
    driver.ready()
    hal.new_signal("door-open", HAL_BIT)
    hal.link("driver.door-open", "door-open")
    hal.link("web.messages.door", "door-open")

    async def run() -> None:
        async with aiohttp.ClientSession() as session, session.ws_connect(page_url + "ws") as page:
            driver["door-open"] = True
            shown = await receive_until(page, lambda m: m["type"] == "dialog")
            assert shown == {
                "type": "dialog",
                "name": "door",
                "kind": "yesno",
                "title": "Door",
                "text": "Is the door closed?",
                "details": "The interlock switch reports it open.",
                "icon": "WARNING",
            }
            assert pin(hal, "web.messages.door-waiting") == 1
            assert pin(hal, "web.messages.door-response") == 0
            await page.send_json({"cmd": "answer", "name": "door", "is_yes": True, "id": 2})
            assert (await receive_until(page, is_result(2)))["status"] == "DONE"
            closed = await receive_until(page, lambda m: m["type"] == "dialog_close")
            assert closed["name"] == "door"

    try:
        asyncio.run(run())
        assert pin(hal, "web.messages.door-response") == 1
        assert pin(hal, "web.messages.door-waiting") == 0
    finally:
        driver.exit()


def edit_a_tool(machine: Machine, page_url: str) -> None:
    edit = {"cmd": "tool_set", "tool": 2, "z": "1,5", "diameter": "6,35", "comment": "drill"}
    result = asyncio.run(talk(page_url, edit))
    assert result["status"] == "DONE", result
    assert (machine.folder / "test.tbl").read_text() == (
        "T1   P1   D+6.000000 Z+10.000000 ;6 mm end mill\nT2   P2   D+6.350000 Z+1.500000 ;drill\n"
    )
    machine.until(lambda s: [(t.id, t.zoffset, t.diameter) for t in s.tool_table[1:3]] == [
        (1, 10.0, 6.0), (2, 1.5, 6.35)
    ])  # fmt: skip
    machine.ready_to_move()
    for line in ("T2 M6", "G43 G0 X1"):  # the interpreter's copy follows iocontrol's table
        machine.command.mdi(line)
        assert machine.command.wait_complete(20) == cnc.RCS_DONE, line
    machine.until(lambda s: s.tool_offset[2] == 1.5)
